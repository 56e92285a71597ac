"""Point-cloud files and ROS 2 bags in and out.

Readers return clouds in metres and refuse what they cannot read faithfully: truncated or corrupted
files, missing x/y/z, NaN points (unless ``drop_nan=True``), empty clouds, and clouds that look like
millimetres (unless ``units="mm"``). Every refusal is a :class:`~deformap.errors.FileFormatError`
that names the file and what was wrong. No file is ever read with pickle.

Every size a header declares (a point count, a record size, a compressed length, an array's
shape) is checked against the bytes present before anything is allocated, and a binary body that
holds more data than its header declares is refused, not cut (``_common.check_body_size``).

Formats: PCD (ascii, binary, binary_compressed; through pypcd4), PLY (ascii, binary either byte
order; numpy), NPZ (``points``, ``colors``; at most :data:`MAX_NPZ_BYTES` once decompressed), and
ROS 2 bags (sqlite3 and MCAP; through the optional ``rosbags``, extra ``ros``) with
``sensor_msgs/msg/PointCloud2`` and ``geometry_msgs/msg/WrenchStamped``. :func:`iter_bag_messages`
is the one place a bag is opened and read, :func:`bag_writer` the one place one is written;
:func:`pointcloud2_to_cloud` turns a message into a cloud under the file readers' rules.
"""

from __future__ import annotations

from deformap.cloud.io._bag import (
    StampedCloud,
    WrenchSeries,
    read_bag_clouds,
    read_bag_static_transform,
    read_bag_wrenches,
)
from deformap.cloud.io._bag_reader import (
    BAG_STORAGES,
    RawBagMessage,
    bag_error_text,
    bag_read_errors,
    iter_bag_messages,
)
from deformap.cloud.io._bag_writer import bag_writer, fill_chunk_crcs, wrench_message, write_bag
from deformap.cloud.io._common import MM_EXTENT_THRESHOLD, UNITS, path_kind
from deformap.cloud.io._dispatch import CLOUD_FORMATS, read_cloud, write_cloud
from deformap.cloud.io._npz import MAX_NPZ_BYTES, load_npz_arrays, read_npz, write_npz
from deformap.cloud.io._pcd import PCD_ENCODINGS, read_pcd, write_pcd
from deformap.cloud.io._ply import PLY_FORMATS, read_ply, write_ply
from deformap.cloud.io._pointcloud2 import (
    array_to_pointcloud2,
    pointcloud2_structured,
    pointcloud2_to_array,
    pointcloud2_to_cloud,
)
from deformap.cloud.io._ros import ROS_DISTRO, typestore

__all__ = [
    "BAG_STORAGES",
    "CLOUD_FORMATS",
    "MAX_NPZ_BYTES",
    "MM_EXTENT_THRESHOLD",
    "PCD_ENCODINGS",
    "PLY_FORMATS",
    "ROS_DISTRO",
    "UNITS",
    "RawBagMessage",
    "StampedCloud",
    "WrenchSeries",
    "array_to_pointcloud2",
    "bag_error_text",
    "bag_read_errors",
    "bag_writer",
    "fill_chunk_crcs",
    "iter_bag_messages",
    "load_npz_arrays",
    "path_kind",
    "pointcloud2_structured",
    "pointcloud2_to_array",
    "pointcloud2_to_cloud",
    "read_bag_clouds",
    "read_bag_static_transform",
    "read_bag_wrenches",
    "read_cloud",
    "read_npz",
    "read_pcd",
    "read_ply",
    "typestore",
    "wrench_message",
    "write_bag",
    "write_cloud",
    "write_npz",
    "write_pcd",
    "write_ply",
]
