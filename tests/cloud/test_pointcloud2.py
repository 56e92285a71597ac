from __future__ import annotations

import struct
import sys
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("rosbags")

from deformap.cloud.io import array_to_pointcloud2, pointcloud2_to_array, typestore
from deformap.errors import InvalidArgumentError, MissingDependencyError

_CODES = {"f4": (7, "f", 4), "f8": (8, "d", 8), "u2": (4, "H", 2), "u4": (6, "I", 4)}


def _field(name: str, offset: int, code: str) -> Any:
    datatype, _, _ = _CODES[code]
    return SimpleNamespace(name=name, offset=offset, datatype=datatype, count=1)


def _pack_cloud(
    points: np.ndarray,
    *,
    height: int,
    codes: dict[str, str],
    order: list[str],
    gap: int,
    row_pad: int,
    big_endian: bool,
    is_dense: bool,
) -> SimpleNamespace:
    """Pack points byte by byte with struct: an implementation independent of the reader's."""
    n = points.shape[0]
    width = n // height
    offsets, pos = {}, 0
    for name in order:  # fields in a given order with `gap` padding bytes between them
        offsets[name] = pos
        pos += _CODES[codes[name]][2] + gap
    point_step = pos
    row_step = width * point_step + row_pad
    data = bytearray(height * row_step)
    prefix = ">" if big_endian else "<"
    for i in range(n):
        row, col = divmod(i, width)
        base = row * row_step + col * point_step
        for name in order:
            value = points[i, "xyz".index(name)] if name in "xyz" else i
            struct.pack_into(prefix + _CODES[codes[name]][1], data, base + offsets[name], value)
    return SimpleNamespace(
        height=height, width=width, point_step=point_step, row_step=row_step,
        fields=[_field(name, offsets[name], codes[name]) for name in order],
        is_bigendian=big_endian, is_dense=is_dense, data=bytes(data),
        header=SimpleNamespace(frame_id="cam", stamp=SimpleNamespace(sec=0, nanosec=0)),
    )  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    height=st.integers(1, 4),
    width=st.integers(0, 9),
    xyz_codes=st.lists(st.sampled_from(["f4", "f8"]), min_size=3, max_size=3),
    order=st.permutations(["x", "y", "z", "intensity"]),
    gap=st.integers(0, 5),
    row_pad=st.integers(0, 7),
    big_endian=st.booleans(),
    nan_fraction=st.sampled_from([0.0, 0.3]),
)
def test_any_field_layout_reads_back_the_packed_points(
    seed: int, height: int, width: int, xyz_codes: list[str], order: list[str], gap: int,
    row_pad: int, big_endian: bool, nan_fraction: float,
) -> None:  # fmt: skip
    rng = np.random.default_rng(seed)
    n = height * width
    pts = rng.uniform(-1, 1, (n, 3))
    holes = rng.random(n) < nan_fraction
    pts[holes, rng.integers(0, 3)] = np.nan
    codes = dict(zip("xyz", xyz_codes, strict=True)) | {"intensity": "u2"}
    msg = _pack_cloud(pts, height=height, codes=codes, order=order, gap=gap, row_pad=row_pad,
                      big_endian=big_endian, is_dense=not holes.any())  # fmt: skip
    got, dropped = pointcloud2_to_array(msg, with_count=True)
    want = pts[~holes]
    for i, axis in enumerate("xyz"):
        if codes[axis] == "f4":
            want[:, i] = want[:, i].astype(np.float32)
    assert dropped == int(holes.sum())
    np.testing.assert_array_equal(got, want)
    assert got.dtype == np.float64 and got.shape == (n - dropped, 3)


def test_round_trip_through_cdr_serialisation() -> None:
    rng = np.random.default_rng(1)
    pts = rng.uniform(0, 0.5, (1000, 3))
    cols = rng.integers(0, 256, (1000, 3)) / 255.0
    store = typestore()
    for dtype, atol in [("float64", 0.0), ("float32", 3e-8)]:
        msg = array_to_pointcloud2(pts, colors=cols, frame_id="cam", stamp_ns=12 * 10**9 + 5,
                                   dtype=dtype)  # fmt: skip
        raw = store.serialize_cdr(msg, "sensor_msgs/msg/PointCloud2")
        back = store.deserialize_cdr(raw, "sensor_msgs/msg/PointCloud2")
        assert back.header.frame_id == "cam" and back.header.stamp.sec == 12
        assert back.header.stamp.nanosec == 5
        np.testing.assert_allclose(pointcloud2_to_array(back), pts, rtol=0, atol=atol)
        assert [f.name for f in back.fields] == ["x", "y", "z", "rgb"]


def test_empty_message_gives_an_empty_array() -> None:
    msg = array_to_pointcloud2(np.zeros((0, 3)))
    assert pointcloud2_to_array(msg).shape == (0, 3)


def _good() -> SimpleNamespace:
    pts = np.arange(12.0).reshape(4, 3) / 10
    return _pack_cloud(pts, height=2, codes={"x": "f4", "y": "f4", "z": "f4"},
                       order=["x", "y", "z"], gap=0, row_pad=0, big_endian=False,
                       is_dense=True)  # fmt: skip


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m: setattr(m, "fields", m.fields[:2]), "has no field 'z'"),
        (lambda m: setattr(m.fields[2], "datatype", 6), "field 'z' must be one FLOAT32"),
        (lambda m: setattr(m.fields[1], "datatype", 42), "unknown datatype 42"),
        (lambda m: setattr(m.fields[2], "offset", 10), r"spans bytes 10\.\.14 of a 12-byte"),
        (lambda m: setattr(m, "data", m.data[:-1]), "holds 47 bytes but 2×2 points"),
        (lambda m: setattr(m, "row_step", 20), "row_step 20 is shorter"),
        # the header's point count lowered (one row of two): the surplus row is not dropped
        (lambda m: setattr(m, "height", 1), "24 bytes the header does not count"),
        (lambda m: (setattr(m, "width", 0), setattr(m, "row_step", 0)),
         "48 bytes but 2×0 points: none counted"),
        (lambda m: setattr(m, "data", m.data + b"\0" * 12), "12 bytes the header does not count"),
        (lambda m: setattr(m, "height", -1), "negative size"),
        (
            lambda m: setattr(m, "data", m.data[:12] + struct.pack("<f", np.nan) + m.data[16:]),
            "says is_dense but 1 of 4",
        ),
    ],
)
def test_bad_messages_are_refused_with_the_reason(change: Any, message: str) -> None:
    msg = _good()
    change(msg)
    with pytest.raises(InvalidArgumentError, match=message):
        pointcloud2_to_array(msg)


def test_not_a_message_is_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="must be a sensor_msgs/msg/PointCloud2"):
        pointcloud2_to_array(np.zeros(3))


def test_array_to_pointcloud2_refuses_bad_arguments() -> None:
    with pytest.raises(InvalidArgumentError, match=r"`points` must be a \(n, 3\)"):
        array_to_pointcloud2(np.zeros((3, 2)))
    with pytest.raises(InvalidArgumentError, match="`dtype` must be"):
        array_to_pointcloud2(np.zeros((3, 3)), dtype="float16")
    with pytest.raises(InvalidArgumentError, match="`colors` must lie in"):
        array_to_pointcloud2(np.zeros((1, 3)), colors=[[2.0, 0, 0]])
    with pytest.raises(InvalidArgumentError, match="`stamp_ns` must be an integer >= 0"):
        array_to_pointcloud2(np.zeros((1, 3)), stamp_ns=-1)


def test_missing_rosbags_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    from deformap.cloud.io import _bag, _bag_reader

    monkeypatch.setitem(sys.modules, "rosbags", None)
    monkeypatch.setitem(sys.modules, "rosbags.typesys", None)
    monkeypatch.setitem(sys.modules, "rosbags.rosbag2", None)
    _bag_reader.typestore.cache_clear()
    try:
        with pytest.raises(MissingDependencyError, match=r"pip install 'deformap\[ros\]'"):
            array_to_pointcloud2(np.zeros((1, 3)))
        with pytest.raises(MissingDependencyError, match="reading ROS 2 bags"):
            _bag.read_bag_wrenches("x", "/ft")
    finally:
        _bag_reader.typestore.cache_clear()
