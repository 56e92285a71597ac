"""Point-cloud files (PCD, PLY, NPZ) and ROS 2 bags (sqlite3, MCAP; extra ``ros``) in and out.

Readers return clouds in metres and refuse what they cannot read faithfully (truncated or corrupt
files, sizes a header declares that the bytes do not hold, missing x/y/z, NaN points unless
``drop_nan=True``, empty clouds, metres that look like millimetres unless ``units="mm"``) with one
:class:`~deformap.errors.FileFormatError` naming the file; nothing is unpickled.
:func:`iter_bag_messages` is the one bag reader, :func:`bag_writer` the one writer. Colours (RGB in
[0, 1]) are read from every format's usual fields and written whenever a cloud has them.
"""

from __future__ import annotations

from deformap.cloud.io._bag import (
    StampedCloud,
    WrenchSeries,
    bag_writer,
    read_bag_clouds,
    read_bag_static_transform,
    read_bag_transforms,
    read_bag_wrenches,
    wrench_message,
    write_bag,
)
from deformap.cloud.io._bag_reader import (
    BAG_STORAGES,
    RawBagMessage,
    bag_error_text,
    bag_read_errors,
    bag_topics,
    header_message,
    header_stamp_ns,
    iter_bag_messages,
    typestore,
)
from deformap.cloud.io._common import MM_EXTENT_THRESHOLD, UNITS, path_kind
from deformap.cloud.io._dispatch import CLOUD_FORMATS, read_cloud, write_cloud
from deformap.cloud.io._npz import MAX_NPZ_BYTES, load_npz_arrays, read_npz, write_npz
from deformap.cloud.io._pcd import PCD_ENCODINGS, read_pcd, write_pcd
from deformap.cloud.io._ply import PLY_FORMATS, read_ply, write_ply
from deformap.cloud.io._pointcloud2 import (
    array_to_pointcloud2,
    pointcloud2_colors,
    pointcloud2_structured,
    pointcloud2_to_array,
    pointcloud2_to_cloud,
    xyz_with_holes,
)
from deformap.cloud.io._tf import TransformTree

__all__ = ["BAG_STORAGES", "CLOUD_FORMATS", "MAX_NPZ_BYTES", "MM_EXTENT_THRESHOLD", "PCD_ENCODINGS",
           "PLY_FORMATS", "UNITS", "RawBagMessage", "StampedCloud", "TransformTree", "WrenchSeries",
           "array_to_pointcloud2", "bag_error_text", "bag_read_errors", "bag_topics", "bag_writer",
           "header_message", "header_stamp_ns", "iter_bag_messages", "load_npz_arrays", "path_kind",
           "pointcloud2_colors", "pointcloud2_structured", "pointcloud2_to_array",
           "pointcloud2_to_cloud", "read_bag_clouds", "read_bag_static_transform", "read_bag_transforms",
           "read_bag_wrenches", "read_cloud", "read_npz", "read_pcd", "read_ply", "typestore",
           "wrench_message", "write_bag", "write_cloud", "write_npz", "write_pcd", "write_ply",
           "xyz_with_holes"]
