"""PLY files (ascii, binary_little_endian, binary_big_endian), read and written with numpy.

The ``vertex`` element must carry ``x``, ``y``, ``z``; ``red``, ``green``, ``blue`` are the colours
and every other scalar vertex property an extra field. Other elements are skipped when they follow
the vertices, or, in binary files, precede them without list properties. In a binary file every
byte after the header must belong to a declared element, so a lowered vertex count is refused.

References
----------
G. Turk, "The PLY polygon file format", 1994, http://paulbourke.net/dataformats/ply/
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._files import atomic_path
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._common import (
    check_body_size,
    check_text_rows,
    check_units,
    finish_cloud,
    parse_errors,
    readable_path,
)
from deformap.cloud.io._pcd import _check_cloud_and_extras
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["PLY_FORMATS", "read_ply", "write_ply"]

PLY_FORMATS = ("ascii", "binary_little_endian", "binary_big_endian")

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
              "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
              "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}  # fmt: skip
_NUMPY_TO_PLY = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int",
                 "u4": "uint", "f4": "float", "f8": "double"}  # fmt: skip
_COLOR_NAMES = ("red", "green", "blue")
_MAX_HEADER_BYTES = 1 << 16


@dataclass
class _Element:
    name: str
    count: int
    props: list[tuple[str, str]] = field(default_factory=list)  # (name, numpy type code)
    has_list: bool = False
    # Every property in order: (numpy code of a list's count, or "", numpy code of the values).
    layout: list[tuple[str, str]] = field(default_factory=list)


def _parse_header(path: Path, data: bytes) -> tuple[str, list[_Element], int]:
    end = data.find(b"end_header", 0, _MAX_HEADER_BYTES)
    if not data.startswith(b"ply") or end < 0:
        raise FileFormatError(f"{path}: not a PLY file (no 'ply' magic or no 'end_header')")
    newline = data.find(b"\n", end)
    body_start = len(data) if newline < 0 else newline + 1
    fmt, elements = "", []
    for number, raw in enumerate(data[:end].decode("ascii").splitlines()[1:], start=2):
        words = raw.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) == 3 and words[1] in PLY_FORMATS:
            fmt = words[1]
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append(_Element(words[1], int(words[2])))
        elif (words[0] == "property" and elements and len(words) == 5 and words[1] == "list"
              and words[2] in _PLY_TYPES and words[3] in _PLY_TYPES
              and _PLY_TYPES[words[2]][0] in "iu"):  # fmt: skip
            elements[-1].has_list = True
            elements[-1].layout.append((_PLY_TYPES[words[2]], _PLY_TYPES[words[3]]))
        elif words[0] == "property" and elements and len(words) == 3 and words[1] in _PLY_TYPES:
            elements[-1].props.append((words[2], _PLY_TYPES[words[1]]))
            elements[-1].layout.append(("", _PLY_TYPES[words[1]]))
        else:
            raise FileFormatError(f"{path}: PLY header line {number} not understood: {raw!r}")
    if not fmt:
        raise FileFormatError(f"{path}: PLY header has no valid 'format' line")
    return fmt, elements, body_start


def _vertex_dtype(path: Path, vertex: _Element, fmt: str) -> np.dtype[Any]:
    if vertex.has_list:
        raise FileFormatError(f"{path}: PLY 'vertex' element has a list property (not supported)")
    names = [name for name, _ in vertex.props]
    if len(set(names)) != len(names):
        raise FileFormatError(f"{path}: PLY 'vertex' element repeats a property name: {names}")
    order = ">" if fmt == "binary_big_endian" else "<"
    return np.dtype([(name, order + code) for name, code in vertex.props])


def _read_vertices(path: Path, data: bytes) -> NDArray[Any]:
    fmt, elements, body_start = _parse_header(path, data)
    index = next((i for i, e in enumerate(elements) if e.name == "vertex"), None)
    if index is None:
        raise FileFormatError(f"{path}: PLY has no 'vertex' element")
    vertex = elements[index]
    dtype = _vertex_dtype(path, vertex, fmt)
    if fmt == "ascii":
        # One element per line; blank lines separate nothing, and would shift every row after them.
        lines = [line for line in data[body_start:].decode("ascii").splitlines() if line.strip()]
        total = sum(e.count for e in elements)
        if len(lines) > total:
            raise FileFormatError(
                f"{path}: PLY header declares {total} element rows, the ascii body holds "
                f"{len(lines)}; the counts are wrong or the file is corrupted")
        skip = sum(e.count for e in elements[:index])
        rows = lines[skip : skip + vertex.count]
        if len(rows) < vertex.count:
            raise FileFormatError(
                f"{path}: PLY header says {vertex.count} vertices, the file holds {len(rows)}")
        if vertex.count == 0:
            return np.empty(0, dtype=dtype)
        check_text_rows(path, "the ascii body", data[body_start:], None)
        width, last = len(dtype.names or ()), len(rows[-1].split())
        if last != width:  # a row short inside the body numpy refuses itself
            raise FileFormatError(
                f"{path}: PLY vertex {vertex.count - 1} (the last) holds {last} values where the "
                f"header declares {width} properties: the file was cut or the row damaged")
        table = np.loadtxt(io.StringIO("\n".join(rows)), dtype=np.float64, ndmin=2, comments=None)
        if table.shape[1] != len(dtype.names or ()):
            raise FileFormatError(
                f"{path}: PLY vertex rows have {table.shape[1]} values, the header declares "
                f"{len(dtype.names or ())} properties")
        return _fill_ascii(path, table, dtype)
    offset = body_start
    for element in elements[:index]:
        if element.has_list:
            raise FileFormatError(
                f"{path}: PLY element {element.name!r} before the vertices has a list property; "
                "cannot skip it in a binary file")
        offset += element.count * _vertex_dtype(path, element, fmt).itemsize
    # Every byte must belong to an element: a lowered vertex count must not drop points silently.
    need = vertex.count * dtype.itemsize
    after = offset + need
    for element in elements[index + 1 :]:
        after = _skip_binary_element(path, data, after, element, fmt)
    what = (f"binary vertex data of {vertex.count} vertices × {dtype.itemsize} bytes"
            + (" and the elements after them" if index + 1 < len(elements) else ""))  # fmt: skip
    check_body_size(path, what, after - offset, memoryview(data)[offset:])
    return np.frombuffer(data, dtype=dtype, count=vertex.count, offset=offset).copy()


def _skip_binary_element(path: Path, data: bytes, offset: int, element: _Element, fmt: str) -> int:
    """Where the binary rows of ``element`` that start at ``offset`` end: fixed-size rows in one
    step, rows with lists one by one; a walk past the end of the data stops there (truncated)."""
    order = ">" if fmt == "binary_big_endian" else "<"
    if not element.has_list:
        return offset + element.count * _vertex_dtype(path, element, fmt).itemsize
    end = len(data)
    if element.count == 0 or offset >= end:
        return offset + element.count  # a row takes at least a byte: too short, or empty
    at = offset
    for _ in range(element.count):
        if at >= end:
            return at + 1  # past the end: the caller reports the shortfall
        for count_code, code in element.layout:
            if count_code and at + int(count_code[1]) <= end:
                n = int(np.frombuffer(data, order + count_code, 1, at)[0])
                if n < 0:
                    raise FileFormatError(f"{path}: PLY element {element.name!r} has a list "
                                          f"of negative length {n} at byte {at}")  # fmt: skip
                at += int(count_code[1]) + n * int(code[1])
            else:
                at += int(count_code[1]) if count_code else int(code[1])
    return at


def _fill_ascii(path: Path, table: NDArray[np.float64], dtype: np.dtype[Any]) -> NDArray[Any]:
    """Store ascii values in their declared types; refuse a value the type cannot hold."""
    out = np.empty(table.shape[0], dtype=dtype)
    for i, name in enumerate(dtype.names or ()):
        column = table[:, i]
        with np.errstate(over="ignore", invalid="ignore"):
            out[name] = column
            stored = out[name].astype(np.float64)
        if dtype[name].kind == "f":
            bad = np.isfinite(column) & ~np.isfinite(stored)  # overflow to inf
        else:
            bad = stored != column  # out of range, fractional, or NaN
        if np.any(bad):
            row = int(np.argmax(bad))
            kind = _NUMPY_TO_PLY[dtype[name].str[1:]]
            raise FileFormatError(
                f"{path}: PLY vertex property {name!r} is declared {kind}, but vertex {row} "
                f"holds {float(column[row]):g}, which {kind} cannot hold")
    return out


def read_ply(path: str | Path, *, units: str = "m", drop_nan: bool = False
             ) -> tuple[PointCloud, dict[str, NDArray[Any]]]:  # fmt: skip
    """Read the vertices of a PLY file (ascii or binary, either byte order), as :func:`read_pcd`
    reads a PCD file: colours from ``red``, ``green``, ``blue`` (all three or none), the other vertex
    properties as extras in native byte order."""
    scale = check_units(units)
    p = readable_path(path)
    with parse_errors(p, "the PLY file"):
        vertices = _read_vertices(p, p.read_bytes())
    names = vertices.dtype.names or ()
    missing = [axis for axis in "xyz" if axis not in names]
    if missing:
        raise FileFormatError(
            f"{p}: PLY 'vertex' element has no property {missing[0]!r} (has: {list(names)})")
    has_color = all(c in names for c in _COLOR_NAMES)
    partial = [c for c in _COLOR_NAMES if c in names]
    if partial and not has_color:
        raise FileFormatError(
            f"{p}: PLY 'vertex' element has colour properties {partial} but not "
            f"{[c for c in _COLOR_NAMES if c not in names]}; a colour needs all three")
    taken = {"x", "y", "z", *(_COLOR_NAMES if has_color else ())}
    # Widening a signalling NaN (a corrupted float) raises "invalid"; finish_cloud handles NaN.
    with np.errstate(invalid="ignore"):
        xyz = np.column_stack([vertices[a].astype(np.float64) for a in "xyz"])
        colors = np.column_stack([vertices[c] for c in _COLOR_NAMES]) if has_color else None
        extras = {n: vertices[n].astype(vertices[n].dtype.newbyteorder("=")) for n in names
                  if n not in taken}  # fmt: skip
    return finish_cloud(p, xyz, colors, extras, scale=scale, drop_nan=drop_nan,
                        color_field="red/green/blue")  # fmt: skip


def write_ply(path: str | Path, cloud: PointCloud, *, format: str = "binary_little_endian",
              extra_fields: dict[str, Any] | None = None) -> None:
    """Write a cloud as the ``vertex`` element of a PLY file of ``format`` in ``PLY_FORMATS``:
    x, y, z as ``double`` (exact round trip), colours as ``uchar``, ``extra_fields`` as more
    properties (8- to 32-bit integers, float32 or float64). Written atomically
    (:func:`deformap._files.atomic_path`)."""
    if format not in PLY_FORMATS:
        raise InvalidArgumentError(f"`format` must be one of {PLY_FORMATS}; got {format!r}")
    cloud, extras = _check_cloud_and_extras(cloud, extra_fields)
    order = ">" if format == "binary_big_endian" else "<"
    fields: list[tuple[str, NDArray[Any]]] = [(a, cloud.points[:, i]) for i, a in enumerate("xyz")]
    if cloud.colors is not None:
        rgb = np.round(cloud.colors * 255).astype(np.uint8)
        fields += [(c, rgb[:, i]) for i, c in enumerate(_COLOR_NAMES)]
    for name, values in extras.items():
        code = values.dtype.str[1:]
        if code not in _NUMPY_TO_PLY:
            raise InvalidArgumentError(
                f"`extra_fields[{name!r}]` has dtype {values.dtype}, which PLY cannot store "
                f"(use one of {sorted(_NUMPY_TO_PLY)})")
        fields.append((name, values))
    dtype = np.dtype([(name, order + values.dtype.str[1:]) for name, values in fields])
    table = np.empty(len(cloud), dtype=dtype)
    for name, values in fields:
        table[name] = values
    header = ["ply", f"format {format} 1.0", "comment written by deformap",
              f"element vertex {len(cloud)}"]  # fmt: skip
    header += [f"property {_NUMPY_TO_PLY[values.dtype.str[1:]]} {name}" for name, values in fields]
    header.append("end_header")
    with atomic_path(path) as tmp, open(tmp, "xb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        if format == "ascii":
            fmts = ["%.17g" if v.dtype.kind == "f" else "%d" for _, v in fields]
            np.savetxt(fh, table, fmt=fmts)
        else:
            fh.write(table.tobytes())
