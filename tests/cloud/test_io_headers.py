"""Readers check every size a header declares against the bytes present, before allocating
(issue 14): a forged count is refused at once, a lowered one does not drop points silently, an ascii
body under a binary header is not read as floats, and an NPZ is bounded before it is inflated."""

from __future__ import annotations

import io
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.cloud.io import (
    MAX_NPZ_BYTES,
    load_npz_arrays,
    read_npz,
    read_pcd,
    read_ply,
    write_npz,
    write_pcd,
    write_ply,
)
from deformap.errors import FileFormatError


def _cloud(n: int = 50) -> PointCloud:
    return PointCloud(np.random.default_rng(3).uniform(0.0, 0.5, (n, 3)))


def _npy(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, array, allow_pickle=False)
    return buf.getvalue()


def _zip(path: Path, members: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


@pytest.mark.parametrize("new", [b"40", b"49"])
def test_binary_pcd_with_a_lowered_point_count_is_refused(tmp_path: Path, new: bytes) -> None:
    path = tmp_path / "low.pcd"
    write_pcd(path, _cloud(), encoding="binary")
    data = path.read_bytes()
    path.write_bytes(data.replace(b"WIDTH 50", b"WIDTH " + new).replace(b"POINTS 50",
                                                                       b"POINTS " + new))
    with pytest.raises(FileFormatError, match=rf"low\.pcd: binary body of POINTS {new.decode()} "
                                              r".*more\); the header's count is too low"):
        read_pcd(path)


def test_compressed_pcd_with_surplus_bytes_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "c.pcd"
    write_pcd(path, PointCloud(np.tile([0.1, 0.2, 0.3], (500, 1))), encoding="binary_compressed")
    assert b"DATA binary_compressed" in path.read_bytes()
    read_pcd(path)  # intact: reads
    path.write_bytes(path.read_bytes() + b"\x01\x02\x03\x04")
    with pytest.raises(FileFormatError, match=r"c\.pcd: binary_compressed body .*\(4 more\)"):
        read_pcd(path)


def test_a_trailing_newline_after_binary_data_is_tolerated(tmp_path: Path) -> None:
    pcd, ply = tmp_path / "t.pcd", tmp_path / "t.ply"
    write_pcd(pcd, _cloud(), encoding="binary")
    write_ply(ply, _cloud())
    for path, read in ((pcd, read_pcd), (ply, read_ply)):
        path.write_bytes(path.read_bytes() + b"\n")
        cloud, _ = read(path)
        np.testing.assert_array_equal(cloud.points, _cloud().points)


def test_pcd_count_of_a_billion_is_refused_at_once(tmp_path: Path) -> None:
    path = tmp_path / "count.pcd"
    write_pcd(path, _cloud(), encoding="binary")
    path.write_bytes(path.read_bytes().replace(b"COUNT 1 1 1", b"COUNT 1000000000 1 1"))
    start = time.perf_counter()
    with pytest.raises(FileFormatError, match=r"count\.pcd: binary body of POINTS 50 × "
                                              r"8000000016 bytes: expected 400000000800 bytes"):
        read_pcd(path)
    assert time.perf_counter() - start < 1.0  # nothing allocated for the declared size


def test_pcd_with_zero_points_or_an_odd_size_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "z.pcd"
    write_pcd(path, _cloud(), encoding="binary")
    good = path.read_bytes()
    path.write_bytes(good.replace(b"WIDTH 50", b"WIDTH 0").replace(b"POINTS 50", b"POINTS 0")
                     .replace(b"COUNT 1 1 1", b"COUNT 1000000000 1 1"))  # fmt: skip
    with pytest.raises(FileFormatError, match=r"z\.pcd: header says POINTS 0"):
        read_pcd(path)
    path.write_bytes(good.replace(b"SIZE 8 8 8", b"SIZE 8 8 3"))
    with pytest.raises(FileFormatError, match=r"z\.pcd: header SIZE must be 1, 2, 4 or 8; got 3"):
        read_pcd(path)


def test_ascii_body_under_a_binary_header_is_refused(tmp_path: Path) -> None:
    pcd, ply = tmp_path / "a.pcd", tmp_path / "a.ply"
    write_pcd(pcd, _cloud(), encoding="ascii")
    pcd.write_bytes(pcd.read_bytes().replace(b"DATA ascii", b"DATA binary"))
    with pytest.raises(FileFormatError, match=r"a\.pcd: .*bytes of text \(an ascii body under"):
        read_pcd(pcd)
    write_ply(ply, _cloud(), format="ascii")
    ply.write_bytes(ply.read_bytes().replace(b"format ascii", b"format binary_little_endian"))
    with pytest.raises(FileFormatError, match=r"a\.ply: .*bytes of text \(an ascii body under"):
        read_ply(ply)


def _ply_with_faces(path: Path, n_vertices_declared: int, faces: list[list[int]]) -> Path:
    verts = _cloud(4).points.astype("<f4")
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {n_vertices_declared}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    body = b"".join(np.uint8(len(f)).tobytes() + np.asarray(f, "<i4").tobytes() for f in faces)
    path.write_bytes(header.encode() + verts.tobytes() + body)
    return path


@pytest.mark.parametrize("faces", [[[0, 1, 2], [0, 2, 3]], [[0, 1, 2], [0, 1, 2, 3]]])
def test_binary_ply_with_faces_after_the_vertices(tmp_path: Path, faces: list[list[int]]) -> None:
    """Uniform (triangles) and mixed list lengths are both walked to the exact end."""
    path = _ply_with_faces(tmp_path / "f.ply", 4, faces)
    cloud, _ = read_ply(path)
    assert len(cloud) == 4
    # The surplus vertex is then walked as faces: a float byte read as a list length.
    _ply_with_faces(path, 3, faces)
    with pytest.raises(FileFormatError, match=r"f\.ply: binary vertex data of 3 vertices .* and "
                                              r"the elements after them: expected .* count is"):
        read_ply(path)
    _ply_with_faces(path, 4, faces)
    path.write_bytes(path.read_bytes()[:-3])
    with pytest.raises(FileFormatError, match=r"f\.ply: .*the file is truncated"):
        read_ply(path)


def test_binary_ply_with_a_lowered_vertex_count_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "v.ply"
    write_ply(path, _cloud())
    path.write_bytes(path.read_bytes().replace(b"element vertex 50", b"element vertex 40"))
    with pytest.raises(FileFormatError, match=r"v\.ply: binary vertex data of 40 vertices × 24 "
                                              r"bytes: expected 960 bytes, the file holds 1200"):
        read_ply(path)


def test_npz_member_with_a_malformed_header_is_a_clean_error(tmp_path: Path) -> None:
    good = _npy(np.zeros((5, 3)))
    # The dict's brace never closes: numpy's tokenizer raises tokenize.TokenError.
    bad = good.replace(b"(5, 3), }", b"(5, 3),  ")
    assert bad != good
    path = _zip(tmp_path / "h.npz", {"points.npy": bad})
    with pytest.raises(FileFormatError, match=r"h\.npz: NPZ member 'points\.npy': expected a "
                                              r"\.npy header, got a malformed one"):
        read_npz(path)


def test_npz_member_whose_shape_disagrees_with_its_size_is_refused(tmp_path: Path) -> None:
    good = _npy(np.zeros((5, 3)))
    path = _zip(tmp_path / "s.npz", {"points.npy": good.replace(b"(5, 3)", b"(9, 3)")})
    with pytest.raises(FileFormatError, match=r"s\.npz: NPZ member 'points\.npy' of shape "
                                              r"\(9, 3\) × 8 bytes: expected 216 bytes, the file "
                                              r"holds 120; the file is truncated"):
        read_npz(path)
    path = _zip(tmp_path / "s.npz", {"points.npy": good.replace(b"(5, 3)", b"(4, 3)")})
    with pytest.raises(FileFormatError, match=r"expected 96 bytes, the file holds 120 \(24 more"):
        read_npz(path)


def test_npz_is_bounded_before_it_is_inflated(tmp_path: Path) -> None:
    # 8 MB of zeros deflate to a few kB: refused from the zip directory under a 1 MB limit.
    path = _zip(tmp_path / "bomb.npz", {"points.npy": _npy(np.zeros((350_000, 3)))})
    assert path.stat().st_size < 50_000
    with pytest.raises(FileFormatError, match=r"bomb\.npz: the NPZ archive's arrays decompress "
                                              r"to 8400128 bytes; expected at most 1000000"):
        load_npz_arrays(path, "the NPZ archive", max_bytes=1_000_000)
    assert len(read_npz(path, units="m")[0]) == 350_000  # within the default limit
    assert MAX_NPZ_BYTES == 256 * 2**20


def test_npz_with_a_foreign_member_or_a_bare_npy_is_refused(tmp_path: Path) -> None:
    write_npz(tmp_path / "ok.npz", _cloud())
    path = _zip(tmp_path / "x.npz", {"points.npy": _npy(_cloud().points), "notes.txt": b"hi"})
    with pytest.raises(FileFormatError, match=r"x\.npz: NPZ member 'notes\.txt': expected a "
                                              r"\.npy array"):
        read_npz(path)
    bare = tmp_path / "bare.npz"
    bare.write_bytes(_npy(_cloud().points))
    with pytest.raises(FileFormatError, match=r"bare\.npz: a single \.npy array"):
        read_npz(bare)


def test_npz_with_a_flipped_data_byte_fails_its_crc(tmp_path: Path) -> None:
    path = tmp_path / "crc.npz"
    write_npz(path, _cloud(), compressed=False)
    data = bytearray(path.read_bytes())
    data[data.index(b"NUMPY") + 200] ^= 0x10  # inside the stored array's floats
    path.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match=r"crc\.npz: could not read the NPZ archive: "
                                              r"BadZipFile: Bad CRC-32"):
        read_npz(path)
