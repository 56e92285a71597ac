"""``read_cloud`` and ``write_cloud``: one entry point that picks the format from the suffix."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from deformap._validation import check_path
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._npz import read_npz, write_npz
from deformap.cloud.io._pcd import read_pcd, write_pcd
from deformap.cloud.io._ply import read_ply, write_ply
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["CLOUD_FORMATS", "read_cloud", "write_cloud"]

_READERS: dict[str, Callable[..., tuple[PointCloud, dict[str, Any]]]] = {
    "pcd": read_pcd, "ply": read_ply, "npz": read_npz}
CLOUD_FORMATS = tuple(_READERS)


def _format_of(path: Path, format: str | None) -> str:
    if format is not None:
        if format not in CLOUD_FORMATS:
            raise InvalidArgumentError(f"`format` must be one of {CLOUD_FORMATS}; got {format!r}")
        return format
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in CLOUD_FORMATS:
        expected = f"expected one of {['.' + f for f in CLOUD_FORMATS]} (or pass format=)"
        other = _NOT_CLOUDS.get(suffix)
        if other is not None:
            raise FileFormatError(f"{path}: {other}, not a point cloud; {expected}")
        raise FileFormatError(f"{path}: unknown point-cloud suffix {path.suffix!r}; {expected}")
    return suffix


#: Files deformap reads that are no point cloud, by suffix: what each is, for the message.
_NOT_CLOUDS = {"yaml": "a YAML file (a session, run or scenario file?)",
               "yml": "a YAML file (a session, run or scenario file?)",
               "mcap": "a ROS 2 bag (MCAP; `deformap map` reads it)",
               "db3": "a ROS 2 bag (sqlite3; `deformap map` reads it)",
               "json": "a JSON file (a report?)", "jsonl": "a journal (JSON lines)"}


def read_cloud(path: str | Path, *, units: str = "m", drop_nan: bool = False,
               format: str | None = None) -> PointCloud:
    """Read a point cloud (metres, frame ``"world"``) from a ``.pcd``, ``.ply`` or ``.npz`` file.

    ``units`` and ``drop_nan`` are the readers' (:func:`read_pcd`, which also return the other
    per-point fields); ``format`` overrides the suffix.
    """
    p = check_path("path", path)
    cloud, _ = _READERS[_format_of(p, format)](p, units=units, drop_nan=drop_nan)
    return cloud


def write_cloud(path: str | Path, cloud: PointCloud, *, format: str | None = None,
                binary: bool = True) -> None:
    """Write a point cloud (metres) to a ``.pcd``, ``.ply`` or ``.npz`` file.

    ``binary`` picks PCD ``binary`` and PLY ``binary_little_endian`` (else ``ascii``; NPZ is
    always binary); ``format`` overrides the suffix.
    """
    p = check_path("path", path)
    fmt = _format_of(p, format)
    if fmt == "pcd":
        write_pcd(p, cloud, encoding="binary" if binary else "ascii")
    elif fmt == "ply":
        write_ply(p, cloud, format="binary_little_endian" if binary else "ascii")
    else:
        write_npz(p, cloud)
