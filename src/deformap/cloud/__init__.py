"""Point clouds: the container, filters (crop, statistical outliers, convex hull), tactile points,
and file I/O.

All functions are pure: they take ``(n, 3)`` arrays of metres and return masks or new arrays.
"""

from __future__ import annotations

from deformap.cloud._pointcloud import PointCloud

__all__ = ["PointCloud"]
