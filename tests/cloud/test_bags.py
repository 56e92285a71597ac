from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

pytest.importorskip("rosbags")

from rosbags.rosbag2 import StoragePlugin, Writer

from deformap.cloud import PointCloud
from deformap.cloud.io import (
    BAG_STORAGES,
    WrenchSeries,
    read_bag_clouds,
    read_bag_static_transform,
    read_bag_wrenches,
    typestore,
    write_bag,
)
from deformap.errors import FileFormatError, InvalidArgumentError


def _pose(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    mat = np.eye(4)
    mat[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    mat[:3, 3] = rng.uniform(-0.5, 0.5, 3)
    return mat


def _cloud(seed: int, n: int = 200, frame: str = "camera") -> PointCloud:
    rng = np.random.default_rng(seed)
    return PointCloud(rng.uniform(-0.3, 0.3, (n, 3)), rng.integers(0, 256, (n, 3)), frame=frame)


def _wrenches(n: int = 5) -> WrenchSeries:
    rng = np.random.default_rng(9)
    return WrenchSeries(stamp_ns=np.arange(n, dtype=np.int64) * 10**8 + 3,
                        force_n=rng.normal(size=(n, 3)), torque_nm=rng.normal(size=(n, 3)),
                        frame_id="ft_sensor")  # fmt: skip


@pytest.fixture(params=BAG_STORAGES)
def storage(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def test_clouds_and_wrenches_round_trip(tmp_path: Path, storage: str) -> None:
    clouds = [(10**9, _cloud(1)), (2 * 10**9 + 7, _cloud(2))]
    series = _wrenches()
    bag = tmp_path / "bag"
    write_bag(bag, storage=storage, clouds={"/camera/points": clouds},
              wrenches={"/ft": series}, cloud_dtype="float64")  # fmt: skip
    got = read_bag_clouds(bag, "/camera/points")
    assert [g.stamp_ns for g in got] == [10**9, 2 * 10**9 + 7]
    assert [g.log_time_ns for g in got] == [10**9, 2 * 10**9 + 7]
    for (_, want), g in zip(clouds, got, strict=True):
        np.testing.assert_array_equal(g.cloud.points, want.points)
        np.testing.assert_array_equal(g.cloud.colors, want.colors)  # type: ignore[arg-type]
        assert g.cloud.frame == "camera" and g.n_dropped == 0
    w = read_bag_wrenches(bag, "/ft")
    np.testing.assert_array_equal(w.stamp_ns, series.stamp_ns)
    np.testing.assert_array_equal(w.force_n, series.force_n)
    np.testing.assert_array_equal(w.torque_nm, series.torque_nm)
    assert w.frame_id == "ft_sensor"
    # A single storage file reads as well as the folder.
    single = next(bag.glob("*.mcap" if storage == "mcap" else "*.db3"))
    assert len(read_bag_clouds(single, "/camera/points")) == 2


def test_cam2world_matrix_and_tf_static_chain(tmp_path: Path, storage: str) -> None:
    world2base, base2cam = _pose(1), _pose(2)  # parent-from-child: base in world, cam in base
    cam2world = world2base @ base2cam
    bag = tmp_path / "bag"
    write_bag(bag, storage=storage, clouds={"/pts": [(5, _cloud(3, frame="cam"))]},
              static_transforms=[("world", "base", world2base), ("base", "cam", base2cam)],
              cloud_dtype="float64")  # fmt: skip
    raw = _cloud(3, frame="cam").points
    expected = raw @ cam2world[:3, :3].T + cam2world[:3, 3]
    via_tf = read_bag_clouds(bag, "/pts", cam2world="tf_static")[0].cloud
    via_matrix = read_bag_clouds(bag, "/pts", cam2world=cam2world)[0].cloud
    assert via_tf.frame == via_matrix.frame == "world"
    np.testing.assert_allclose(via_tf.points, expected, atol=1e-12)
    np.testing.assert_allclose(via_matrix.points, expected, atol=1e-12)
    # The inverse direction walks the tree downwards.
    np.testing.assert_allclose(read_bag_static_transform(bag, "world", "cam"),
                               np.linalg.inv(cam2world), atol=1e-12)  # fmt: skip
    np.testing.assert_array_equal(read_bag_static_transform(bag, "cam", "cam"), np.eye(4))


def _write_raw_cloud_bag(bag: Path, storage: str, msgs: list[object]) -> None:
    store = typestore()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(bag, version=9, storage_plugin=plugin) as writer:
        conn = writer.add_connection("/pts", "sensor_msgs/msg/PointCloud2", typestore=store)
        for i, msg in enumerate(msgs):
            writer.write(conn, i, store.serialize_cdr(msg, "sensor_msgs/msg/PointCloud2"))


def _organised_big_endian(points: np.ndarray, height: int) -> object:
    """An organised, padded, big-endian float64 cloud with NaN holes, as some drivers send."""
    types = typestore().types
    field = types["sensor_msgs/msg/PointField"]
    width = len(points) // height
    offsets = {"z": 0, "x": 16, "y": 8}
    layout = np.dtype({"names": list(offsets), "formats": [">f8"] * 3,
                       "offsets": list(offsets.values()), "itemsize": 32})  # fmt: skip
    table = np.zeros(len(points), dtype=layout)
    for i, axis in enumerate("xyz"):
        table[axis] = points[:, i]
    rows = table.view(np.uint8).reshape(height, width * 32)
    padded = np.zeros((height, width * 32 + 16), np.uint8)
    padded[:, : width * 32] = rows
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="cam"
    )
    return types["sensor_msgs/msg/PointCloud2"](
        header=header, height=height, width=width,
        fields=[field(name=a, offset=o, datatype=8, count=1) for a, o in offsets.items()],
        is_bigendian=True, point_step=32, row_step=width * 32 + 16, data=padded.reshape(-1),
        is_dense=False,
    )  # fmt: skip


def test_organised_clouds_with_holes_drop_and_count_them(tmp_path: Path, storage: str) -> None:
    rng = np.random.default_rng(4)
    pts = rng.uniform(-0.2, 0.2, (24, 3))
    pts[[1, 5, 17]] = np.nan
    bag = tmp_path / "bag"
    _write_raw_cloud_bag(bag, storage, [_organised_big_endian(pts, height=4)])
    (got,) = read_bag_clouds(bag, "/pts")
    assert got.n_dropped == 3 and got.stamp_ns == 10**9 + 2
    np.testing.assert_array_equal(got.cloud.points, np.delete(pts, [1, 5, 17], axis=0))
    assert got.cloud.colors is None


def test_bad_bags_name_file_topic_and_problem(tmp_path: Path, storage: str) -> None:
    bag = tmp_path / "bag"
    write_bag(bag, storage=storage, clouds={"/pts": [(1, _cloud(1, frame="cam"))]},
              wrenches={"/ft": _wrenches()})  # fmt: skip
    with pytest.raises(FileFormatError, match=r"bag: bag has no topic '/nope' \(topics: \['/ft'"):
        read_bag_clouds(bag, "/nope")
    with pytest.raises(FileFormatError, match="topic '/pts' carries sensor_msgs/msg/PointCloud2"):
        read_bag_wrenches(bag, "/pts")
    with pytest.raises(FileFormatError, match="bag has no topic '/tf_static'"):
        read_bag_clouds(bag, "/pts", cam2world="tf_static")
    with pytest.raises(FileFormatError, match="no such bag"):
        read_bag_clouds(tmp_path / "missing", "/pts")
    with pytest.raises(FileFormatError, match="File name too long"):  # over NAME_MAX (255)
        read_bag_clouds(tmp_path / ("a" * 300), "/pts")
    with pytest.raises(InvalidArgumentError, match=r"`cam2world` must be a \(4, 4\)"):
        read_bag_clouds(bag, "/pts", cam2world=np.eye(3))
    with pytest.raises(InvalidArgumentError, match="`topic` must be a non-empty str"):
        read_bag_wrenches(bag, "")
    with pytest.raises(InvalidArgumentError, match="exists already"):
        write_bag(bag, storage=storage)
    with pytest.raises(InvalidArgumentError, match="`storage` must be one of"):
        write_bag(tmp_path / "other", storage="rosbag1")


def test_tf_static_that_does_not_reach_the_world_is_refused(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    write_bag(bag, clouds={"/pts": [(1, _cloud(1, frame="cam"))]},
              static_transforms=[("robot", "cam", _pose(0))])  # fmt: skip
    with pytest.raises(FileFormatError, match="does not connect frame 'cam' to 'world'"):
        read_bag_clouds(bag, "/pts", cam2world="tf_static")
    assert read_bag_clouds(bag, "/pts", cam2world="tf_static", world_frame="robot")


def test_millimetre_and_all_nan_messages_are_refused(tmp_path: Path) -> None:
    bag = tmp_path / "mm"
    write_bag(bag, clouds={"/pts": [(1, PointCloud(_cloud(1).points * 1000, frame="cam"))]})
    with pytest.raises(
        FileFormatError, match=r"\[/pts message 1\]: coordinates reach .* units='mm'"
    ):
        read_bag_clouds(bag, "/pts")
    got = read_bag_clouds(bag, "/pts", units="mm")[0].cloud
    np.testing.assert_allclose(got.points, _cloud(1).points, rtol=1e-6)
    bag = tmp_path / "nan"
    _write_raw_cloud_bag(bag, "mcap", [_organised_big_endian(np.full((4, 3), np.nan), 2)])
    with pytest.raises(FileFormatError, match=r"\[/pts message 1\]: the cloud is empty"):
        read_bag_clouds(bag, "/pts")


@pytest.mark.parametrize("cut", [0.3, 0.6, 0.9])
def test_truncated_and_garbled_bags_raise_file_format_errors(
    tmp_path: Path, storage: str, cut: float
) -> None:
    bag = tmp_path / "bag"
    write_bag(bag, storage=storage, clouds={"/pts": [(i, _cloud(i)) for i in range(3)]})
    data_file = next(p for p in bag.iterdir() if p.suffix in (".mcap", ".db3"))
    data = data_file.read_bytes()
    data_file.write_bytes(data[: int(len(data) * cut)])
    with pytest.raises(FileFormatError, match=r"bag"):
        read_bag_clouds(bag, "/pts")
    data_file.write_bytes(bytes(b ^ 0x5A for b in data))
    with pytest.raises(FileFormatError, match=r"bag"):
        read_bag_clouds(bag, "/pts")


def _same_clouds(got: list, want: list) -> bool:  # type: ignore[type-arg]
    return len(got) == len(want) and all(
        g.stamp_ns == w.stamp_ns
        and np.array_equal(g.cloud.points, w.cloud.points)
        and np.array_equal(g.cloud.colors, w.cloud.colors)
        for g, w in zip(got, want, strict=True)
    )


def _same_wrenches(got: WrenchSeries, want: WrenchSeries) -> bool:
    return (np.array_equal(got.stamp_ns, want.stamp_ns) and np.array_equal(got.force_n, want.force_n)
            and np.array_equal(got.torque_nm, want.torque_nm))  # fmt: skip


@pytest.mark.parametrize("storage_name", BAG_STORAGES)
def test_hypothesis_corrupted_bags_are_refused_naming_the_bag_or_read_whole(
    tmp_path_factory: pytest.TempPathFactory, storage_name: str
) -> None:
    """A cut bag is refused with a DeformapError naming it; flipped bytes are refused the same way
    or read as the same number of messages of the same sizes (a flip inside a float payload
    cannot be detected: neither format checksums it); an untouched bag reads exactly as written.
    """
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from deformap.errors import DeformapError

    source = tmp_path_factory.mktemp("bag") / "bag"
    write_bag(source, storage=storage_name, clouds={"/pts": [(i, _cloud(i, n=50)) for i in range(2)]},
              wrenches={"/w": _wrenches()})  # fmt: skip
    data_file = next(p for p in source.iterdir() if p.suffix in (".mcap", ".db3"))
    original = data_file.read_bytes()
    clouds, wrenches = read_bag_clouds(source, "/pts"), read_bag_wrenches(source, "/w")

    @settings(max_examples=25, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow])
    @given(
        cut=st.integers(min_value=0, max_value=len(original)),
        flips=st.lists(st.tuples(st.integers(0, len(original) - 1), st.integers(1, 255)),
                       max_size=8),
    )
    def check(cut: int, flips: list[tuple[int, int]]) -> None:
        data = bytearray(original[:cut] if cut < len(original) else original)
        for offset, mask in flips:
            if offset < len(data):
                data[offset] ^= mask
        data_file.write_bytes(bytes(data))
        reads = ((lambda: read_bag_clouds(source, "/pts"), clouds, _same_clouds),
                 (lambda: read_bag_wrenches(source, "/w"), wrenches, _same_wrenches))
        for read, want, same in reads:
            try:
                got = read()
            except DeformapError as exc:
                assert str(source) in str(exc)
                continue
            assert cut >= len(original), f"a bag cut at {cut} of {len(original)} bytes was read"
            if bytes(data) == original:
                assert same(got, want)
            elif isinstance(got, WrenchSeries):
                assert got.force_n.shape == want.force_n.shape
            else:
                assert [g.cloud.points.shape for g in got] == [w.cloud.points.shape for w in want]

    try:
        check()
    finally:
        data_file.write_bytes(original)


def test_bags_cut_anywhere_raise_file_format_errors_naming_the_bag(
    tmp_path: Path, storage: str
) -> None:
    """Regression: rosbags reads sqlite3 through apsw, whose CorruptError escaped the reader."""
    bag = tmp_path / "bag"
    write_bag(bag, storage=storage, clouds={"/pts": [(i, _cloud(i, n=50)) for i in range(2)]})
    data_file = next(p for p in bag.iterdir() if p.suffix in (".mcap", ".db3"))
    data = data_file.read_bytes()
    for cut in np.linspace(0, len(data) - 1, 40).astype(int):
        data_file.write_bytes(data[:cut])
        with pytest.raises(FileFormatError, match=re.escape(str(bag))):
            read_bag_clouds(bag, "/pts")


def test_one_reader_yields_several_topics_in_bag_order(tmp_path: Path, storage: str) -> None:
    from deformap.cloud.io import iter_bag_messages, pointcloud2_to_cloud

    bag = tmp_path / "bag"
    series = _wrenches(2)
    write_bag(bag, storage=storage, clouds={"/pts": [(7, _cloud(4)), (10**9, _cloud(5))]},
              wrenches={"/ft": series}, cloud_dtype="float64")  # fmt: skip
    topics = {"/pts": "sensor_msgs/msg/PointCloud2", "/ft": "geometry_msgs/msg/WrenchStamped"}
    raws = list(iter_bag_messages(bag, topics))
    times = [m.log_time_ns for m in raws]
    assert times == sorted(times) and len(raws) == 4
    assert sorted(m.topic for m in raws) == ["/ft", "/ft", "/pts", "/pts"]
    first = next(m for m in raws if m.topic == "/pts")
    msg = typestore().deserialize_cdr(bytes(first.data), topics["/pts"])
    cloud, dropped = pointcloud2_to_cloud(msg, where="here", frame="world", colors=False)
    np.testing.assert_array_equal(cloud.points, _cloud(4).points)
    assert cloud.colors is None and cloud.frame == "world" and dropped == 0
    with_colors, _ = pointcloud2_to_cloud(msg, where="here")
    np.testing.assert_array_equal(with_colors.colors, _cloud(4).colors)  # type: ignore[arg-type]
    assert with_colors.frame == "camera"
    with pytest.raises(FileFormatError, match=r"no topic '/nope' .*carrying sensor_msgs"):
        list(iter_bag_messages(bag, {**topics, "/nope": "sensor_msgs/msg/PointCloud2"}))
    with pytest.raises(FileFormatError, match="topic '/ft' carries geometry_msgs"):
        list(iter_bag_messages(bag, {"/ft": "sensor_msgs/msg/PointCloud2"}))
    with pytest.raises(InvalidArgumentError, match="`topics` must be a non-empty mapping"):
        list(iter_bag_messages(bag, {}))


def test_mcap_chunks_carry_their_crc_so_a_flipped_point_byte_is_refused(tmp_path: Path) -> None:
    import struct
    import zlib

    bag = tmp_path / "bag"
    clouds = [(i, _cloud(i)) for i in range(3)]
    write_bag(bag, storage="mcap", clouds={"/pts": clouds})
    (data_file,) = bag.glob("*.mcap")
    data = bytearray(data_file.read_bytes())
    # walk the records: every chunk has a non-zero CRC equal to the CRC-32 of its records
    at, chunks = 8, 0
    while at + 9 <= len(data) - 8:
        opcode, length = data[at], struct.unpack_from("<Q", data, at + 1)[0]
        if opcode == 0x06:
            crc, name_len = struct.unpack_from("<II", data, at + 9 + 24)
            records_at = at + 9 + 32 + name_len
            (records_len,) = struct.unpack_from("<Q", data, records_at)
            assert crc != 0 and name_len == 0
            assert crc == zlib.crc32(data[records_at + 8:records_at + 8 + records_len])
            chunks += 1
        at += 9 + length
    assert chunks >= 1
    # a point's coordinate changed in place (the message still parses) is caught by the CRC
    needle = np.asarray(clouds[1][1].points[7], dtype=np.float32).tobytes()
    where = bytes(data).find(needle)
    assert where > 0
    data[where] ^= 0x01
    data_file.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match=r"bag"):
        read_bag_clouds(bag, "/pts")


def test_mcap_written_by_deformap_reads_with_crc_checks_in_the_mcap_library(
        tmp_path: Path) -> None:
    reader_module = pytest.importorskip("mcap.reader")
    bag = tmp_path / "bag"
    write_bag(bag, storage="mcap", clouds={"/pts": [(i, _cloud(i)) for i in range(2)]})
    (data_file,) = bag.glob("*.mcap")
    with open(data_file, "rb") as fh:
        reader = reader_module.make_reader(fh, validate_crcs=True)
        assert sum(1 for _ in reader.iter_messages()) == 2


def test_a_programs_fault_is_not_read_as_a_damaged_bag() -> None:
    from deformap.cloud.io import bag_error_text

    assert bag_error_text(RuntimeError("LZ4F_decompress failed:\n  ERROR_frameType")) == \
        "RuntimeError: LZ4F_decompress failed: ERROR_frameType"  # lz4's, on one line
    for fault in (NotImplementedError("no such codec path"), RecursionError("deep")):
        with pytest.raises(type(fault)):
            bag_error_text(fault)
