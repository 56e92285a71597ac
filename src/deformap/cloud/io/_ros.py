"""Lazy access to the optional ``rosbags`` package (extra ``ros``)."""

from __future__ import annotations

from functools import cache
from typing import Any

from deformap.errors import missing_extra

__all__ = ["ROS_DISTRO", "typestore"]

#: The message definitions used to write and, for bags that carry none, read messages. The
#: messages deformap uses (PointCloud2, WrenchStamped, TFMessage) are identical from Humble on.
ROS_DISTRO = "ros2_humble"


@cache
def typestore() -> Any:
    """Return rosbags' typestore for :data:`ROS_DISTRO`, or raise MissingDependencyError."""
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise missing_extra("rosbags", "ros", "reading and writing ROS 2 messages") from None
    return get_typestore(Stores(ROS_DISTRO))
