"""Writing ROS 2 bags (sqlite3 or MCAP) of clouds, wrenches and static transforms, for the tests
and simulated recordings.

rosbags writes each MCAP chunk's CRC-32 as zero; once its writer has closed the bag each CRC is
filled in (:func:`fill_chunk_crcs`), so a flipped byte in a stored cloud is refused when read.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from deformap._files import atomic_path
from deformap._validation import check_array
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._bag import CLOUD_TYPE, TF_STATIC_TOPIC, TF_TYPE, WRENCH_TYPE, WrenchSeries
from deformap.cloud.io._bag_reader import BAG_STORAGES, _rosbag2
from deformap.cloud.io._pointcloud2 import array_to_pointcloud2
from deformap.cloud.io._ros import typestore
from deformap.errors import InvalidArgumentError

__all__ = ["bag_writer", "fill_chunk_crcs", "wrench_message", "write_bag"]

_MCAP_MAGIC = b"\x89MCAP0\r\n"
_CHUNK_OPCODE = 0x06
# a chunk's fields before its CRC: message start and end time, uncompressed size (u64 each)
_CHUNK_CRC_AT = 24


def fill_chunk_crcs(path: str | Path) -> int:
    """Write each uncompressed chunk's CRC-32 where a writer left it zero, rewriting the MCAP
    file atomically; returns how many were filled.

    A chunk record (MCAP specification): opcode ``0x06``, content length (u64), message start and end
    time and uncompressed size (u64 each), the CRC (u32), the compression (u32 length + name) and the
    records (u64 length + bytes); all little-endian.
    """
    data = bytearray(Path(path).read_bytes())
    if not data.startswith(_MCAP_MAGIC):
        raise InvalidArgumentError(f"`path` {path} is not an MCAP file (no leading magic)")
    filled, at = 0, len(_MCAP_MAGIC)
    while at + 9 <= len(data) - len(_MCAP_MAGIC):
        opcode = data[at]
        (length,) = struct.unpack_from("<Q", data, at + 1)
        content = at + 9
        if content + length > len(data):
            raise InvalidArgumentError(f"`path` {path}: a record runs past the file's end")
        if opcode == _CHUNK_OPCODE:
            crc_at = content + _CHUNK_CRC_AT
            (crc,) = struct.unpack_from("<I", data, crc_at)
            (name_len,) = struct.unpack_from("<I", data, crc_at + 4)
            records_at = crc_at + 8 + name_len
            (records_len,) = struct.unpack_from("<Q", data, records_at)
            if crc == 0 and name_len == 0:  # uncompressed: the CRC is of the records as stored
                records = data[records_at + 8:records_at + 8 + records_len]
                struct.pack_into("<I", data, crc_at, zlib.crc32(records))
                filled += 1
        at = content + length
    if filled:
        with atomic_path(path) as tmp:
            tmp.write_bytes(bytes(data))
    return filled


def _header(stamp_ns: int, frame_id: str) -> Any:
    types = typestore().types
    time = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    return types["std_msgs/msg/Header"](stamp=time, frame_id=frame_id)


def _tf_message(transforms: Sequence[tuple[str, str, Any]]) -> Any:
    from scipy.spatial.transform import Rotation

    types = typestore().types
    items = []
    for parent, child, matrix in transforms:
        mat = check_array("static_transforms matrix", matrix, (4, 4), what="transform entries")
        x, y, z, w = Rotation.from_matrix(mat[:3, :3]).as_quat()
        transform = types["geometry_msgs/msg/Transform"](
            translation=types["geometry_msgs/msg/Vector3"](x=mat[0, 3], y=mat[1, 3], z=mat[2, 3]),
            rotation=types["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w),
        )
        items.append(types["geometry_msgs/msg/TransformStamped"](
            header=_header(0, parent), child_frame_id=child, transform=transform))  # fmt: skip
    return types[TF_TYPE](transforms=items)


def wrench_message(stamp_ns: int, frame_id: str, force: Any, torque: Any) -> Any:
    """A rosbags ``WrenchStamped`` of ``force`` [N] and ``torque`` [N·m], each ``(3,)``."""
    types = typestore().types
    vec = types["geometry_msgs/msg/Vector3"]
    wrench = types["geometry_msgs/msg/Wrench"](force=vec(*map(float, force)),
                                               torque=vec(*map(float, torque)))  # fmt: skip
    return types[WRENCH_TYPE](header=_header(stamp_ns, frame_id), wrench=wrench)


@contextmanager
def bag_writer(path: str | Path, storage: str = "mcap") -> Iterator[Any]:
    """A rosbags ``Writer`` on a new ROS 2 bag folder (rosbag2 version 9, ``storage`` "mcap" or
    "sqlite3"): the one bag writer. The bag is closed and its chunk CRCs filled when the block ends."""
    rosbag2 = _rosbag2()
    if storage not in BAG_STORAGES:
        raise InvalidArgumentError(f"`storage` must be one of {BAG_STORAGES}; got {storage!r}")
    plugin = rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbag2.StoragePlugin.SQLITE3
    p = Path(path)
    if p.exists():
        raise InvalidArgumentError(f"`path` {p} exists already; a bag is written to a new folder")
    with rosbag2.Writer(p, version=9, storage_plugin=plugin) as writer:
        yield writer
    for mcap in sorted(p.glob("*.mcap")) if storage == "mcap" else ():
        fill_chunk_crcs(mcap)


def write_bag(path: str | Path, *, storage: str = "mcap",
              clouds: dict[str, Sequence[tuple[int, PointCloud]]] | None = None,
              wrenches: dict[str, WrenchSeries] | None = None,
              static_transforms: Sequence[tuple[str, str, Any]] = (),
              cloud_dtype: str = "float32") -> None:
    """Write to a new ROS 2 bag folder (version 9, ``storage`` "mcap" or "sqlite3"): ``clouds``
    (topic → (stamp_ns, PointCloud) pairs) as PointCloud2 in ``cloud.frame`` with coordinates as
    ``cloud_dtype``, ``wrenches`` (topic → WrenchSeries) as WrenchStamped, and
    ``static_transforms`` ((parent, child, 4×4 child2parent) triples) as one ``/tf_static``
    TFMessage at time 0."""
    store = typestore()
    with bag_writer(path, storage) as writer:
        if static_transforms:
            conn = writer.add_connection(TF_STATIC_TOPIC, TF_TYPE, typestore=store)
            msg = _tf_message(static_transforms)
            writer.write(conn, 0, store.serialize_cdr(msg, TF_TYPE))
        for topic, stamped in (clouds or {}).items():
            conn = writer.add_connection(topic, CLOUD_TYPE, typestore=store)
            for stamp, cloud in stamped:
                msg = array_to_pointcloud2(cloud.points, colors=cloud.colors, frame_id=cloud.frame,
                                           stamp_ns=stamp, dtype=cloud_dtype)  # fmt: skip
                writer.write(conn, stamp, store.serialize_cdr(msg, CLOUD_TYPE))
        for topic, series in (wrenches or {}).items():
            conn = writer.add_connection(topic, WRENCH_TYPE, typestore=store)
            for stamp, force, torque in zip(series.stamp_ns, series.force_n, series.torque_nm,
                                            strict=True):  # fmt: skip
                msg = wrench_message(int(stamp), series.frame_id, force, torque)
                writer.write(conn, int(stamp), store.serialize_cdr(msg, WRENCH_TYPE))
