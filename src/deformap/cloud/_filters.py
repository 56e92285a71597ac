"""Point filters: axis-aligned crop, statistical outliers, steep faces, convex-hull membership.

Each takes ``points : (n, 3) float, metres`` and returns an ``(n,)`` boolean mask of the points to
keep (for :func:`points_in_hull`, of those inside), so that masks compose with ``&`` and apply
through ``cloud.select(mask)``.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import (
    check_int,
    check_points,
    check_positive,
    check_slope_deg,
    check_vector,
)
from deformap.errors import InvalidArgumentError

__all__ = ["HULL_TOLERANCE_M", "crop_box", "height_field_mask", "hull_parts", "points_in_hull",
           "statistical_outlier_mask"]

logger = logging.getLogger(__name__)

#: How far [m] a point may lie outside a hull facet and count as inside: far above Qhull's
#: round-off and far below a depth camera's resolution.
HULL_TOLERANCE_M = 1e-6


def crop_box(points: Any, lower: Any, upper: Any) -> NDArray[np.bool_]:
    """Mask of the points inside the axis-aligned box ``lower <= p <= upper`` ((3,) metres each,
    ``lower <= upper`` on every axis)."""
    pts = check_points("points", points, min_rows=0)
    lo = check_vector("lower", lower, 3, what="metres")
    hi = check_vector("upper", upper, 3, what="metres")
    if np.any(lo > hi):
        raise InvalidArgumentError(
            f"`lower` must be <= `upper` on every axis; got lower={lo.tolist()}, "
            f"upper={hi.tolist()}")
    return np.all((pts >= lo) & (pts <= hi), axis=1)


def statistical_outlier_mask(points: Any, k: int, std_ratio: float) -> NDArray[np.bool_]:
    """Mask of the points kept by Open3D's statistical outlier rule.

    A point is kept when its average distance to its ``k`` nearest neighbours (itself included) is
    strictly below ``m + std_ratio · s``, ``m`` the mean of the averages and ``s`` their sample
    standard deviation. As in Open3D's code, a zero average counts in ``m`` but not in ``s`` and is
    never kept, and equal averages (``s = 0``) remove every point.

    References
    ----------
    Open3D, ``PointCloud::RemoveStatisticalOutliers``; Rusu et al., "Towards 3D point cloud based
    object maps for household environments", 2008.
    """
    k = check_int("k", k, minimum=1)
    ratio = check_positive("std_ratio", std_ratio)
    pts = check_points("points", points, min_rows=0)
    n = pts.shape[0]
    if n < max(k, 2):
        raise InvalidArgumentError(
            f"`points` must hold at least k={k} points (and at least 2) for the statistical "
            f"outlier rule; got {n}")
    from scipy.spatial import cKDTree  # imported here: scipy.spatial is slow to import

    # Open3D counts the point itself among its k neighbours (distance 0), so query k, not k + 1.
    avg = cKDTree(pts).query(pts, k=k)[0].reshape(n, k).mean(axis=1)
    positive = avg > 0
    mean = avg.sum() / n
    std = np.sqrt(np.sum((avg[positive] - mean) ** 2) / (n - 1))
    threshold = mean + ratio * std
    mask = positive & (avg < threshold)
    logger.debug("statistical outliers: kept %d of %d (threshold %.3g m)", mask.sum(), n, threshold)
    return np.asarray(mask)


def height_field_mask(points: Any, k: int = 20, max_slope_deg: float = 60.0) -> NDArray[np.bool_]:
    """Mask of the points whose local surface is flat enough for a height field ``z = f(x, y)``.

    A point is kept when the normal of the plane fitted (PCA) to its ``k`` nearest neighbours (itself
    included, ``k >= 3``) lies within ``max_slope_deg`` (in (0, 90]; 90 keeps all) of ``z``: vertical
    faces and flying pixels, fitted as heights, would make a surface GP ring. 60° keeps a dent's walls,
    with margin for the normals' noise, and removes vertical faces and veils.

    References
    ----------
    Rusu, R. B. (2009). Semantic 3D object maps for everyday manipulation in human living
    environments, §4.1 (normals by PCA of the k nearest neighbours).
    """
    from scipy.spatial import cKDTree

    k = check_int("k", k, minimum=3)
    slope = check_slope_deg("max_slope_deg", max_slope_deg)
    pts = check_points("points", points, min_rows=0)
    n = pts.shape[0]
    if n < k:
        raise InvalidArgumentError(
            f"`points` must hold at least k={k} points for the local plane fits; got {n}")
    if slope == 90.0:
        return np.ones(n, dtype=bool)
    _, idx = cKDTree(pts).query(pts, k=k)
    normal_z = np.empty(n)
    for lo in range(0, n, 65536):  # bounded memory: (chunk, k, 3) neighbourhoods
        nb = pts[idx[lo : lo + 65536]]
        nb = nb - nb.mean(axis=1, keepdims=True)
        cov = np.einsum("nki,nkj->nij", nb, nb)
        _, vec = np.linalg.eigh(cov)
        normal_z[lo : lo + 65536] = vec[:, 2, 0]
    mask = np.abs(normal_z) >= np.cos(np.radians(slope))
    logger.debug("height field: kept %d of %d points (max slope %.0f°)", mask.sum(), n, slope)
    return np.asarray(mask)


def hull_parts(hull_points: Any) -> tuple[Any, ...] | None:
    """The hulls of a tuple or list of 2-D entries (one ``(m_i, 3)`` hull per part), or None."""
    if isinstance(hull_points, (tuple, list)) and hull_points and all(
        np.ndim(part) == 2 for part in hull_points
    ):
        return tuple(hull_points)
    return None


def points_in_hull(points: Any, hull_points: Any, *, tolerance_m: float = HULL_TOLERANCE_M
                   ) -> NDArray[np.bool_]:  # fmt: skip
    """Mask of the points inside (or on) the convex hull of ``hull_points`` ((m, 3) metres, at
    least 4 points not on one plane), or of any hull of a tuple or list of such arrays (one per robot
    part); a point at most ``tolerance_m`` outside every facet plane counts as inside."""
    pts = check_points("points", points, min_rows=0)
    tol = check_positive("tolerance_m", tolerance_m, allow_zero=True)
    parts = hull_parts(hull_points)
    if parts is None:
        return _in_one_hull(pts, check_points("hull_points", hull_points, min_rows=4), tol)
    inside = np.zeros(pts.shape[0], dtype=bool)
    for i, part in enumerate(parts):
        inside |= _in_one_hull(pts, check_points(f"hull_points[{i}]", part, min_rows=4), tol)
    return inside


def _in_one_hull(pts: NDArray[np.float64], verts: NDArray[np.float64], tol: float
                 ) -> NDArray[np.bool_]:  # fmt: skip
    centered = verts - verts.mean(axis=0)
    singular = np.linalg.svd(centered, compute_uv=False)
    # Relative rank test: a hull flatter than 1e-9 of its size has no interior worth the name.
    if singular[2] <= 1e-9 * max(singular[0], np.finfo(float).tiny):
        raise InvalidArgumentError(
            "`hull_points` must span a volume (at least 4 points, not all on one plane or line); "
            f"got {verts.shape[0]} points whose spread is {singular.tolist()} along its axes")
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(verts)
    except QhullError as exc:
        raise InvalidArgumentError(
            f"`hull_points` do not form a 3-D convex hull (Qhull: {str(exc).splitlines()[0]})"
        ) from None
    # Qhull's equations are unit outward normals n and offsets d with n·x + d <= 0 inside.
    normals, offsets = hull.equations[:, :3], hull.equations[:, 3]
    signed = pts @ normals.T + offsets
    return np.asarray(np.all(signed <= tol, axis=1))
