from __future__ import annotations

import logging
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformap.cloud import PointCloud
from deformap.cloud.io import (
    MM_EXTENT_THRESHOLD,
    PCD_ENCODINGS,
    PLY_FORMATS,
    read_cloud,
    read_npz,
    read_pcd,
    read_ply,
    write_cloud,
    write_npz,
    write_pcd,
    write_ply,
)
from deformap.errors import DeformapError, FileFormatError, InvalidArgumentError


def _cloud(n: int = 50, seed: int = 0, colors: bool = True) -> PointCloud:
    rng = np.random.default_rng(seed)
    pts = rng.uniform([0, 0, 0], [0.6, 0.4, 0.1], (n, 3))
    return PointCloud(pts, rng.integers(0, 256, (n, 3)) if colors else None)


def _extras(n: int) -> dict[str, np.ndarray]:
    return {
        "intensity": np.linspace(0, 1, n).astype(np.float32),
        "ring": (np.arange(n) % 16).astype(np.uint16),
        "label": (np.arange(n) - 7).astype(np.int32),
    }


# ---- round trips ----


@pytest.mark.parametrize("encoding", PCD_ENCODINGS)
@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_pcd_round_trip(tmp_path: Path, encoding: str, dtype: str) -> None:
    cloud, extras = _cloud(), _extras(50)
    path = tmp_path / "c.pcd"
    write_pcd(path, cloud, encoding=encoding, dtype=dtype, extra_fields=extras)
    got, got_extras = read_pcd(path)
    # float32 storage rounds to half an ulp at 0.6 m; pypcd4's ascii prints 10 decimals.
    atol = 4e-8 if dtype == "float32" else (1e-10 if encoding == "ascii" else 0.0)
    np.testing.assert_allclose(got.points, cloud.points, rtol=0, atol=atol)
    assert got.colors is not None and cloud.colors is not None
    np.testing.assert_array_equal(got.colors, cloud.colors)
    assert sorted(got_extras) == sorted(extras)
    for name, values in extras.items():
        assert got_extras[name].dtype == values.dtype
        np.testing.assert_allclose(got_extras[name], values, rtol=0, atol=1e-9)


@pytest.mark.parametrize("fmt", PLY_FORMATS)
@pytest.mark.parametrize("colors", [True, False])
def test_ply_round_trip_is_exact(tmp_path: Path, fmt: str, colors: bool) -> None:
    cloud, extras = _cloud(colors=colors), _extras(50)
    path = tmp_path / "c.ply"
    write_ply(path, cloud, format=fmt, extra_fields=extras)
    got, got_extras = read_ply(path)
    np.testing.assert_array_equal(got.points, cloud.points)
    if colors:
        np.testing.assert_array_equal(got.colors, cloud.colors)  # type: ignore[arg-type]
    else:
        assert got.colors is None
    assert sorted(got_extras) == sorted(extras)
    for name, values in extras.items():
        assert got_extras[name].dtype == values.dtype
        np.testing.assert_array_equal(got_extras[name], values)


@pytest.mark.parametrize("compressed", [True, False])
def test_npz_round_trip_is_exact(tmp_path: Path, compressed: bool) -> None:
    cloud = _cloud()
    path = tmp_path / "c.npz"
    write_npz(path, cloud, compressed=compressed, extra_fields={"t": np.arange(50.0)})
    got, extras = read_npz(path)
    np.testing.assert_array_equal(got.points, cloud.points)
    np.testing.assert_array_equal(got.colors, cloud.colors)  # type: ignore[arg-type]
    np.testing.assert_array_equal(extras["t"], np.arange(50.0))


@pytest.mark.parametrize("suffix", [".pcd", ".ply", ".npz", ".PLY"])
@pytest.mark.parametrize("binary", [True, False])
def test_read_and_write_cloud_dispatch_on_the_suffix(
    tmp_path: Path, suffix: str, binary: bool
) -> None:
    cloud = _cloud(colors=False)
    path = tmp_path / f"c{suffix}"
    write_cloud(path, cloud, binary=binary)
    got = read_cloud(path)
    np.testing.assert_allclose(got.points, cloud.points, rtol=0, atol=1e-10)
    assert got.frame == "world"


def test_format_argument_overrides_the_suffix(tmp_path: Path) -> None:
    path = tmp_path / "cloud.dat"
    write_cloud(path, _cloud(), format="ply")
    assert path.read_bytes().startswith(b"ply\n")
    assert len(read_cloud(path, format="ply")) == 50
    write_cloud(path, _cloud(), format="npz")
    assert zipfile.is_zipfile(path) and len(read_cloud(path, format="npz")) == 50


def test_ply_from_another_writer_with_faces_and_float_colours(tmp_path: Path) -> None:
    text = (
        "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float red\nproperty float green\nproperty float blue\nproperty float nx\n"
        "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 1 0 0 0.5\n0.1 0 0 0 1 0 0.5\n0 0.1 0 0 0 1 0.5\n0 0 0.1 1 1 1 0.5\n"
        "3 0 1 2\n3 0 2 3\n"
    )
    path = tmp_path / "hand.ply"
    path.write_text(text)
    cloud, extras = read_ply(path)
    np.testing.assert_allclose(cloud.points[1], [0.1, 0, 0], rtol=1e-7)
    np.testing.assert_array_equal(cloud.colors[2], [0, 0, 1])  # type: ignore[index]
    assert list(extras) == ["nx"]


def test_binary_ply_skips_fixed_size_elements_before_the_vertices(tmp_path: Path) -> None:
    pre = np.array([(1.5, 7)], dtype=[("a", "<f8"), ("b", "<i4")])
    verts = np.array([(0.1, 0.2, 0.3), (0.0, 0.1, 0.2)], dtype=[(a, "<f4") for a in "xyz"])
    header = (
        "ply\nformat binary_little_endian 1.0\nelement camera 1\nproperty double a\n"
        "property int b\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
        "end_header\n"
    )
    path = tmp_path / "pre.ply"
    path.write_bytes(header.encode() + pre.tobytes() + verts.tobytes())
    cloud, _ = read_ply(path)
    np.testing.assert_allclose(cloud.points, [[0.1, 0.2, 0.3], [0.0, 0.1, 0.2]], rtol=1e-7)


def test_pcd_from_pcl_with_padding_and_integer_rgb_in_ascii(tmp_path: Path) -> None:
    text = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z _ rgb\n"
        "SIZE 4 4 4 1 4\nTYPE F F F U F\nCOUNT 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\n"
        "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
        "0.1 0.2 0.3 0 16711680\n0.4 0.5 0.6 0 255\n"
    )
    path = tmp_path / "pcl.pcd"
    path.write_text(text)
    cloud, extras = read_pcd(path)
    np.testing.assert_allclose(cloud.points, [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]], rtol=1e-7)
    np.testing.assert_array_equal(cloud.colors, [[1, 0, 0], [0, 0, 1]])  # type: ignore[arg-type]
    assert extras == {}


# ---- units and NaN ----


@pytest.mark.parametrize("suffix", [".pcd", ".ply", ".npz"])
def test_millimetre_clouds_are_refused_unless_units_say_so(tmp_path: Path, suffix: str) -> None:
    cloud_mm = PointCloud(_cloud(colors=False).points * 1000.0)
    path = tmp_path / f"mm{suffix}"
    write_cloud(path, cloud_mm)
    with pytest.raises(FileFormatError, match=r"mm\.\w+: coordinates reach .* millimetres"):
        read_cloud(path)
    got = read_cloud(path, units="mm")
    np.testing.assert_allclose(got.points, cloud_mm.points * 1e-3, rtol=1e-12)
    assert np.abs(got.points).max() < MM_EXTENT_THRESHOLD


@pytest.mark.parametrize("suffix", [".pcd", ".ply", ".npz"])
def test_nan_points_are_refused_or_dropped_on_request(
    tmp_path: Path, suffix: str, caplog: pytest.LogCaptureFixture
) -> None:
    pts = _cloud(colors=False).points.copy()
    pts[[3, 10], 1] = np.nan
    path = tmp_path / f"nan{suffix}"
    # PointCloud refuses NaN, so write the raw file with the format's own writer of a valid cloud
    # and a NaN-free placeholder, then patch the coordinates in.
    _write_raw(path, pts)
    with pytest.raises(FileFormatError, match=r"nan\.\w+: 2 of 50 points have a NaN"):
        read_cloud(path)
    with caplog.at_level(logging.WARNING, logger="deformap.cloud.io"):
        got = read_cloud(path, drop_nan=True)
    assert len(got) == 48
    np.testing.assert_allclose(got.points, np.delete(pts, [3, 10], axis=0), rtol=1e-7)
    assert "dropped 2 of 50 points" in caplog.text


def _write_raw(path: Path, pts: np.ndarray) -> None:
    if path.suffix == ".npz":
        np.savez(path, points=pts)
    elif path.suffix == ".ply":
        table = np.array([tuple(p) for p in pts], dtype=[(a, "<f8") for a in "xyz"])
        header = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\n"
        header += "".join(f"property double {a}\n" for a in "xyz") + "end_header\n"
        path.write_bytes(header.encode() + table.tobytes())
    else:
        from pypcd4 import PointCloud as PcdCloud

        PcdCloud.from_xyz_points(pts.astype(np.float32)).save(path)


def test_empty_and_all_nan_clouds_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "empty.npz"
    np.savez(path, points=np.zeros((0, 3)))
    with pytest.raises(FileFormatError, match=r"empty\.npz: the cloud is empty"):
        read_cloud(path)
    path = tmp_path / "allnan.npz"
    np.savez(path, points=np.full((3, 3), np.nan))
    with pytest.raises(FileFormatError, match="every point has a NaN"):
        read_cloud(path, drop_nan=True)
    path = tmp_path / "empty.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n")  # fmt: skip
    with pytest.raises(FileFormatError, match="empty"):
        read_cloud(path)
    path = tmp_path / "empty.pcd"
    from pypcd4 import PointCloud as PcdCloud

    PcdCloud.from_xyz_points(np.zeros((0, 3), np.float32)).save(path)
    with pytest.raises(FileFormatError, match="empty"):
        read_cloud(path)


# ---- bad input ----


def test_missing_xyz_fields_are_named(tmp_path: Path) -> None:
    path = tmp_path / "noz.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                    "property float y\nproperty float w\nend_header\n1 2 3\n")  # fmt: skip
    with pytest.raises(FileFormatError, match=r"noz\.ply: .* no property 'z'"):
        read_cloud(path)
    from pypcd4 import PointCloud as PcdCloud

    path = tmp_path / "noy.pcd"
    PcdCloud.from_points(np.zeros((2, 3)), ("x", "q", "z"), (np.float32,) * 3).save(path)
    with pytest.raises(FileFormatError, match=r"noy\.pcd: PCD has no field 'y'"):
        read_cloud(path)
    path = tmp_path / "nopoints.npz"
    np.savez(path, xyz=np.zeros((2, 3)))
    with pytest.raises(FileFormatError, match=r"nopoints\.npz: NPZ has no array 'points'"):
        read_cloud(path)
    path = tmp_path / "shape.npz"
    np.savez(path, points=np.zeros((2, 2)))
    with pytest.raises(FileFormatError, match=r"'points' must be \(n, 3\)"):
        read_cloud(path)


def test_pickled_npz_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "pickled.npz"
    np.savez(path, points=np.array([object(), 1], dtype=object))
    with pytest.raises(FileFormatError,
                       match=r"pickled\.npz: NPZ member 'points\.npy' holds Python objects"):
        read_cloud(path)


def test_unknown_suffix_missing_file_and_bad_arguments(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match=r"c\.xyz: unknown point-cloud suffix '\.xyz'"):
        read_cloud(tmp_path / "c.xyz")
    with pytest.raises(FileFormatError, match=r"missing\.pcd: no such file"):
        read_cloud(tmp_path / "missing.pcd")
    with pytest.raises(FileFormatError, match="not a regular file"):
        read_pcd(tmp_path)
    with pytest.raises(InvalidArgumentError, match="`units` must be one of"):
        read_cloud(tmp_path / "x.pcd", units="cm")
    with pytest.raises(InvalidArgumentError, match="`format` must be one of"):
        read_cloud(tmp_path / "x.pcd", format="las")
    with pytest.raises(InvalidArgumentError, match="`path` must be a str"):
        read_cloud(3)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`cloud` must hold at least one point"):
        write_cloud(tmp_path / "e.ply", PointCloud(np.zeros((0, 3))))
    with pytest.raises(InvalidArgumentError, match="`cloud` must be a PointCloud"):
        write_cloud(tmp_path / "e.ply", np.zeros((3, 3)))  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`encoding` must be one of"):
        write_pcd(tmp_path / "e.pcd", _cloud(), encoding="lzma")
    with pytest.raises(InvalidArgumentError, match="`format` must be one of"):
        write_ply(tmp_path / "e.ply", _cloud(), format="binary")
    with pytest.raises(InvalidArgumentError, match=r"`extra_fields\['t'\]` must be a \(50,\)"):
        write_ply(tmp_path / "e.ply", _cloud(), extra_fields={"t": np.zeros(3)})
    with pytest.raises(InvalidArgumentError, match="PLY cannot store"):
        write_ply(tmp_path / "e.ply", _cloud(), extra_fields={"t": np.zeros(50, np.int64)})
    with pytest.raises(InvalidArgumentError, match="keys must be identifiers"):
        write_npz(tmp_path / "e.npz", _cloud(), extra_fields={"x": np.zeros(50)})


@pytest.mark.parametrize("suffix", [".pcd", ".ply", ".npz"])
def test_a_file_name_the_system_refuses_is_a_file_format_error(tmp_path: Path, suffix: str) -> None:
    with pytest.raises(FileFormatError, match="File name too long"):
        read_cloud(tmp_path / ("a" * 300 + suffix))


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda b: b[: len(b) - 7], "truncated"),
        (lambda b: b.replace(b"POINTS 50", b"POINTS 5000000000"), "POINTS"),
        (lambda b: b.replace(b"FIELDS x y z", b"FIELDS x y"), "FIELDS"),
        (lambda b: b.replace(b"DATA binary", b"DATA xml"), "could not read"),
        (lambda b: b.replace(b"TYPE F F F", b"TYPE F F Q"), "could not read"),
    ],
)
def test_corrupted_pcd_headers_name_the_file(tmp_path: Path, mutate, message: str) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "bad.pcd"
    write_pcd(path, _cloud(colors=False), encoding="binary")
    path.write_bytes(mutate(path.read_bytes()))
    with pytest.raises(FileFormatError, match=rf"bad\.pcd: .*{message}"):
        read_cloud(path)


def test_truncated_ply_and_compressed_pcd_name_the_problem(tmp_path: Path) -> None:
    path = tmp_path / "t.ply"
    write_ply(path, _cloud())
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(FileFormatError, match=r"t\.ply: .*truncated"):
        read_cloud(path)
    path = tmp_path / "t.pcd"
    # A repetitive cloud, so that LZF compresses it (pypcd4 writes plain binary otherwise).
    write_pcd(path, PointCloud(np.tile([0.1, 0.2, 0.3], (500, 1))), encoding="binary_compressed")
    assert b"DATA binary_compressed" in path.read_bytes()
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(FileFormatError, match=r"t\.pcd: binary_compressed body .*truncated"):
        read_cloud(path)


_ASCII_PLY_HEADER = (
    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
    "property float z\n{extra}end_header\n"
)


@pytest.mark.parametrize(
    "body",
    [
        "\n0.1 0.2 0.3\n0.4 0.5 0.6\n",  # a blank line before the rows
        "0.1 0.2 0.3\n\n0.4 0.5 0.6\n",  # and between them
        "# made by hand\n0.1 0.2 0.3\n0.4 0.5 0.6\n",
    ],
)
def test_ascii_ply_rows_are_read_as_written_or_refused(tmp_path: Path, body: str) -> None:
    path = tmp_path / "rows.ply"
    path.write_text(_ASCII_PLY_HEADER.format(extra="") + body)
    try:
        cloud, _ = read_ply(path)
    except FileFormatError as exc:
        assert "rows.ply" in str(exc)
    else:
        np.testing.assert_allclose(cloud.points, [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]], rtol=1e-7)


def test_ascii_ply_with_more_rows_than_declared_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "more.ply"
    path.write_text(_ASCII_PLY_HEADER.format(extra="") + "0.1 0.2 0.3\n0.4 0.5 0.6\n0.7 0.8 0.9\n")
    with pytest.raises(FileFormatError, match=r"more\.ply: .*declares 2 .*3"):
        read_ply(path)


@pytest.mark.parametrize(
    ("prop", "values", "match"),
    [
        ("uchar red", ("300", "0"), r"'red' .*uchar.* 300"),
        ("uchar red", ("-5", "0"), r"'red' .*uchar.* -5"),
        ("int ring", ("2.5", "1"), r"'ring' .*int.* 2\.5"),
        ("float intensity", ("1e300", "1"), r"'intensity' .*float.* 1e\+300"),
    ],
)
def test_ascii_ply_values_that_do_not_fit_their_type_are_refused(
    tmp_path: Path, prop: str, values: tuple[str, str], match: str
) -> None:
    if prop.endswith("red"):
        extra = "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        rows = [f"0.1 0.2 0.3 {values[0]} 0 0", f"0.4 0.5 0.6 {values[1]} 0 0"]
    else:
        extra = f"property {prop}\n"
        rows = [f"0.1 0.2 0.3 {values[0]}", f"0.4 0.5 0.6 {values[1]}"]
    path = tmp_path / "fit.ply"
    path.write_text(_ASCII_PLY_HEADER.format(extra=extra) + "\n".join(rows) + "\n")
    with pytest.raises(FileFormatError, match=rf"fit\.ply: .*{match}"):
        read_ply(path)


# ---- corruption fuzzing: succeed or raise a DeformapError, nothing else ----


def _valid_files(tmp: Path) -> list[Path]:
    cloud, extras = _cloud(20, seed=4), _extras(20)
    paths = []
    # A lattice with repeated coordinates, so that LZF really compresses the binary_compressed one.
    g = np.arange(5) * 0.01
    lattice = PointCloud(np.stack(np.meshgrid(g, g, [0.0]), -1).reshape(-1, 3)[:20], cloud.colors)
    for enc in PCD_ENCODINGS:
        paths.append(tmp / f"v_{enc}.pcd")
        write_pcd(paths[-1], lattice, encoding=enc, dtype="float32", extra_fields=extras)
        assert f"DATA {enc}".encode() in paths[-1].read_bytes()
    for fmt in PLY_FORMATS:
        paths.append(tmp / f"v_{fmt}.ply")
        write_ply(paths[-1], cloud, format=fmt, extra_fields=extras)
    for compressed in (True, False):
        paths.append(tmp / f"v_{compressed}.npz")
        write_npz(paths[-1], cloud, compressed=compressed)
    return paths


def _corrupt(data: bytes, kind: str, a: int, b: int, junk: bytes) -> bytes:
    if not data:
        return data
    i, j = sorted((a % len(data), b % len(data)))
    if kind == "truncate":
        return data[:i]
    if kind == "flip":
        return data[:i] + bytes([data[i] ^ (1 + b % 255)]) + data[i + 1 :]
    if kind == "splice":
        return data[:i] + junk + data[j:]
    # Garble one header line: replace the text between two newlines near the start.
    head = data[:400]
    lines = head.split(b"\n")
    k = a % max(len(lines) - 1, 1)
    lines[k] = junk
    return b"\n".join(lines) + data[400:]


@settings(
    max_examples=250, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    which=st.integers(min_value=0, max_value=7),
    kind=st.sampled_from(["truncate", "flip", "splice", "header"]),
    a=st.integers(min_value=0, max_value=10**6),
    b=st.integers(min_value=0, max_value=10**6),
    junk=st.binary(max_size=24),
)
def test_corrupted_files_never_raise_anything_but_deformap_errors(
    tmp_path: Path, which: int, kind: str, a: int, b: int, junk: bytes
) -> None:
    """Each read is refused naming the file, or returns a finite cloud; where the damage can be
    told (a cut file, a zip's CRC, bytes left as they were) a read that succeeds returns the
    intact file's points. A flipped byte inside raw floats cannot be told (no format checksums
    them): such a read must only return a finite cloud."""
    sources = _valid_files_cache(tmp_path)
    src = sources[which]
    bad = tmp_path / f"fuzz{src.suffix}"
    original = src.read_bytes()
    corrupted = _corrupt(original, kind, a, b, junk)
    bad.write_bytes(corrupted)
    must_match = corrupted == original or kind == "truncate" or src.suffix == ".npz"
    for drop_nan in (False, True):
        try:
            cloud = read_cloud(bad, drop_nan=drop_nan)
        except DeformapError as exc:
            assert "fuzz" in str(exc)
        else:
            assert isinstance(cloud, PointCloud) and len(cloud) > 0
            assert np.isfinite(cloud.points).all()
            if must_match:
                # an ASCII file cut after its last number reads whole
                np.testing.assert_array_equal(cloud.points, read_cloud(src).points)


_CACHE: dict[Path, list[Path]] = {}


def _valid_files_cache(tmp: Path) -> list[Path]:
    if tmp not in _CACHE:
        _CACHE[tmp] = _valid_files(tmp)
    return _CACHE[tmp]
