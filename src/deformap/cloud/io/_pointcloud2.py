"""``sensor_msgs/msg/PointCloud2`` to and from arrays, for any field layout.

A PointCloud2 is ``height`` rows of ``width`` points of ``point_step`` bytes, each field at its
``offset``, rows every ``row_step`` bytes (rows may be padded). Reading views the data through a
numpy structured dtype with those offsets. ``msg`` is a rosbags message or any object with its
attributes (``data`` as bytes or uint8); ``where`` names it in errors.

References
----------
ROS 2 ``sensor_msgs/msg/PointCloud2`` and ``sensor_msgs/msg/PointField``;
``sensor_msgs_py.point_cloud2`` (the reference reader).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_int, check_points
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._bag_reader import header_message, typestore
from deformap.cloud.io._common import check_colors, check_units, finish_cloud, pack_rgb, unpack_rgb
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["array_to_pointcloud2", "pointcloud2_colors", "pointcloud2_structured",
           "pointcloud2_to_array", "pointcloud2_to_cloud", "xyz_with_holes"]

logger = logging.getLogger(__name__)

# sensor_msgs/msg/PointField datatype constants.
_DATATYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}
_FLOAT_CODES = {7: "f4", 8: "f8"}


def _message_bytes(msg: Any) -> NDArray[np.uint8]:
    data = msg.data
    if isinstance(data, np.ndarray):
        return data.view(np.uint8).reshape(-1) if data.dtype.itemsize == 1 else data.view(np.uint8)
    return np.frombuffer(bytes(data), dtype=np.uint8)


def _layout(msg: Any) -> tuple[np.dtype[Any], int, int, int, int]:
    try:
        height, width = int(msg.height), int(msg.width)
        point_step, row_step = int(msg.point_step), int(msg.row_step)
        fields = list(msg.fields)
        order = ">" if bool(msg.is_bigendian) else "<"
    except (AttributeError, TypeError, ValueError) as exc:
        raise InvalidArgumentError(
            f"`msg` must be a sensor_msgs/msg/PointCloud2 message; got {type(msg).__name__} ({exc})"
        ) from None
    if min(height, width, point_step, row_step) < 0:
        raise InvalidArgumentError(
            f"`msg` has a negative size: height={height}, width={width}, "
            f"point_step={point_step}, row_step={row_step}")
    names, formats, offsets = [], [], []
    for f in fields:
        code = _DATATYPES.get(int(f.datatype))
        count = int(f.count)
        if code is None:
            raise InvalidArgumentError(f"`msg` field {f.name!r} has unknown datatype {f.datatype}")
        if not f.name or f.name in names or count < 1:
            continue  # unnamed or repeated fields and count 0 carry nothing we can address
        end = int(f.offset) + np.dtype(code).itemsize * count
        if int(f.offset) < 0 or end > point_step:
            raise InvalidArgumentError(
                f"`msg` field {f.name!r} spans bytes {f.offset}..{end} of a {point_step}-byte point"
            )
        names.append(f.name)
        formats.append(order + code if count == 1 else (order + code, (count,)))
        offsets.append(int(f.offset))
    dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets,
                      "itemsize": point_step})  # fmt: skip
    if height > 1 and row_step < width * point_step:
        raise InvalidArgumentError(
            f"`msg` row_step {row_step} is shorter than width·point_step = {width * point_step}")
    return dtype, height, width, point_step, row_step


def pointcloud2_structured(msg: Any) -> NDArray[Any]:
    """``(height·width,)`` structured view of a PointCloud2's points, one field per PointField,
    in the message's byte order (padding between fields and rows skipped)."""
    dtype, height, width, point_step, row_step = _layout(msg)
    data = _message_bytes(msg)
    n = height * width
    if n == 0:
        if data.size > height * row_step:  # a header lowered to no points over data
            raise InvalidArgumentError(
                f"`msg` data holds {data.size} bytes but {height}×{width} points: none counted")
        return np.empty(0, dtype=dtype)
    if point_step == 0:
        raise InvalidArgumentError(f"`msg` has {n} points but point_step 0")
    # The last row needs only width·point_step bytes; earlier rows need row_step each.
    need = (height - 1) * row_step + width * point_step
    if data.size < need:
        raise InvalidArgumentError(
            f"`msg` data holds {data.size} bytes but {height}×{width} points of {point_step} bytes "
            f"(row_step {row_step}) need {need}")
    # a message holds height·row_step bytes: more is data the header no longer counts (its
    # height or width lowered), which reading would drop silently
    most = max(height * row_step, need)
    if data.size > most:
        raise InvalidArgumentError(
            f"`msg` data holds {data.size} bytes but {height}×{width} points of {point_step} bytes "
            f"(row_step {row_step}) fill {most}: {data.size - most} bytes the header does not count"
        )
    if row_step == width * point_step or height == 1:
        return np.frombuffer(data, dtype=dtype, count=n)
    rows = np.lib.stride_tricks.as_strided(
        data, shape=(height, width * point_step), strides=(row_step, 1), writeable=False)
    return np.ascontiguousarray(rows).view(dtype).reshape(-1)


def pointcloud2_to_array(msg: Any, *, with_count: bool = False) -> Any:
    """``(n, 3)`` float64 x, y, z (FLOAT32 or FLOAT64 at any offsets, either byte order) in the
    message's units and frame, and with ``with_count`` the number of points dropped for a NaN or
    infinite coordinate (the holes of an organised cloud; refused when ``is_dense``)."""
    xyz = xyz_with_holes(msg, pointcloud2_structured(msg))
    finite = np.isfinite(xyz).all(axis=1)
    dropped = int(xyz.shape[0] - np.count_nonzero(finite))
    if dropped:
        xyz = xyz[finite]
        logger.debug("PointCloud2: dropped %d non-finite points of %d", dropped, finite.size)
    return (xyz, dropped) if with_count else xyz


def xyz_with_holes(msg: Any, table: NDArray[Any]) -> NDArray[np.float64]:
    """``(height·width, 3)`` float64 x, y, z of a viewed PointCloud2, NaN holes included;
    missing or non-float x/y/z, and non-finite points when ``is_dense``, are refused."""
    fields = {f.name: f for f in msg.fields}
    for axis in "xyz":
        if axis not in fields:
            raise InvalidArgumentError(
                f"`msg` has no field {axis!r} (fields: {[f.name for f in msg.fields]})")
        if int(fields[axis].datatype) not in _FLOAT_CODES or int(fields[axis].count) != 1:
            raise InvalidArgumentError(
                f"`msg` field {axis!r} must be one FLOAT32 or FLOAT64; got datatype "
                f"{fields[axis].datatype} with count {fields[axis].count}")
    xyz = np.empty((table.shape[0], 3))
    with np.errstate(invalid="ignore"):  # signalling NaNs in the holes widen to quiet ones
        for i, axis in enumerate("xyz"):
            xyz[:, i] = table[axis]
    if bool(msg.is_dense):
        bad = int(np.count_nonzero(~np.isfinite(xyz).all(axis=1)))
        if bad:
            raise InvalidArgumentError(
                f"`msg` says is_dense but {bad} of {xyz.shape[0]} points are NaN or infinite")
    return xyz


def array_to_pointcloud2(points: Any, *, colors: Any = None, frame_id: str = "world",
                         stamp_ns: int = 0, dtype: str = "float32") -> Any:
    """An unorganised (height 1), dense, little-endian ``sensor_msgs/msg/PointCloud2``.

    ``points`` are (n, 3) metres stored as ``dtype`` (``"float32"`` or ``"float64"``); ``colors``,
    (n, 3) in [0, 1], go into a packed FLOAT32 ``rgb`` field (the PCL/RViz convention); the header
    gets ``frame_id`` and ``stamp_ns``.
    """
    pts = check_points("points", points, min_rows=0)
    stamp = check_int("stamp_ns", stamp_ns, minimum=0)
    if dtype not in ("float32", "float64"):
        raise InvalidArgumentError(f"`dtype` must be 'float32' or 'float64'; got {dtype!r}")
    if not isinstance(frame_id, str):
        raise InvalidArgumentError(f"`frame_id` must be a str; got {type(frame_id).__name__}")
    types = typestore().types
    point_field, size = types["sensor_msgs/msg/PointField"], np.dtype(dtype).itemsize
    code = point_field.FLOAT32 if dtype == "float32" else point_field.FLOAT64
    fields = [point_field(name=a, offset=i * size, datatype=code, count=1)
              for i, a in enumerate("xyz")]  # fmt: skip
    layout = [(a, "<" + np.dtype(dtype).str[1:]) for a in "xyz"]
    if colors is not None:
        cols = check_array("colors", colors, (pts.shape[0], 3), what="RGB values in [0, 1]")
        if cols.size and (cols.min() < 0 or cols.max() > 1):
            raise InvalidArgumentError("`colors` must lie in [0, 1]")
        fields.append(point_field(name="rgb", offset=3 * size, datatype=7, count=1))
        layout.append(("rgb", "<u4"))
    table = np.empty(pts.shape[0], dtype=layout)
    for i, a in enumerate("xyz"):
        table[a] = pts[:, i]
    if colors is not None:
        table["rgb"] = pack_rgb(cols)
    return types["sensor_msgs/msg/PointCloud2"](
        header=header_message(stamp, frame_id), height=1, width=pts.shape[0], fields=fields,
        is_bigendian=False, point_step=table.dtype.itemsize, row_step=table.nbytes,
        data=table.view(np.uint8), is_dense=True)


def _packed_colors(where: str, table: NDArray[Any], field: str) -> NDArray[np.uint8]:
    column = table[field]
    if column.ndim != 1 or column.dtype.itemsize != 4 or column.dtype.kind not in "fiu":
        raise FileFormatError(
            f"{where}: colour field {field!r} must be one FLOAT32 or UINT32 word per point "
            f"(packed 0x00RRGGBB); got {column.dtype.itemsize}-byte {column.dtype.kind!r} values, "
            f"count {1 if column.ndim == 1 else column.shape[1]}")
    return unpack_rgb(column)


def _separate_colors(where: str, table: NDArray[Any], present: list[str]) -> NDArray[Any]:
    kinds = {table[c].dtype.str[1:] for c in present}
    if len(present) != 3 or any(table[c].ndim != 1 for c in present) or len(kinds) != 1 or not (
            kinds <= {"u1", "f4", "f8"}):  # fmt: skip
        raise FileFormatError(
            f"{where}: colour fields r, g, b must be all three, one UINT8 or FLOAT32 each, of "
            f"one type; got {[(c, table[c].dtype.str[1:], table[c].shape[1:]) for c in present]}")
    return np.column_stack([table[c] for c in present])


def pointcloud2_colors(msg: Any, *, where: str = "PointCloud2", table: Any = None,
                       valid: Any = None) -> NDArray[np.float64] | None:  # fmt: skip
    """``(height·width, 3)`` float64 colours in [0, 1] of a PointCloud2, or None without any.

    Read from ``rgb`` (FLOAT32 or UINT32 ``0x00RRGGBB``, read for its bits: realsense, Azure Kinect,
    PCL), ``rgba`` (``0xAARRGGBB``, alpha ignored) or ``r``, ``g``, ``b`` (UINT8 in [0, 255] or
    FLOAT32 in [0, 1]). ``table`` is ``pointcloud2_structured(msg)`` when the caller has it; only
    the ``valid`` points' colours (default all) are checked, the others' rows are NaN. Another field
    type or count, only some of ``r``, ``g``, ``b``, or a bad colour is a FileFormatError.
    """
    table = pointcloud2_structured(msg) if table is None else table
    names = table.dtype.names or ()
    packed = next((c for c in ("rgb", "rgba") if c in names), None)
    present = [c for c in "rgb" if c in names]
    if packed is not None:
        raw, field = _packed_colors(where, table, packed), packed
    elif present:
        raw, field = _separate_colors(where, table, present), "r/g/b"
    else:
        return None
    keep = np.ones(len(table), dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    out = np.full((len(table), 3), np.nan)
    out[keep] = check_colors(where, raw[keep], field)
    return out


def pointcloud2_to_cloud(msg: Any, *, where: str, units: str = "m", frame: str | None = None,
                         colors: bool = True) -> tuple[PointCloud, int]:
    """A PointCloud2 as a :class:`~deformap.cloud.PointCloud` under the file readers' rules,
    and the number of points dropped for a non-finite coordinate.

    ``units`` are the coordinates'; ``frame`` defaults to the header's ``frame_id`` (``"sensor"``
    when empty); ``colors`` reads the message's colours (:func:`pointcloud2_colors`).
    """
    scale = check_units(units)
    try:
        table = pointcloud2_structured(msg)
        xyz = xyz_with_holes(msg, table)
    except InvalidArgumentError as exc:
        raise FileFormatError(f"{where}: {str(exc).replace('`msg` ', '')}") from None
    finite = np.isfinite(xyz).all(axis=1)
    rgb = pointcloud2_colors(msg, where=where, table=table, valid=finite) if colors else None
    dropped = int(finite.size - finite.sum())
    xyz, rgb = xyz[finite], None if rgb is None else rgb[finite]
    frame = (msg.header.frame_id or "sensor") if frame is None else frame
    cloud, _ = finish_cloud(where, xyz, rgb, {}, scale=scale, drop_nan=False, frame=frame)
    return cloud, dropped
