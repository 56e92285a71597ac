"""``read_cloud`` and ``write_cloud``: one entry point that picks the format from the suffix."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._npz import read_npz, write_npz
from deformap.cloud.io._pcd import read_pcd, write_pcd
from deformap.cloud.io._ply import read_ply, write_ply
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["CLOUD_FORMATS", "read_cloud", "write_cloud"]

_READERS: dict[str, Callable[..., tuple[PointCloud, dict[str, Any]]]] = {
    "pcd": read_pcd,
    "ply": read_ply,
    "npz": read_npz,
}
CLOUD_FORMATS = tuple(_READERS)


def _format_of(path: Path, format: str | None) -> str:
    if format is not None:
        if format not in CLOUD_FORMATS:
            raise InvalidArgumentError(f"`format` must be one of {CLOUD_FORMATS}; got {format!r}")
        return format
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in CLOUD_FORMATS:
        raise FileFormatError(
            f"{path}: unknown point-cloud suffix {path.suffix!r}; expected one of "
            f"{['.' + f for f in CLOUD_FORMATS]} (or pass format=)"
        )
    return suffix


def read_cloud(
    path: str | Path, *, units: str = "m", drop_nan: bool = False, format: str | None = None
) -> PointCloud:
    """Read a point cloud from a ``.pcd``, ``.ply`` or ``.npz`` file.

    Parameters
    ----------
    path : str or Path
    units : {"m", "mm"}
        Units of the file; a cloud that looks like millimetres is refused unless ``"mm"``.
    drop_nan : bool
        Drop (and log) points with a NaN or infinite coordinate instead of refusing the file.
    format : {"pcd", "ply", "npz"}, optional
        Overrides the suffix.

    Returns
    -------
    PointCloud
        Points in metres, frame ``"world"``. Use :func:`read_pcd`, :func:`read_ply` or
        :func:`read_npz` to get the file's other per-point fields too.
    """
    if not isinstance(path, (str, Path)):
        raise InvalidArgumentError(
            f"`path` must be a str or pathlib.Path; got {type(path).__name__}"
        )
    p = Path(path)
    cloud, _ = _READERS[_format_of(p, format)](p, units=units, drop_nan=drop_nan)
    return cloud


def write_cloud(
    path: str | Path, cloud: PointCloud, *, format: str | None = None, binary: bool = True
) -> None:
    """Write a point cloud (metres) to a ``.pcd``, ``.ply`` or ``.npz`` file.

    Parameters
    ----------
    path : str or Path
    cloud : PointCloud
    format : {"pcd", "ply", "npz"}, optional
        Overrides the suffix.
    binary : bool
        PCD: ``binary`` (else ``ascii``; use :func:`write_pcd` for ``binary_compressed``);
        PLY: ``binary_little_endian`` (else ``ascii``); NPZ is always binary.
    """
    if not isinstance(path, (str, Path)):
        raise InvalidArgumentError(
            f"`path` must be a str or pathlib.Path; got {type(path).__name__}"
        )
    p = Path(path)
    fmt = _format_of(p, format)
    if fmt == "pcd":
        write_pcd(p, cloud, encoding="binary" if binary else "ascii")
    elif fmt == "ply":
        write_ply(p, cloud, format="binary_little_endian" if binary else "ascii")
    else:
        write_npz(p, cloud)
