"""Small exact helpers for convex polygons in the table plane (no shapely needed).

Polygons are ``(k, 2)`` float arrays of vertices in metres, counter-clockwise, without repeating the
first vertex at the end.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "clip_halfplane",
    "convex_overlap_area",
    "is_convex",
    "points_in_polygon",
    "polygon_area",
    "rectangle",
]

_EPS = 1e-12


def rectangle(x0: float, y0: float, x1: float, y1: float) -> NDArray[np.float64]:
    """Counter-clockwise ``(4, 2)`` vertices of the rectangle ``[x0, x1] × [y0, y1]``."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def polygon_area(poly: NDArray[np.float64]) -> float:
    """Signed area (shoelace), positive for counter-clockwise vertices, m²."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def is_convex(poly: NDArray[np.float64]) -> bool:
    """True when the counter-clockwise polygon turns left (or goes straight) at every vertex."""
    e = np.roll(poly, -1, axis=0) - poly
    cross = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
    return bool(np.all(cross >= -_EPS))


def points_in_polygon(points: NDArray[np.float64], poly: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Mask of ``(n, 2)`` points inside the polygon (even-odd rule; works for non-convex ones).

    A point on an edge may fall either way; callers that need a unique owner (ground-truth labels)
    take the first block that claims a point.
    """
    px, py = points[:, 0][:, None], points[:, 1][:, None]
    x0, y0 = poly[:, 0][None, :], poly[:, 1][None, :]
    x1, y1 = np.roll(poly[:, 0], -1)[None, :], np.roll(poly[:, 1], -1)[None, :]
    straddles = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    crossings = straddles & (px < x_cross)
    return np.asarray(np.count_nonzero(crossings, axis=1) % 2 == 1)


def clip_halfplane(
    poly: NDArray[np.float64], point: NDArray[np.float64], normal: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Part of a convex polygon where ``(p - point) · normal <= 0`` (Sutherland–Hodgman step).

    Returns a ``(k, 2)`` array, possibly with ``k < 3`` when nothing of area is left.
    """
    d = (poly - point) @ normal
    out: list[NDArray[np.float64]] = []
    n = len(poly)
    for i in range(n):
        j = (i + 1) % n
        if d[i] <= 0:
            out.append(poly[i])
        if (d[i] < 0 < d[j]) or (d[j] < 0 < d[i]):
            t = d[i] / (d[i] - d[j])
            out.append(poly[i] + t * (poly[j] - poly[i]))
    return np.array(out, dtype=float).reshape(-1, 2)


def convex_overlap_area(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Area of the intersection of two convex counter-clockwise polygons, m²."""
    clipped = a
    for i in range(len(b)):
        edge = b[(i + 1) % len(b)] - b[i]
        outward = np.array([edge[1], -edge[0]])
        clipped = clip_halfplane(clipped, b[i], outward)
        if len(clipped) < 3:
            return 0.0
    return max(0.0, polygon_area(clipped))
