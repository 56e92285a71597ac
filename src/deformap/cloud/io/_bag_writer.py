"""Writing ROS 2 bags (sqlite3 or MCAP) of clouds, wrenches and static transforms.

Used by the tests and by simulated recordings, so that the bag-reading path runs on real files.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from deformap._validation import check_array
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud.io._bag import (
    BAG_STORAGES,
    CLOUD_TYPE,
    TF_STATIC_TOPIC,
    TF_TYPE,
    WRENCH_TYPE,
    WrenchSeries,
    _rosbag2,
)
from deformap.cloud.io._pointcloud2 import array_to_pointcloud2
from deformap.cloud.io._ros import typestore
from deformap.errors import InvalidArgumentError

__all__ = ["bag_writer", "wrench_message", "write_bag"]


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
    """A ``geometry_msgs/msg/WrenchStamped`` (rosbags message) of ``force`` (N) and ``torque``
    (N·m), each ``(3,)``, stamped ``stamp_ns`` nanoseconds in frame ``frame_id``."""
    types = typestore().types
    vec = types["geometry_msgs/msg/Vector3"]
    wrench = types["geometry_msgs/msg/Wrench"](force=vec(*map(float, force)),
                                               torque=vec(*map(float, torque)))  # fmt: skip
    return types[WRENCH_TYPE](header=_header(stamp_ns, frame_id), wrench=wrench)


@contextmanager
def bag_writer(path: str | Path, storage: str = "mcap") -> Iterator[Any]:
    """A rosbags ``Writer`` open on a new ROS 2 bag (rosbag2 version 9): the one bag writer.

    Parameters
    ----------
    path : str or Path
        The bag folder to create; it must not exist.
    storage : {"mcap", "sqlite3"}

    Yields
    ------
    rosbags.rosbag2.Writer
        Add connections with ``typestore=typestore()`` and write serialised messages; the bag is
        closed (its metadata written) when the block ends.
    """
    rosbag2 = _rosbag2()
    if storage not in BAG_STORAGES:
        raise InvalidArgumentError(f"`storage` must be one of {BAG_STORAGES}; got {storage!r}")
    plugin = rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbag2.StoragePlugin.SQLITE3
    p = Path(path)
    if p.exists():
        raise InvalidArgumentError(f"`path` {p} exists already; a bag is written to a new folder")
    with rosbag2.Writer(p, version=9, storage_plugin=plugin) as writer:
        yield writer


def write_bag(
    path: str | Path,
    *,
    storage: str = "mcap",
    clouds: dict[str, Sequence[tuple[int, PointCloud]]] | None = None,
    wrenches: dict[str, WrenchSeries] | None = None,
    static_transforms: Sequence[tuple[str, str, Any]] = (),
    cloud_dtype: str = "float32",
) -> None:
    """Write clouds, wrenches and static transforms to a new ROS 2 bag (rosbag2 version 9).

    Parameters
    ----------
    path : str or Path
        The bag folder to create; it must not exist.
    storage : {"mcap", "sqlite3"}
    clouds : dict of topic to sequence of (stamp_ns, PointCloud), optional
        Written as ``sensor_msgs/msg/PointCloud2`` with ``header.frame_id = cloud.frame``.
    wrenches : dict of topic to WrenchSeries, optional
        Written as ``geometry_msgs/msg/WrenchStamped``.
    static_transforms : sequence of (parent, child, (4, 4) child2parent)
        Written as one ``tf2_msgs/msg/TFMessage`` on ``/tf_static`` at time 0.
    cloud_dtype : {"float32", "float64"}
        Storage of the cloud coordinates.
    """
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
