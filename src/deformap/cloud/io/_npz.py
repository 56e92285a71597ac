"""NPZ files: archives with ``points`` (n, 3) and optional ``colors`` (n, 3), never pickled."""

from __future__ import annotations

import io
import math
import tokenize
import zipfile
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from deformap._files import atomic_path
from deformap._validation import check_int
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._common import (
    check_body_size,
    check_units,
    finish_cloud,
    parse_errors,
    readable_path,
)
from deformap.cloud.io._pcd import _check_cloud_and_extras
from deformap.errors import FileFormatError

__all__ = ["MAX_NPZ_BYTES", "load_npz_arrays", "read_npz", "write_npz"]

#: The most bytes an NPZ archive's arrays may hold decompressed, checked before anything is
#: inflated (a zip bomb): 2.5 times a 1920 × 1080 frame's float64 points and colours.
MAX_NPZ_BYTES = 256 * 2**20


def _check_members(path: Path, archive: zipfile.ZipFile, max_bytes: int) -> list[zipfile.ZipInfo]:
    """The archive's ``.npy`` members, their total size checked against ``max_bytes``."""
    members = archive.infolist()
    if not members:
        raise FileFormatError(f"{path}: the NPZ archive holds no arrays")
    total = 0
    for info in members:
        if not info.filename.endswith(".npy") or info.is_dir():
            raise FileFormatError(
                f"{path}: NPZ member {info.filename!r}: expected a .npy array, got another file")
        total += info.file_size
    if total > max_bytes:
        raise FileFormatError(
            f"{path}: the NPZ archive's arrays decompress to {total} bytes; expected at most "
            f"{max_bytes} (deformap.cloud.io.MAX_NPZ_BYTES; pass max_bytes= to allow more)")
    return members


def _read_member(path: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo) -> NDArray[Any]:
    """One ``.npy`` member, its header's shape checked against its size before it is read."""
    with archive.open(info) as fh:
        try:
            version = np.lib.format.read_magic(fh)
            if version not in ((1, 0), (2, 0)):
                raise ValueError(f"format version {version[0]}.{version[1]}, expected 1.0 or 2.0")
            read_header = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                           else np.lib.format.read_array_header_2_0)  # fmt: skip
            shape, fortran, dtype = read_header(fh)
        except (ValueError, SyntaxError, tokenize.TokenError, EOFError) as exc:
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise FileFormatError(
                f"{path}: NPZ member {info.filename!r}: expected a .npy header, got a malformed "
                f"one ({detail[:120]})") from None
        if dtype.hasobject:
            raise FileFormatError(
                f"{path}: NPZ member {info.filename!r} holds Python objects (dtype {dtype}), "
                "which would need pickle; refused")
        if any(int(n) < 0 for n in shape):
            raise FileFormatError(
                f"{path}: NPZ member {info.filename!r}: expected a shape of sizes >= 0, got {shape}"
            )
        need = math.prod(int(n) for n in shape) * dtype.itemsize
        what = f"NPZ member {info.filename!r} of shape {shape} × {dtype.itemsize} bytes"
        check_body_size(path, what, need, info.file_size - fh.tell())
        data = fh.read()  # to the end, so that zipfile checks the member's CRC-32
    check_body_size(path, what, need, data, text=True)
    order: Literal["C", "F"] = "F" if fortran else "C"
    return np.frombuffer(data, dtype=dtype, count=need // max(dtype.itemsize, 1)).reshape(
        shape, order=order).copy()  # fmt: skip


def load_npz_arrays(path: str | Path, what: str, *, max_bytes: int = MAX_NPZ_BYTES
                    ) -> dict[str, NDArray[Any]]:  # fmt: skip
    """All named arrays of an NPZ archive, without pickle; a damaged file is a FileFormatError.

    The members' decompressed sizes are checked against ``max_bytes`` and each ``.npy`` header's
    shape against its member's size before anything is inflated; each member's CRC-32 is verified
    as it is read. ``what`` names the archive in messages.
    """
    p = Path(path)
    limit = check_int("max_bytes", max_bytes, minimum=1)
    with parse_errors(p, what):
        # Read into memory first, so that a corrupted archive leaves no file handle open.
        raw = p.read_bytes()
        if raw.startswith(b"\x93NUMPY"):
            raise FileFormatError(f"{p}: a single .npy array, not an NPZ archive of named arrays")
        with zipfile.ZipFile(io.BytesIO(raw)) as archive:
            members = _check_members(p, archive, limit)
            out = {info.filename[: -len(".npy")]: _read_member(p, archive, info)
                   for info in members}  # fmt: skip
        if len(out) != len(members):
            raise FileFormatError(f"{p}: the NPZ archive names an array twice")
        return out


def read_npz(path: str | Path, *, units: str = "m", drop_nan: bool = False,
             max_bytes: int = MAX_NPZ_BYTES) -> tuple[PointCloud, dict[str, NDArray[Any]]]:
    """Read an NPZ archive of ``points`` (n, 3) and optional ``colors`` (n, 3; integers in
    [0, 255] or floats in [0, 1]), as :func:`read_pcd` reads a PCD file; the extras are the other
    1-D arrays of the cloud's length. Object arrays are refused (no pickle)."""
    scale = check_units(units)
    p = readable_path(path)
    arrays = load_npz_arrays(p, "the NPZ archive", max_bytes=max_bytes)
    if "points" not in arrays:
        raise FileFormatError(f"{p}: NPZ has no array 'points' (has: {sorted(arrays)})")
    points = arrays.pop("points")
    if points.ndim != 2 or points.shape[1] != 3 or points.dtype.kind not in "iuf":
        raise FileFormatError(
            f"{p}: NPZ array 'points' must be (n, 3) numbers; got shape {points.shape} and "
            f"dtype {points.dtype}")
    colors = arrays.pop("colors", None)
    if colors is not None and (colors.shape != points.shape or colors.dtype.kind not in "iuf"):
        raise FileFormatError(
            f"{p}: NPZ array 'colors' must be {points.shape} numbers; got shape {colors.shape} "
            f"and dtype {colors.dtype}")
    extras = {k: v for k, v in arrays.items()
              if v.shape == (len(points),) and v.dtype.kind in "iufb"}  # fmt: skip
    return finish_cloud(p, points, colors, extras, scale=scale, drop_nan=drop_nan,
                        color_field="colors")  # fmt: skip


def write_npz(path: str | Path, cloud: PointCloud, *, compressed: bool = True,
              extra_fields: dict[str, Any] | None = None) -> None:
    """Write ``points``, ``colors`` (when the cloud has them) and ``extra_fields`` (per-point
    arrays) to an NPZ archive at exactly ``path``, zip-deflated when ``compressed``; atomically
    (:func:`deformap._files.atomic_path`)."""
    cloud, extras = _check_cloud_and_extras(cloud, extra_fields)
    arrays: dict[str, NDArray[Any]] = {"points": np.asarray(cloud.points), **extras}
    if cloud.colors is not None:
        arrays["colors"] = np.asarray(cloud.colors)
    save = np.savez_compressed if compressed else np.savez
    with atomic_path(path) as tmp, open(tmp, "xb") as fh:
        save(fh, **arrays)  # type: ignore[arg-type]  # numpy's stub types **kwds as allow_pickle
