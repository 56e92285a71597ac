"""Small exact helpers for polygons in the table plane: ``(k, 2)`` float arrays of vertices in
metres, counter-clockwise, the first vertex not repeated at the end.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["clip_halfplane", "convex_overlap_area", "is_simple", "overlap_area",
           "points_in_polygon", "polygon_area", "rectangle", "triangulate"]

_EPS = 1e-12


def rectangle(x0: float, y0: float, x1: float, y1: float) -> NDArray[np.float64]:
    """Counter-clockwise ``(4, 2)`` vertices of the rectangle ``[x0, x1] × [y0, y1]``."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def polygon_area(poly: NDArray[np.float64]) -> float:
    """Signed area (shoelace), positive for counter-clockwise vertices, m²."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def points_in_polygon(points: NDArray[np.float64], poly: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Mask of ``(n, 2)`` points inside the polygon (even-odd rule); a point on an edge may fall
    either way."""
    px, py = points[:, 0][:, None], points[:, 1][:, None]
    x0, y0 = poly[:, 0][None, :], poly[:, 1][None, :]
    x1, y1 = np.roll(poly[:, 0], -1)[None, :], np.roll(poly[:, 1], -1)[None, :]
    straddles = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    crossings = straddles & (px < x_cross)
    return np.asarray(np.count_nonzero(crossings, axis=1) % 2 == 1)


def clip_halfplane(poly: NDArray[np.float64], point: NDArray[np.float64],
                   normal: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(k, 2)`` part of a convex polygon where ``(p - point) · normal <= 0`` (Sutherland–Hodgman
    step); ``k < 3`` when nothing of area is left."""
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


def _cross(o: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
           ) -> NDArray[np.float64]:
    """z of ``(a - o) × (b - o)``, broadcast over leading axes."""
    return np.asarray((a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1])
                      - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0]))


def is_simple(poly: NDArray[np.float64]) -> bool:
    """True when no two edges of the polygon meet except neighbours at their shared vertex
    (every pair of non-adjacent edges tested by orientation signs, collinear overlaps touching)."""
    k = len(poly)
    if k < 3:
        return False
    a, b = poly, np.roll(poly, -1, axis=0)
    if np.any(np.all(np.abs(b - a) <= _EPS, axis=1)):
        return False  # a repeated vertex
    i, j = np.triu_indices(k, k=2)
    keep = ~((i == 0) & (j == k - 1))  # the last edge and the first share vertex 0
    i, j = i[keep], j[keep]
    p1, p2, q1, q2 = a[i], b[i], a[j], b[j]
    d1, d2 = _cross(q1, q2, p1), _cross(q1, q2, p2)
    d3, d4 = _cross(p1, p2, q1), _cross(p1, p2, q2)
    proper = (d1 * d2 < -_EPS**2) & (d3 * d4 < -_EPS**2)

    def on_segment(o: NDArray, s: NDArray, e: NDArray, d: NDArray) -> NDArray[np.bool_]:
        lo, hi = np.minimum(s, e) - _EPS, np.maximum(s, e) + _EPS
        return np.asarray((np.abs(d) <= _EPS) & np.all((o >= lo) & (o <= hi), axis=-1))

    touch = (on_segment(p1, q1, q2, d1) | on_segment(p2, q1, q2, d2)
             | on_segment(q1, p1, p2, d3) | on_segment(q2, p1, p2, d4))
    return not bool(np.any(proper | touch))


def triangulate(poly: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(k - 2, 3, 2)`` counter-clockwise triangles that tile a simple counter-clockwise polygon,
    by ear clipping (Meisters 1975)."""
    idx = list(range(len(poly)))
    out: list[NDArray[np.float64]] = []
    while len(idx) > 3:
        n = len(idx)
        for m in range(n):
            ia, ib, ic = idx[m - 1], idx[m], idx[(m + 1) % n]
            a, b, c = poly[ia], poly[ib], poly[ic]
            if float(_cross(a, b, c)) <= _EPS**2:
                continue  # reflex or flat: not an ear
            others = poly[[i for i in idx if i not in (ia, ib, ic)]]
            inside = ((_cross(a, b, others) >= -_EPS**2) & (_cross(b, c, others) >= -_EPS**2)
                      & (_cross(c, a, others) >= -_EPS**2))
            if not np.any(inside):
                out.append(np.array([a, b, c]))
                del idx[m]
                break
        else:  # only for a polygon that is not simple (callers check first) or degenerate
            raise ValueError("triangulate: no ear found; the polygon is not simple")
    out.append(poly[idx])
    return np.array(out, dtype=float).reshape(-1, 3, 2)


def _triangles_overlap(ta: NDArray[np.float64], tb: NDArray[np.float64]) -> float:
    """Total overlap of two sets of triangles (each set disjoint), m²."""
    total = 0.0
    lo_a, hi_a = ta.min(axis=1), ta.max(axis=1)
    lo_b, hi_b = tb.min(axis=1), tb.max(axis=1)
    hits = np.all((lo_a[:, None] < hi_b[None]) & (lo_b[None] < hi_a[:, None]), axis=2)
    for i, j in zip(*np.nonzero(hits), strict=True):
        total += convex_overlap_area(ta[i], tb[j])
    return total


def overlap_area(a: NDArray[np.float64], b: NDArray[np.float64],
                 holes_a: Sequence[NDArray[np.float64]] = (),
                 holes_b: Sequence[NDArray[np.float64]] = ()) -> float:
    """Area shared by two footprints, each a simple counter-clockwise polygon less its holes, m²:
    ``|A₀ ∩ B₀| − Σ|hᵢ ∩ B₀| − Σ|A₀ ∩ gⱼ| + ΣΣ|hᵢ ∩ gⱼ|`` over the outer polygons and their holes
    (inside them and apart), each term from the overlaps of their triangles."""
    tri = [triangulate(p) for p in (a, *holes_a)], [triangulate(p) for p in (b, *holes_b)]
    total = 0.0
    for i, ta in enumerate(tri[0]):
        for j, tb in enumerate(tri[1]):
            sign = (-1.0 if i else 1.0) * (-1.0 if j else 1.0)
            total += sign * _triangles_overlap(ta, tb)
    return max(0.0, total)
