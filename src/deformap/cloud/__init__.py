"""Point clouds: the container, filters (crop, statistical outliers, steep faces, convex hull),
tactile points, and file I/O (in :mod:`deformap.cloud.io`).

All functions are pure: they take ``(n, 3)`` arrays of metres and return masks or new arrays.
"""

from __future__ import annotations

from deformap.cloud._filters import (
    HULL_TOLERANCE_M,
    crop_box,
    height_field_mask,
    hull_parts,
    points_in_hull,
    statistical_outlier_mask,
)
from deformap.cloud._pointcloud import PointCloud
from deformap.cloud._tactile import (
    DEFAULT_CAP_HALF_ANGLE_DEG,
    contact_cap,
    tactile_points,
    tip_in_view,
)

__all__ = ["DEFAULT_CAP_HALF_ANGLE_DEG", "HULL_TOLERANCE_M", "PointCloud", "contact_cap",
           "crop_box", "height_field_mask", "hull_parts", "points_in_hull",
           "statistical_outlier_mask", "tactile_points", "tip_in_view"]
