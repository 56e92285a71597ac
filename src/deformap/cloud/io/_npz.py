"""NPZ files: archives with ``points`` (n, 3) and optional ``colors`` (n, 3), never pickled."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._common import check_units, finish_cloud, parse_errors, readable_path
from deformap.cloud.io._pcd import _check_cloud_and_extras
from deformap.errors import FileFormatError

__all__ = ["load_npz_arrays", "read_npz", "write_npz"]


def load_npz_arrays(path: str | Path, what: str) -> dict[str, NDArray[Any]]:
    """All named arrays of an NPZ archive, without pickle; a damaged file is a FileFormatError.

    ``what`` names the archive in messages (``"the NPZ archive"``).
    """
    p = Path(path)
    with parse_errors(p, what):
        # Loading from memory, so that a corrupted archive leaves no file handle open.
        loaded = np.load(io.BytesIO(p.read_bytes()), allow_pickle=False)
        if not isinstance(loaded, np.lib.npyio.NpzFile):
            raise FileFormatError(f"{p}: a single .npy array, not an NPZ archive of named arrays")
        with loaded as archive:
            return {name: archive[name] for name in archive.files}


def read_npz(
    path: str | Path, *, units: str = "m", drop_nan: bool = False
) -> tuple[PointCloud, dict[str, NDArray[Any]]]:
    """Read an NPZ archive with ``points`` and optional ``colors``; other arrays become extras.

    The archive is opened with ``allow_pickle=False``: object arrays are refused.

    Parameters
    ----------
    path : str or Path
    units : {"m", "mm"}
        Units of ``points`` (see :func:`read_pcd`).
    drop_nan : bool
        Drop points with a NaN or infinite coordinate (logged) instead of refusing the file.

    Returns
    -------
    cloud : PointCloud
    extras : dict of str to (n,) array
        Every other 1-D array of the cloud's length in the archive.
    """
    scale = check_units(units)
    p = readable_path(path)
    arrays = load_npz_arrays(p, "the NPZ archive")
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
    return finish_cloud(p, points, colors, extras, scale=scale, drop_nan=drop_nan)


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
