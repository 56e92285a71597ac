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


#: The most bytes the arrays of one NPZ archive may hold once decompressed (256 MiB). The largest
#: cloud deformap reads is a depth camera's frame: 1920 × 1080 points as float64 x, y, z and
#: float64 colours take 99.5 MB, so 256 MiB leaves a factor 2.5; an archive that decompresses
#: to more is refused before anything is inflated (a zip bomb), unless ``max_bytes`` allows it.
MAX_NPZ_BYTES = 256 * 2**20


def _check_members(path: Path, archive: zipfile.ZipFile, max_bytes: int) -> list[zipfile.ZipInfo]:
    """The archive's ``.npy`` members, their sizes checked against the limit before any read."""
    members = archive.infolist()
    if not members:
        raise FileFormatError(f"{path}: the NPZ archive holds no arrays")
    total = 0
    for info in members:
        if not info.filename.endswith(".npy") or info.is_dir():
            raise FileFormatError(
                f"{path}: NPZ member {info.filename!r}: expected a .npy array, got another file"
            )
        total += info.file_size
    if total > max_bytes:
        raise FileFormatError(
            f"{path}: the NPZ archive's arrays decompress to {total} bytes; expected at most "
            f"{max_bytes} (deformap.cloud.io.MAX_NPZ_BYTES; pass max_bytes= to allow more)"
        )
    return members


def _read_member(path: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo) -> NDArray[Any]:
    """One ``.npy`` member: its header's shape checked against the member's size, then read."""
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
                f"one ({detail[:120]})"
            ) from None
        if dtype.hasobject:
            raise FileFormatError(
                f"{path}: NPZ member {info.filename!r} holds Python objects (dtype {dtype}), "
                "which would need pickle; refused"
            )
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


def load_npz_arrays(
    path: str | Path, what: str, *, max_bytes: int = MAX_NPZ_BYTES
) -> dict[str, NDArray[Any]]:
    """All named arrays of an NPZ archive, without pickle; a damaged file is a FileFormatError.

    Sizes are checked before anything is inflated: the members' decompressed sizes (from the
    zip directory) against ``max_bytes``, and each ``.npy`` header's shape against its member's
    size. The zip's CRC-32 of each member is verified as it is read.

    Parameters
    ----------
    path : str or Path
    what : str
        Names the archive in messages (``"the NPZ archive"``).
    max_bytes : int
        The most bytes the arrays may hold together (:data:`MAX_NPZ_BYTES`).
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


def read_npz(
    path: str | Path, *, units: str = "m", drop_nan: bool = False, max_bytes: int = MAX_NPZ_BYTES
) -> tuple[PointCloud, dict[str, NDArray[Any]]]:
    """Read an NPZ archive with ``points`` and optional ``colors``; other arrays become extras.

    ``colors`` is (n, 3): integers in [0, 255] or floats in [0, 1]; NaN or out-of-range values
    are refused (a point dropped for a NaN coordinate drops its colour too).

    The archive is opened with ``allow_pickle=False``: object arrays are refused.

    Parameters
    ----------
    path : str or Path
    units : {"m", "mm"}
        Units of ``points`` (see :func:`read_pcd`).
    drop_nan : bool
        Drop points with a NaN or infinite coordinate (logged) instead of refusing the file.
    max_bytes : int
        The most bytes the archive's arrays may hold once decompressed (:data:`MAX_NPZ_BYTES`).

    Returns
    -------
    cloud : PointCloud
    extras : dict of str to (n,) array
        Every other 1-D array of the cloud's length in the archive.
    """
    scale = check_units(units)
    p = readable_path(path)
    arrays = load_npz_arrays(p, "the NPZ archive", max_bytes=max_bytes)
    if "points" not in arrays:
        raise FileFormatError(f"{p}: NPZ has no array 'points' (has: {sorted(arrays)})")
    points = arrays.pop("points")
    if points.ndim != 2 or points.shape[1] != 3 or points.dtype.kind not in "iuf":
        raise FileFormatError(
            f"{p}: NPZ array 'points' must be (n, 3) numbers; got shape {points.shape} and "
            f"dtype {points.dtype}"
        )
    colors = arrays.pop("colors", None)
    if colors is not None and (colors.shape != points.shape or colors.dtype.kind not in "iuf"):
        raise FileFormatError(
            f"{p}: NPZ array 'colors' must be {points.shape} numbers; got shape {colors.shape} "
            f"and dtype {colors.dtype}"
        )
    extras = {
        k: v for k, v in arrays.items() if v.shape == (len(points),) and v.dtype.kind in "iufb"
    }
    return finish_cloud(p, points, colors, extras, scale=scale, drop_nan=drop_nan,
                        color_field="colors")  # fmt: skip


def write_npz(
    path: str | Path,
    cloud: PointCloud,
    *,
    compressed: bool = True,
    extra_fields: dict[str, Any] | None = None,
) -> None:
    """Write ``points`` (and ``colors`` when the cloud has them) to an NPZ archive.

    Parameters
    ----------
    path : str or Path
        Where to write, exactly as named (no ``.npz`` is appended).
    cloud : PointCloud
    compressed : bool
        Use zip deflate (``np.savez_compressed``).
    extra_fields : dict of str to (n,) array, optional
        More per-point arrays, stored under their names.
    """
    cloud, extras = _check_cloud_and_extras(cloud, extra_fields)
    arrays: dict[str, NDArray[Any]] = {"points": np.asarray(cloud.points), **extras}
    if cloud.colors is not None:
        arrays["colors"] = np.asarray(cloud.colors)
    save = np.savez_compressed if compressed else np.savez
    with open(path, "wb") as fh:
        save(fh, **arrays)  # type: ignore[arg-type]  # numpy's stub types **kwds as allow_pickle
