"""Typed messages of a ROS 2 bag: PointCloud2 topics read into clouds (in the world frame given a
4×4 ``cam2world``, or one composed from the bag's ``/tf_static``), WrenchStamped topics into arrays.

``path`` is the bag (a rosbag2 folder, ``.mcap`` or ``.db3``), read through
:func:`~deformap.cloud.io.iter_bag_messages`.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._bag_reader import (
    _rosbag2,
    bag_error_text,
    bag_read_errors,
    iter_bag_messages,
)
from deformap.cloud.io._common import check_units
from deformap.cloud.io._pointcloud2 import _to_cloud
from deformap.cloud.io._ros import typestore
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["CLOUD_TYPE", "TF_STATIC_TOPIC", "TF_TYPE", "WRENCH_TYPE", "StampedCloud",
           "WrenchSeries", "read_bag_clouds", "read_bag_static_transform", "read_bag_wrenches"]

CLOUD_TYPE = "sensor_msgs/msg/PointCloud2"
WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"
TF_STATIC_TOPIC = "/tf_static"


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


def _stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


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


def _transform_matrix(transform: Any) -> NDArray[np.float64]:
    from scipy.spatial.transform import Rotation

    q = transform.rotation
    quat = np.array([q.x, q.y, q.z, q.w], dtype=float)
    if not np.isfinite(quat).all() or abs(np.linalg.norm(quat) - 1.0) > 1e-3:
        raise ValueError(f"rotation quaternion {quat.tolist()} is not a unit quaternion")
    mat = np.eye(4)
    mat[:3, :3] = Rotation.from_quat(quat).as_matrix()
    t = transform.translation
    mat[:3, 3] = [t.x, t.y, t.z]
    return mat


def read_bag_static_transform(
    path: str | Path, source_frame: str, target_frame: str, *, topic: str = TF_STATIC_TOPIC
) -> NDArray[np.float64]:
    """The 4×4 ``source2target`` transform (``p_t = T[:3, :3] p_s + T[:3, 3]``)
    composed from a bag's static transforms on ``topic``, between frames named as in the messages."""
    # Each TransformStamped gives child2parent; walk the tree in both directions.
    edges: dict[str, list[tuple[str, NDArray[np.float64]]]] = {}
    p = Path(path) if isinstance(path, (str, Path)) else path
    for _, msg in _messages(path, topic, TF_TYPE):
        for tf in msg.transforms:
            try:
                child2parent = _transform_matrix(tf.transform)
            except ValueError as exc:
                raise FileFormatError(
                    f"{p}: {topic} transform {tf.header.frame_id!r} -> {tf.child_frame_id!r}: {exc}"
                ) from None
            parent, child = tf.header.frame_id, tf.child_frame_id
            edges.setdefault(child, []).append((parent, child2parent))
            edges.setdefault(parent, []).append((child, np.asarray(np.linalg.inv(child2parent))))
    if source_frame == target_frame:
        return np.eye(4)
    seen = {source_frame: np.eye(4)}
    queue = deque([source_frame])
    while queue:
        frame = queue.popleft()
        for neighbour, frame2neighbour in edges.get(frame, []):
            if neighbour not in seen:
                seen[neighbour] = frame2neighbour @ seen[frame]
                queue.append(neighbour)
    if target_frame not in seen:
        raise FileFormatError(
            f"{p}: {topic} does not connect frame {source_frame!r} to {target_frame!r} "
            f"(frames: {sorted(edges)}); pass cam2world= instead")
    return seen[target_frame]


def read_bag_clouds(path: str | Path, topic: str, *, cam2world: Any = None,
                    world_frame: str = "world", units: str = "m") -> list[StampedCloud]:
    """Every PointCloud2 message of ``topic``, in the bag's order, as :class:`StampedCloud`.

    ``cam2world`` None keeps each cloud in its header's frame; a (4, 4) matrix maps them to the world
    frame; ``"tf_static"`` composes it from the bag's ``/tf_static`` for each header's ``frame_id``
    up to ``world_frame``. ``units`` are the coordinates'. NaN holes are dropped and counted; a
    message with no finite point is refused.
    """
    scale = check_units(units)
    fixed = None
    if cam2world is not None and not (isinstance(cam2world, str) and cam2world == "tf_static"):
        fixed = check_array("cam2world", cam2world, (4, 4), what="homogeneous transform entries")
    transforms: dict[str, NDArray[np.float64]] = {}
    out = []
    for index, (log_time, msg) in enumerate(_messages(path, topic, CLOUD_TYPE)):
        where = f"{path} [{topic} message {index + 1}]"
        cloud, dropped = _to_cloud(msg, where, scale, msg.header.frame_id or "sensor", True)
        if cam2world is not None:
            if fixed is None:
                frame = msg.header.frame_id
                if frame not in transforms:
                    transforms[frame] = read_bag_static_transform(path, frame, world_frame)
                matrix = transforms[frame]
            else:
                matrix = fixed
            cloud = cloud.transformed(matrix, world_frame if fixed is None else "world")
        out.append(StampedCloud(stamp_ns=_stamp_ns(msg.header), log_time_ns=log_time,
                                cloud=cloud, n_dropped=dropped))  # fmt: skip
    if not out:
        raise FileFormatError(f"{path}: topic {topic!r} has no messages")
    return out


def read_bag_wrenches(path: str | Path, topic: str) -> WrenchSeries:
    """A ``geometry_msgs/msg/WrenchStamped`` topic as a :class:`WrenchSeries`, in the bag's order."""
    stamps, forces, torques, frames = [], [], [], set()
    for _, msg in _messages(path, topic, WRENCH_TYPE):
        stamps.append(_stamp_ns(msg.header))
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
