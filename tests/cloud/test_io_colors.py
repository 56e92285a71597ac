"""Colours through every cloud format: written when a cloud has them, read in the layouts that PCL,
PLY tools and ROS drivers use, and refused with one line naming the field and the file when NaN,
out of range or malformed. A constant, black or saturated colour is valid data at this layer."""

from __future__ import annotations

import struct
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.cloud.io import (
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
from deformap.errors import DeformapError, FileFormatError


def _cloud(n: int = 40, seed: int = 0) -> PointCloud:
    """Points with 8-bit colours (k/255), as a camera gives them."""
    rng = np.random.default_rng(seed)
    return PointCloud(rng.uniform(-0.5, 0.5, (n, 3)), rng.integers(0, 256, (n, 3)) / 255.0)


def _word(rgb: tuple[int, int, int], alpha: int = 0) -> int:
    return (alpha << 24) | (rgb[0] << 16) | (rgb[1] << 8) | rgb[2]


# -- round trips --------------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", PCD_ENCODINGS)
def test_pcd_round_trips_8_bit_colours_exactly(tmp_path: Path, encoding: str) -> None:
    cloud = _cloud()
    write_pcd(tmp_path / "c.pcd", cloud, encoding=encoding)
    got, extras = read_pcd(tmp_path / "c.pcd")
    np.testing.assert_array_equal(got.colors, cloud.colors)  # type: ignore[arg-type]
    assert extras == {}


@pytest.mark.parametrize("fmt", PLY_FORMATS)
def test_ply_round_trips_8_bit_colours_exactly(tmp_path: Path, fmt: str) -> None:
    cloud = _cloud()
    write_ply(tmp_path / "c.ply", cloud, format=fmt)
    got, _ = read_ply(tmp_path / "c.ply")
    np.testing.assert_array_equal(got.colors, cloud.colors)  # type: ignore[arg-type]


def test_any_colour_rounds_to_the_nearest_8_bit_level_and_npz_keeps_it_exactly(
        tmp_path: Path) -> None:  # fmt: skip
    rng = np.random.default_rng(1)
    cloud = PointCloud(rng.uniform(0, 1, (30, 3)), rng.uniform(0, 1, (30, 3)))
    for name in ("c.pcd", "c.ply"):
        write_cloud(tmp_path / name, cloud)
        got = read_cloud(tmp_path / name)
        assert got.colors is not None and cloud.colors is not None
        assert np.abs(got.colors - cloud.colors).max() <= 0.5 / 255 + 1e-12
    write_npz(tmp_path / "c.npz", cloud)
    got, _ = read_npz(tmp_path / "c.npz")
    np.testing.assert_array_equal(got.colors, cloud.colors)  # type: ignore[arg-type]


@pytest.mark.parametrize("name", ["c.pcd", "c.ply", "c.npz"])
@pytest.mark.parametrize("value", [0.0, 1.0, 0.5])
def test_black_saturated_and_constant_colours_are_valid(tmp_path: Path, name: str,
                                                        value: float) -> None:  # fmt: skip
    cloud = PointCloud(_cloud().points, np.full((40, 3), round(value * 255) / 255))
    write_cloud(tmp_path / name, cloud)
    np.testing.assert_array_equal(read_cloud(tmp_path / name).colors, cloud.colors)


@pytest.mark.parametrize("name", ["c.pcd", "c.ply", "c.npz"])
def test_a_cloud_without_colour_is_written_and_read_without(tmp_path: Path, name: str) -> None:
    write_cloud(tmp_path / name, PointCloud(_cloud().points))
    assert read_cloud(tmp_path / name).colors is None


# -- PCD layouts ---------------------------------------------------------------------------------


def _pcd(path: Path, fields: list[tuple[str, str, str]], rows: list[tuple[Any, ...]],
         encoding: str = "binary") -> Path:  # fmt: skip
    """A PCD written by hand: ``fields`` as (name, TYPE, struct code), one tuple per point."""
    sizes = " ".join(str(struct.calcsize(c)) for _, _, c in fields)
    header = (f"VERSION 0.7\nFIELDS {' '.join(f for f, _, _ in fields)}\nSIZE {sizes}\n"
              f"TYPE {' '.join(t for _, t, _ in fields)}\nCOUNT {' '.join('1' for _ in fields)}\n"
              f"WIDTH {len(rows)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(rows)}\n"
              f"DATA {encoding}\n")  # fmt: skip
    if encoding == "ascii":
        body = "".join(" ".join(str(v) for v in row) + "\n" for row in rows).encode()
    else:
        fmt = "<" + "".join(c for _, _, c in fields)
        body = b"".join(struct.pack(fmt, *row) for row in rows)
    path.write_bytes(header.encode() + body)
    return path


XYZ = [("x", "F", "f"), ("y", "F", "f"), ("z", "F", "f")]
RGB = [(255, 0, 0), (0, 128, 255), (17, 34, 51)]


def _as_float(word: int) -> float:
    return float(struct.unpack("<f", struct.pack("<I", word))[0])


@pytest.mark.parametrize("alpha", [0, 255])
def test_pcd_rgb_packed_in_a_float_as_pcl_writes_it(tmp_path: Path, alpha: int) -> None:
    # with an alpha byte of 255 (PCL's PointXYZRGB) the float of some words is NaN: only bits count
    rows = [(0.1 * i, 0.0, 0.0, _as_float(_word(c, alpha))) for i, c in enumerate(RGB)]
    path = _pcd(tmp_path / "c.pcd", [*XYZ, ("rgb", "F", "f")], rows)
    cloud, extras = read_pcd(path)
    np.testing.assert_array_equal(np.round(cloud.colors * 255), RGB)  # type: ignore[operator]
    assert extras == {}


def test_pcd_ascii_rgb_words_with_alpha_are_read_exactly(tmp_path: Path) -> None:
    # PCL's ascii writer prints the float's bits as an unsigned integer; 0xFF0000FF and its
    # neighbours differ in the last bits, which float32 cannot hold
    rows = [(0.1 * i, 0.0, 0.0, _word(c, 255)) for i, c in enumerate(RGB)]
    path = _pcd(tmp_path / "c.pcd", [*XYZ, ("rgb", "F", "f")], rows, encoding="ascii")
    np.testing.assert_array_equal(np.round(read_pcd(path)[0].colors * 255), RGB)  # type: ignore[operator]


@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_pcd_rgba_as_an_unsigned_word(tmp_path: Path, encoding: str) -> None:
    rows = [(0.1 * i, 0.0, 0.0, _word(c, 200)) for i, c in enumerate(RGB)]
    path = _pcd(tmp_path / "c.pcd", [*XYZ, ("rgba", "U", "I")], rows, encoding=encoding)
    np.testing.assert_array_equal(np.round(read_pcd(path)[0].colors * 255), RGB)  # type: ignore[operator]


@pytest.mark.parametrize(("kind", "code", "scale"), [("U", "B", 1), ("F", "f", 1 / 255)])
def test_pcd_separate_r_g_b_fields(tmp_path: Path, kind: str, code: str, scale: float) -> None:
    rows = [(0.1 * i, 0.0, 0.0, *(v * scale for v in c)) for i, c in enumerate(RGB)]
    fields = [*XYZ, ("r", kind, code), ("g", kind, code), ("b", kind, code)]
    cloud, extras = read_pcd(_pcd(tmp_path / "c.pcd", fields, rows))
    np.testing.assert_allclose(cloud.colors * 255, RGB, atol=1e-4)  # type: ignore[operator]
    assert extras == {}


@pytest.mark.parametrize(("value", "shown"), [(1.5, "1.5"), (-0.25, "-0.25"), (float("nan"), "nan")])
def test_pcd_float_colours_outside_0_1_or_nan_are_refused_naming_field_and_file(
        tmp_path: Path, value: float, shown: str) -> None:  # fmt: skip
    rows = [(0.0, 0.0, 0.0, 0.2, 0.2, 0.2), (0.1, 0.0, 0.0, 0.2, value, 0.2)]
    fields = [*XYZ, ("r", "F", "f"), ("g", "F", "f"), ("b", "F", "f")]
    path = _pcd(tmp_path / "c.pcd", fields, rows)
    with pytest.raises(FileFormatError) as info:
        read_pcd(path)
    text = str(info.value)
    assert str(path) in text and "'r/g/b'" in text and "point 1" in text and shown in text
    assert "\n" not in text


def test_pcd_rgb_of_the_wrong_size_is_refused(tmp_path: Path) -> None:
    path = _pcd(tmp_path / "c.pcd", [*XYZ, ("rgb", "F", "d")], [(0.0, 0.0, 0.0, 0.5)])
    with pytest.raises(FileFormatError, match=r"c\.pcd: colour field 'rgb' must be one 4-byte"):
        read_pcd(path)


def test_pcd_nan_point_drops_its_colour_with_drop_nan(tmp_path: Path) -> None:
    nan = float("nan")
    rows = [(0.0, 0.0, 0.0, 0.2, 0.4, 0.6), (nan, nan, nan, nan, nan, nan)]
    fields = [*XYZ, ("r", "F", "f"), ("g", "F", "f"), ("b", "F", "f")]
    cloud, _ = read_pcd(_pcd(tmp_path / "c.pcd", fields, rows), drop_nan=True)
    assert len(cloud) == 1
    np.testing.assert_allclose(cloud.colors, [[0.2, 0.4, 0.6]], atol=1e-7)  # type: ignore[arg-type]


# -- PLY and NPZ ---------------------------------------------------------------------------------


def _ply(path: Path, props: list[tuple[str, str]], rows: list[str]) -> Path:
    head = ["ply", "format ascii 1.0", f"element vertex {len(rows)}",
            *(f"property {t} {n}" for n, t in props), "end_header"]  # fmt: skip
    path.write_text("\n".join(head + rows) + "\n")
    return path


XYZ_PLY = [("x", "float"), ("y", "float"), ("z", "float")]


def test_ply_float_red_green_blue_in_0_1(tmp_path: Path) -> None:
    props = [*XYZ_PLY, ("red", "float"), ("green", "float"), ("blue", "float")]
    path = _ply(tmp_path / "c.ply", props, ["0 0 0 1 0.5 0", "0.1 0 0 0 0 0"])
    np.testing.assert_allclose(read_ply(path)[0].colors, [[1, 0.5, 0], [0, 0, 0]])  # type: ignore[arg-type]


@pytest.mark.parametrize(("kind", "value", "limit"),
                         [("float", "1.2", "[0, 1]"), ("float", "nan", "[0, 1]"),
                          ("ushort", "300", "[0, 255]")])  # fmt: skip
def test_ply_colours_out_of_range_are_refused(tmp_path: Path, kind: str, value: str,
                                              limit: str) -> None:  # fmt: skip
    props = [*XYZ_PLY, ("red", kind), ("green", kind), ("blue", kind)]
    path = _ply(tmp_path / "c.ply", props, ["0 0 0 0 0 0", f"0.1 0 0 0 0 {value}"])
    with pytest.raises(FileFormatError) as info:
        read_ply(path)
    text = str(info.value)
    assert str(path) in text and "'red/green/blue'" in text and limit in text and "point 1" in text


def test_ply_with_only_some_colour_properties_is_refused(tmp_path: Path) -> None:
    props = [*XYZ_PLY, ("red", "uchar"), ("green", "uchar")]
    path = _ply(tmp_path / "c.ply", props, ["0 0 0 10 20"])
    with pytest.raises(FileFormatError, match=r"c\.ply: .*colour properties \['red', 'green'\] "
                                              r"but not \['blue'\]"):
        read_ply(path)


def test_npz_colours_nan_or_out_of_range_are_refused(tmp_path: Path) -> None:
    pts = np.zeros((3, 3))
    for bad, shown in ((np.nan, "nan"), (2.0, "2")):
        cols = np.full((3, 3), 0.5)
        cols[2, 1] = bad
        np.savez(tmp_path / "c.npz", points=pts, colors=cols)
        with pytest.raises(FileFormatError, match=r"c\.npz: colour field 'colors' of point 2 is "
                                                  rf"\(0\.5, {shown}, 0\.5\)"):
            read_npz(tmp_path / "c.npz")


def test_npz_nan_point_drops_its_nan_colour(tmp_path: Path) -> None:
    pts = np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    cols = np.array([[0.1, 0.2, 0.3], [np.nan, np.nan, np.nan]])
    np.savez(tmp_path / "c.npz", points=pts, colors=cols)
    cloud, _ = read_npz(tmp_path / "c.npz", drop_nan=True)
    np.testing.assert_array_equal(cloud.colors, [[0.1, 0.2, 0.3]])  # type: ignore[arg-type]


# -- PointCloud2 ---------------------------------------------------------------------------------

_PF = {"u1": (2, "B"), "u4": (6, "I"), "f4": (7, "f"), "f8": (8, "d")}


def _message(xyz: np.ndarray, colour: list[tuple[str, str, list[Any]]], *, height: int = 1,
             big_endian: bool = False, extra_step: int = 0) -> SimpleNamespace:  # fmt: skip
    """A PointCloud2 packed with struct: x, y, z FLOAT32, then ``colour`` fields (name, numpy
    code, one value per point), in an implementation independent of the reader's."""
    fields, offset = [], 0
    for name, code in [("x", "f4"), ("y", "f4"), ("z", "f4"), *((n, c) for n, c, _ in colour)]:
        fields.append(SimpleNamespace(name=name, offset=offset, datatype=_PF[code][0], count=1))
        offset += struct.calcsize(_PF[code][1])
    step = offset + extra_step
    fmt = (">" if big_endian else "<") + "fff" + "".join(_PF[c][1] for _, c, _ in colour)
    data = bytearray(step * len(xyz))
    for i, p in enumerate(xyz):
        struct.pack_into(fmt, data, i * step, *p, *(values[i] for _, _, values in colour))
    return SimpleNamespace(
        height=height, width=len(xyz) // height, point_step=step,
        row_step=step * len(xyz) // height, fields=fields, is_bigendian=big_endian,
        is_dense=not np.isnan(xyz).any(), data=bytes(data),
        header=SimpleNamespace(frame_id="camera", stamp=SimpleNamespace(sec=0, nanosec=0)),
    )  # fmt: skip


def _pc2(msg: Any) -> PointCloud:
    pytest.importorskip("rosbags")
    from deformap.cloud.io import pointcloud2_to_cloud

    return pointcloud2_to_cloud(msg, where="lab.mcap [/points message 1]")[0]


XYZ4 = np.array([[0.1, 0.0, 0.5], [0.2, 0.0, 0.5], [0.3, 0.1, 0.5], [0.4, 0.1, 0.5]])
RGB4 = [(255, 0, 0), (0, 128, 255), (17, 34, 51), (255, 255, 255)]


@pytest.mark.parametrize("big_endian", [False, True])
@pytest.mark.parametrize(("name", "code", "alpha"),
                         [("rgb", "f4", 0), ("rgb", "f4", 255), ("rgb", "u4", 0),
                          ("rgba", "u4", 255), ("rgba", "f4", 255)])  # fmt: skip
def test_pointcloud2_packed_layouts_as_drivers_publish_them(name: str, code: str, alpha: int,
                                                            big_endian: bool) -> None:  # fmt: skip
    words = [_word(c, alpha) for c in RGB4]
    values = [_as_float(w) for w in words] if code == "f4" else words
    cloud = _pc2(_message(XYZ4, [(name, code, values)], big_endian=big_endian))
    np.testing.assert_array_equal(np.round(cloud.colors * 255), RGB4)  # type: ignore[operator]


@pytest.mark.parametrize(("code", "scale"), [("u1", 1), ("f4", 1 / 255)])
def test_pointcloud2_separate_r_g_b_fields(code: str, scale: float) -> None:
    colour = [(c, code, [v[i] * scale for v in RGB4]) for i, c in enumerate("rgb")]
    cloud = _pc2(_message(XYZ4, colour, extra_step=2))  # padded points
    np.testing.assert_allclose(cloud.colors * 255, RGB4, atol=1e-4)  # type: ignore[operator]


def test_pointcloud2_organised_holes_drop_their_colours() -> None:
    xyz = XYZ4.copy()
    xyz[1] = np.nan
    colour = [(c, "f4", [np.nan if k == 1 else v[i] / 255 for k, v in enumerate(RGB4)])
              for i, c in enumerate("rgb")]  # a NaN colour on the hole only
    cloud = _pc2(_message(xyz, colour, height=2))
    np.testing.assert_allclose(cloud.colors * 255, [RGB4[0], *RGB4[2:]], atol=1e-4)  # type: ignore[operator]


@pytest.mark.parametrize(("colour", "words"), [
    ([("r", "f4", [0.1, 0.2, np.nan, 0.4]), ("g", "f4", [0.0] * 4), ("b", "f4", [0.0] * 4)],
     "colour field 'r/g/b' of point 2 is (nan, 0, 0)"),
    ([("r", "f4", [0.1, 0.2, 1.5, 0.4]), ("g", "f4", [0.0] * 4), ("b", "f4", [0.0] * 4)],
     "floats must lie in [0, 1]"),
    ([("r", "u1", [1] * 4), ("g", "u1", [1] * 4)], "colour fields r, g, b must be all three"),
    ([("r", "u1", [1] * 4), ("g", "f4", [1.0] * 4), ("b", "u1", [1] * 4)], "of one type"),
    ([("rgb", "u1", [1] * 4)], "colour field 'rgb' must be one FLOAT32 or UINT32 word"),
    ([("rgb", "f8", [0.5] * 4)], "colour field 'rgb' must be one FLOAT32 or UINT32 word"),
])  # fmt: skip
def test_pointcloud2_bad_colours_are_refused_naming_field_and_message(
        colour: list[Any], words: str) -> None:  # fmt: skip
    with pytest.raises(FileFormatError) as info:
        _pc2(_message(XYZ4, colour))
    text = str(info.value)
    assert text.startswith("lab.mcap [/points message 1]: ") and words in text, text
    assert "\n" not in text


def test_pointcloud2_rgb_field_past_the_point_step_is_refused() -> None:
    msg = _message(XYZ4, [("rgb", "u4", [0] * 4)])
    msg.point_step = msg.row_step = 14  # the rgb word at 12..16 no longer fits
    msg.data = msg.data[: 14 * 4]
    with pytest.raises(DeformapError, match=r"lab\.mcap .*field 'rgb' spans bytes 12\.\.16 of a "
                                            r"14-byte point"):
        _pc2(msg)


def test_pointcloud2_round_trip_and_colours_off() -> None:
    pytest.importorskip("rosbags")
    from deformap.cloud.io import array_to_pointcloud2, pointcloud2_colors, pointcloud2_to_cloud

    cloud = _cloud()
    msg = array_to_pointcloud2(cloud.points, colors=cloud.colors)
    got, _ = pointcloud2_to_cloud(msg, where="m")
    np.testing.assert_array_equal(got.colors, cloud.colors)  # type: ignore[arg-type]
    assert pointcloud2_to_cloud(msg, where="m", colors=False)[0].colors is None
    assert pointcloud2_colors(array_to_pointcloud2(cloud.points)) is None
