"""Typed messages of a ROS 2 bag (``path``: a rosbag2 folder, ``.mcap`` or ``.db3``): PointCloud2
topics read into clouds (in the world frame given a 4×4 ``cam2world`` or the bag's ``/tf_static``),
WrenchStamped topics into arrays; and bags of clouds, wrenches and static transforms written.
rosbags writes each MCAP chunk's CRC-32 as zero; :func:`bag_writer` fills them in once the bag is
closed (:func:`fill_chunk_crcs`), so a flipped byte in a stored cloud is refused when read.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._files import atomic_path
from deformap._validation import check_array
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._bag_reader import (
    _MCAP_MAGIC,
    BAG_STORAGES,
    _rosbag2,
    bag_error_text,
    bag_read_errors,
    header_message,
    header_stamp_ns,
    iter_bag_messages,
    typestore,
)
from deformap.cloud.io._common import check_units
from deformap.cloud.io._pointcloud2 import array_to_pointcloud2, pointcloud2_to_cloud
from deformap.cloud.io._tf import TransformTree
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["StampedCloud", "WrenchSeries", "bag_writer", "fill_chunk_crcs", "read_bag_clouds",
           "read_bag_static_transform", "read_bag_transforms", "read_bag_wrenches",
           "wrench_message", "write_bag"]

CLOUD_TYPE = "sensor_msgs/msg/PointCloud2"
WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"
TF_STATIC_TOPIC = "/tf_static"
TF_TOPIC = "/tf"


@dataclass(frozen=True, kw_only=True)
class StampedCloud:
    """One PointCloud2 message read from a bag: header and log times [ns], the cloud (metres, in
    ``"world"`` when transformed, else in the header's frame), and the NaN points dropped."""

    stamp_ns: int
    log_time_ns: int
    cloud: PointCloud
    n_dropped: int


@dataclass(frozen=True, kw_only=True)
class WrenchSeries:
    """A WrenchStamped topic: ``stamp_ns`` (n,) header times, ``force_n`` and ``torque_nm`` (n, 3)
    in the sensor frame ``frame_id`` all its messages share."""

    stamp_ns: NDArray[np.int64]
    force_n: NDArray[np.float64]
    torque_nm: NDArray[np.float64]
    frame_id: str


def _messages(path: Any, topic: str, msgtype: str) -> Iterator[tuple[int, Any]]:
    """(log time, deserialised message) of ``topic``; every failure names file and topic."""
    if not isinstance(topic, str) or not topic:
        raise InvalidArgumentError(f"`topic` must be a non-empty str; got {topic!r}")
    _rosbag2()  # a missing extra is named for reading bags, before the typestore asks for it
    store, errors = typestore(), bag_read_errors()
    for raw in iter_bag_messages(path, {topic: msgtype}):
        try:
            msg = store.deserialize_cdr(raw.data, msgtype)
        except errors as exc:
            raise FileFormatError(
                f"{Path(path)}: could not read topic {topic!r}: {bag_error_text(exc)}") from exc
        yield raw.log_time_ns, msg


def read_bag_static_transform(
    path: str | Path, source_frame: str, target_frame: str, *, topic: str = TF_STATIC_TOPIC
) -> NDArray[np.float64]:
    """The 4×4 ``source2target`` transform (``p_t = T[:3, :3] p_s + T[:3, 3]``)
    composed from a bag's static transforms on ``topic``, between frames named as in the messages."""
    p = Path(path) if isinstance(path, (str, Path)) else path
    tree = TransformTree(topic, 0)
    for _, msg in _messages(path, topic, TF_TYPE):
        tree.add(msg, static=True, where=f"{p}: {topic}")
    out = np.eye(4)
    if source_frame == target_frame:
        return out
    try:
        rot, trans = tree.lookup(target_frame, source_frame, 0, what=f"{p}: {topic}")
    except FileFormatError:
        raise FileFormatError(
            f"{p}: {topic} does not connect frame {source_frame!r} to {target_frame!r} "
            f"(frames: {tree.frames}); pass cam2world= instead") from None
    out[:3, :3], out[:3, 3] = rot[0], trans[0]
    return out


def read_bag_transforms(path: str | Path, *, tolerance_ns: int) -> TransformTree:
    """A bag's ``/tf_static`` and ``/tf`` (this one may be missing) as one
    :class:`~deformap.cloud.io.TransformTree`, looked up at header stamps [ns] within
    ``tolerance_ns`` of a dynamic edge's nearest sample."""
    p = Path(path)
    tree = TransformTree(TF_TOPIC, tolerance_ns)
    store, errors = typestore(), bag_read_errors()
    for raw in iter_bag_messages(p, {TF_STATIC_TOPIC: TF_TYPE}, optional={TF_TOPIC: TF_TYPE}):
        try:
            msg = store.deserialize_cdr(raw.data, TF_TYPE)
        except errors as exc:
            raise FileFormatError(
                f"{p}: could not read topic {raw.topic!r}: {bag_error_text(exc)}") from exc
        tree.add(msg, static=raw.topic == TF_STATIC_TOPIC, where=f"{p}: {raw.topic}")
    return tree


def read_bag_clouds(path: str | Path, topic: str, *, cam2world: Any = None,
                    world_frame: str = "world", units: str = "m") -> list[StampedCloud]:
    """Every PointCloud2 message of ``topic``, in the bag's order, as :class:`StampedCloud`.

    ``cam2world`` None keeps each cloud in its header's frame; a (4, 4) matrix maps them to the world
    frame; ``"tf_static"`` composes it from the bag's ``/tf_static`` for each header's ``frame_id``
    up to ``world_frame``. ``units`` are the coordinates'. NaN holes are dropped and counted; a
    message with no finite point is refused.
    """
    check_units(units)  # refused before the bag is opened
    fixed = None
    if cam2world is not None and not (isinstance(cam2world, str) and cam2world == "tf_static"):
        fixed = check_array("cam2world", cam2world, (4, 4), what="homogeneous transform entries")
    transforms: dict[str, NDArray[np.float64]] = {}
    out = []
    for index, (log_time, msg) in enumerate(_messages(path, topic, CLOUD_TYPE)):
        where = f"{path} [{topic} message {index + 1}]"
        cloud, dropped = pointcloud2_to_cloud(msg, where=where, units=units)
        if fixed is not None:
            cloud = cloud.transformed(fixed, "world")
        elif cam2world is not None:
            frame = msg.header.frame_id
            if frame not in transforms:
                transforms[frame] = read_bag_static_transform(path, frame, world_frame)
            cloud = cloud.transformed(transforms[frame], world_frame)
        out.append(StampedCloud(stamp_ns=header_stamp_ns(msg.header), log_time_ns=log_time,
                                cloud=cloud, n_dropped=dropped))  # fmt: skip
    if not out:
        raise FileFormatError(f"{path}: topic {topic!r} has no messages")
    return out


def read_bag_wrenches(path: str | Path, topic: str) -> WrenchSeries:
    """A ``geometry_msgs/msg/WrenchStamped`` topic as a :class:`WrenchSeries`, in the bag's order."""
    stamps, forces, torques, frames = [], [], [], set()
    for _, msg in _messages(path, topic, WRENCH_TYPE):
        stamps.append(header_stamp_ns(msg.header))
        f, t = msg.wrench.force, msg.wrench.torque
        forces.append([f.x, f.y, f.z])
        torques.append([t.x, t.y, t.z])
        frames.add(msg.header.frame_id)
    if not stamps:
        raise FileFormatError(f"{path}: topic {topic!r} has no messages")
    if len(frames) > 1:
        raise FileFormatError(f"{path}: topic {topic!r} mixes frames {sorted(frames)}")
    force, torque = np.array(forces, dtype=float), np.array(torques, dtype=float)
    if not (np.isfinite(force).all() and np.isfinite(torque).all()):
        raise FileFormatError(f"{path}: topic {topic!r} holds NaN or infinite wrenches")
    return WrenchSeries(stamp_ns=np.array(stamps, dtype=np.int64), force_n=force,
                        torque_nm=torque, frame_id=frames.pop())  # fmt: skip


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
            header=header_message(0, parent), child_frame_id=child, transform=transform))  # fmt: skip
    return types[TF_TYPE](transforms=items)


def wrench_message(stamp_ns: int, frame_id: str, force: Any, torque: Any) -> Any:
    """A rosbags ``WrenchStamped`` of ``force`` [N] and ``torque`` [N·m], each ``(3,)``."""
    types = typestore().types
    vec = types["geometry_msgs/msg/Vector3"]
    wrench = types["geometry_msgs/msg/Wrench"](force=vec(*map(float, force)),
                                               torque=vec(*map(float, torque)))  # fmt: skip
    return types[WRENCH_TYPE](header=header_message(stamp_ns, frame_id), wrench=wrench)


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
