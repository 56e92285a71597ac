"""PCD files (ascii, binary, binary_compressed) through pypcd4.

The header is checked against the bytes that follow before pypcd4 allocates anything (a corrupted
``POINTS`` must not ask for terabytes), and what pypcd4 returns against the header (a truncated
body must not become a shorter cloud).

References
----------
PCL, "The PCD (Point Cloud Data) file format",
https://pointclouds.org/documentation/tutorials/pcd_file_format.html
"""

from __future__ import annotations

import io
import struct
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from deformap._files import atomic_path
from deformap._validation import check_instance
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._common import (
    check_body_size,
    check_text_rows,
    check_units,
    finish_cloud,
    pack_rgb,
    parse_errors,
    readable_path,
    unpack_rgb,
)
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["PCD_ENCODINGS", "read_pcd", "write_pcd"]

PCD_ENCODINGS = ("ascii", "binary", "binary_compressed")

_PYPCD4_PADDING_PREFIX = "#$%&~~"  # how pypcd4 renames the "_" padding fields


def _split_header(data: bytes) -> tuple[list[str], int]:
    # The same loop as pypcd4.PointCloud.from_fileobj, so that both agree where the body starts.
    buf = io.BytesIO(data)
    lines: list[str] = []
    for raw in buf:
        line = raw.decode("utf-8").strip()
        if line.startswith("#") or not line:
            continue
        lines.append(line)
        if line.startswith("DATA") or len(lines) >= 10:
            break
    return lines, buf.tell()


def _check_header_against_body(path: Path, meta: Any, body: bytes) -> None:
    """Check every size the header declares against the body, before pypcd4 allocates
    ``POINTS`` records of ``SIZE`` × ``COUNT`` bytes."""
    n_fields = len(meta.fields)
    if not (len(meta.size) == len(meta.type) == len(meta.count) == n_fields):
        raise FileFormatError(
            f"{path}: header lists {n_fields} FIELDS but {len(meta.size)} SIZE, "
            f"{len(meta.type)} TYPE and {len(meta.count)} COUNT entries")
    if meta.points != meta.width * meta.height:
        raise FileFormatError(
            f"{path}: header says POINTS {meta.points} but WIDTH×HEIGHT is "
            f"{meta.width}×{meta.height}")
    if meta.points == 0:
        raise FileFormatError(f"{path}: header says POINTS 0: the cloud is empty")
    bad_size = [s for s in meta.size if s not in (1, 2, 4, 8)]
    if bad_size:
        raise FileFormatError(f"{path}: header SIZE must be 1, 2, 4 or 8; got {bad_size[0]}")
    values = sum(meta.count)
    itemsize = sum(s * c for s, c in zip(meta.size, meta.count, strict=True))
    need = meta.points * itemsize
    encoding = meta.data.value
    what = f"{encoding} body of POINTS {meta.points} × {itemsize} bytes"
    if encoding == "ascii":
        # Each value takes at least one character and one separator.
        check_body_size(path, f"ascii body of POINTS {meta.points} × {values} values",
                        meta.points * values, body, exact=False, text=True)  # fmt: skip
        check_text_rows(path, "the ascii body", body, values)
        return
    if encoding == "binary":
        check_body_size(path, what, need, body)
        return
    if len(body) < 8:
        raise FileFormatError(
            f"{path}: {encoding} body: expected 8 bytes of sizes, the file holds {len(body)}")
    compressed, uncompressed = struct.unpack("<II", body[:8])
    # An LZF back-reference of 3 bytes expands to at most 264: a ratio above 88 is corrupt,
    # and checking it first keeps a forged size from allocating gigabytes.
    if uncompressed != need or uncompressed > 100 * compressed:
        raise FileFormatError(
            f"{path}: {what}: expected {need} uncompressed bytes, the size word says "
            f"{uncompressed} (from {compressed} compressed)")
    check_body_size(path, f"{encoding} body of {compressed} compressed bytes + 8 size bytes",
                    compressed + 8, body)  # fmt: skip


_PACKED, _SEPARATE = ("rgb", "rgba"), ("r", "g", "b")  # colour fields, in the order looked for


def _pcd_colors(path: Path, pc_data: NDArray[Any], meta: Any, body: bytes
                ) -> tuple[NDArray[Any] | None, str, tuple[str, ...]]:  # fmt: skip
    """The file's colours (not yet checked), the name of their field(s) and the fields taken.

    ``rgb`` (TYPE F) holds the bits of ``0x00RRGGBB`` in a float, PCL's convention; as TYPE U or
    I, or ``rgba`` (``0xAARRGGBB``), the word itself. PCL's ascii writer prints a float rgb's
    bits as an unsigned integer, so integer-valued floats in an ascii file are the packed word
    (such bits as a float are < 1e-38), read again from ``body`` as float64 (float32 would round
    a word with an alpha byte). Separate ``r``, ``g``, ``b`` are 8-bit integers or floats in [0, 1].
    """
    names = pc_data.dtype.names or ()
    field = next((c for c in _PACKED if c in names), None)
    if field is None:
        if all(c in names for c in _SEPARATE):
            return np.column_stack([pc_data[c] for c in _SEPARATE]), "r/g/b", _SEPARATE
        return None, "", ()
    values = np.asarray(pc_data[field])
    if values.ndim != 1 or values.dtype.itemsize != 4:
        raise FileFormatError(
            f"{path}: colour field {field!r} must be one 4-byte word per point (packed "
            f"0x00RRGGBB); got {values.dtype.itemsize}-byte values, count "
            f"{1 if values.ndim == 1 else values.shape[1]}")
    if values.dtype.kind == "f" and meta.data.value == "ascii":
        column = sum(meta.count[: meta.fields.index(field)])
        values = np.loadtxt(io.BytesIO(body), dtype=np.float64, usecols=column, ndmin=1,
                            comments=None)  # fmt: skip
        if not np.isfinite(values).all():
            row = int(np.argmax(~np.isfinite(values)))
            raise FileFormatError(
                f"{path}: colour field {field!r} of point {row} is {values[row]}: an ascii file "
                "holds the packed word as an integer")
        if np.all(values == np.round(values)):
            if values.min() < 0 or values.max() > 0xFFFFFFFF:
                raise FileFormatError(
                    f"{path}: colour field {field!r} holds {values.min():.0f} to "
                    f"{values.max():.0f}; a packed word lies in [0, 2^32)")
            return unpack_rgb(values.astype(np.uint32)), field, (field,)
    return unpack_rgb(values), field, (field,)


def read_pcd(path: str | Path, *, units: str = "m", drop_nan: bool = False
             ) -> tuple[PointCloud, dict[str, NDArray[Any]]]:  # fmt: skip
    """Read a PCD file (ascii, binary or binary_compressed): the cloud, and the other per-point
    fields as extras in the file's dtype (COUNT > 1 as pypcd4's ``name__0000``, ...).

    ``units`` are the coordinates' (``"m"`` or ``"mm"``; metres that look like millimetres are
    refused, ``MM_EXTENT_THRESHOLD``); ``drop_nan`` drops (and logs) points with a NaN or infinite
    coordinate instead of refusing the file. Colours come from a packed ``rgb`` or ``rgba`` field or
    from ``r``, ``g``, ``b``; a NaN or out-of-range colour is refused, naming the field.
    """
    from pypcd4 import PointCloud as PcdCloud
    from pypcd4.pypcd4 import MetaData

    scale = check_units(units)
    p = readable_path(path)
    with parse_errors(p, "the PCD file"):
        data = p.read_bytes()
        lines, offset = _split_header(data)
        if not lines or not lines[-1].upper().startswith("DATA"):
            raise FileFormatError(f"{p}: no DATA line in the PCD header")
        meta = MetaData.parse_header(lines)
        _check_header_against_body(p, meta, data[offset:])
        pc_data = np.atleast_1d(PcdCloud.from_fileobj(cast(Any, io.BytesIO(data))).pc_data)
    if pc_data.shape[0] != meta.points:
        raise FileFormatError(
            f"{p}: header says POINTS {meta.points} but the body holds {pc_data.shape[0]}")
    names = pc_data.dtype.names or ()
    missing = [axis for axis in "xyz" if axis not in names]
    if missing:
        raise FileFormatError(f"{p}: PCD has no field {missing[0]!r} (fields: {list(names)})")
    xyz = np.column_stack([pc_data[a] for a in "xyz"])
    with parse_errors(p, "the PCD file's colours"):
        colors, color_field, taken = _pcd_colors(p, pc_data, meta, data[offset:])
    extras = {
        name: np.array(pc_data[name])
        for name in names
        if name not in ("x", "y", "z", *taken) and not name.startswith(_PYPCD4_PADDING_PREFIX)}
    return finish_cloud(p, xyz, colors, extras, scale=scale, drop_nan=drop_nan,
                        color_field=color_field)  # fmt: skip


def write_pcd(path: str | Path, cloud: PointCloud, *, encoding: str = "binary",
              dtype: str = "float64", extra_fields: dict[str, Any] | None = None) -> None:
    """Write a cloud (metres) to a PCD file of ``encoding`` in ``PCD_ENCODINGS``.

    Colours go into a packed ``rgb`` field: float bits in binary files (PCL's convention), an
    unsigned integer in ascii. ``dtype`` (``"float64"`` or ``"float32"``) stores x, y, z; float64
    by default as it round-trips exactly in binary files. ``extra_fields`` are more per-point
    fields, 1-D numeric arrays of the cloud's length. Written atomically
    (:func:`deformap._files.atomic_path`).
    """
    from pypcd4 import Encoding
    from pypcd4 import PointCloud as PcdCloud

    if encoding not in PCD_ENCODINGS:
        raise InvalidArgumentError(f"`encoding` must be one of {PCD_ENCODINGS}; got {encoding!r}")
    if dtype not in ("float64", "float32"):
        raise InvalidArgumentError(f"`dtype` must be 'float64' or 'float32'; got {dtype!r}")
    cloud, extras = _check_cloud_and_extras(cloud, extra_fields)
    fields = {a: cloud.points[:, i].astype(dtype) for i, a in enumerate("xyz")}
    if cloud.colors is not None:
        packed = pack_rgb(cloud.colors)
        # pypcd4 prints floats with "%.10f", which would turn packed-float bits into 0 in ascii.
        fields["rgb"] = packed if encoding == "ascii" else packed.view(np.float32)
    fields.update(extras)  # their names are none of the above (_check_cloud_and_extras)
    columns = list(fields.values())
    pc = PcdCloud.from_points(columns, tuple(fields), tuple(c.dtype for c in columns))
    with atomic_path(path) as tmp, open(tmp, "xb") as fh:
        pc.save(fh, encoding=Encoding(encoding))


def _check_cloud_and_extras(cloud: Any, extra_fields: dict[str, Any] | None
                            ) -> tuple[PointCloud, dict[str, NDArray[Any]]]:  # fmt: skip
    """The writers' checks: a non-empty cloud and numeric 1-D extra fields."""
    check_instance("cloud", cloud, PointCloud)
    if len(cloud) == 0:
        raise InvalidArgumentError("`cloud` must hold at least one point; got an empty cloud")
    extras: dict[str, NDArray[Any]] = {}
    reserved = {"x", "y", "z", "rgb", "rgba", "red", "green", "blue"}
    for name, values in (extra_fields or {}).items():
        arr = np.asarray(values)
        if not isinstance(name, str) or not name.isidentifier() or name in reserved:
            raise InvalidArgumentError(
                f"`extra_fields` keys must be identifiers other than {sorted(reserved)}; "
                f"got {name!r}")
        if arr.shape != (len(cloud),) or arr.dtype.kind not in "iuf" or arr.dtype == np.float16:
            raise InvalidArgumentError(
                f"`extra_fields[{name!r}]` must be a ({len(cloud)},) numeric array; got shape "
                f"{arr.shape} and dtype {arr.dtype}")
        extras[name] = arr
    return cloud, extras
