"""Seeded layout families: how a rectangular workspace is cut into the footprints of pieces.

Each family draws from the generator it is given :class:`Piece` footprints that tile the
workspace, each with the index of its material:

* ``cuts``: 2–4 convex pieces by straight cuts at random angles through the largest remaining
  piece, each keeping at least ``min_area_fraction`` of the area.
* ``insert``: a disc or an ellipse of one material inside another (the outer piece has it as a hole).
* ``l-shape``: an L-shaped piece along two sides meeting at a random corner; the rest a rectangle.
* ``checker``: four blocks about a random point near the centre, two materials alternating.
* ``stripes``: 3–5 parallel stripes at a random angle, two or three materials in turn.
* ``non-convex``: a U open toward the far side, or a star-shaped blob, and the rest around it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.world._polygon import clip_halfplane, polygon_area, rectangle

__all__ = ["LAYOUT_FAMILIES", "LayoutFamily", "Piece", "layout_pieces"]

LayoutFamily = Literal["cuts", "insert", "l-shape", "checker", "stripes", "non-convex"]
LAYOUT_FAMILIES: tuple[str, ...] = get_args(LayoutFamily)

#: Vertices of an ellipse's or a blob's outline: its area is within 0.7 % of the curve's.
_OUTLINE_VERTICES = 48


@dataclass(frozen=True)
class Piece:
    """One footprint of a layout: ``polygon`` less its ``holes`` (``(k, 2)``, metres), made of
    material ``material`` (0, 1, …)."""

    polygon: NDArray[np.float64]
    material: int
    holes: tuple[NDArray[np.float64], ...] = ()


def _cut(poly: NDArray[np.float64], rng: np.random.Generator, min_area: float
         ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    point = lo + rng.uniform(0.3, 0.7, size=2) * (hi - lo)
    angle = rng.uniform(0.0, np.pi)
    normal = np.array([np.cos(angle), np.sin(angle)])
    a, b = clip_halfplane(poly, point, normal), clip_halfplane(poly, point, -normal)
    if len(a) < 3 or len(b) < 3 or min(polygon_area(a), polygon_area(b)) < min_area:
        return None
    return a, b


def cut_pieces(ws: Workspace, rng: np.random.Generator, n: int, min_area_fraction: float
               ) -> list[NDArray[np.float64]]:
    """``n`` convex pieces by straight cuts (the ``cuts`` family), sorted by their centroid."""
    pieces = [rectangle(*ws.lower, *ws.upper)]
    min_area = min_area_fraction * polygon_area(pieces[0])
    while len(pieces) < n:
        pieces.sort(key=polygon_area)
        for _ in range(200):
            cut = _cut(pieces[-1], rng, min_area)
            if cut is not None:
                pieces = [*pieces[:-1], *cut]
                break
        else:
            raise InvalidArgumentError(
                f"could not cut {n} regions of at least {min_area_fraction:.0%} of the area; "
                "lower `min_area_fraction`")
    pieces.sort(key=lambda p: tuple(p.mean(axis=0)))
    return pieces


def _unit(ws: Workspace, u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points given in the workspace's unit square, in metres."""
    lo, hi = np.asarray(ws.lower, float), np.asarray(ws.upper, float)
    return lo + np.asarray(u, float) * (hi - lo)


def _flip(u: NDArray[np.float64], flips: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Mirror unit-square points in x and/or y (a random corner or side for a layout)."""
    return np.where(flips, 1.0 - u, u)


def _insert(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    size = np.asarray(ws.size, float)
    short = float(size.min())
    a, b = rng.uniform(0.18, 0.34) * short, rng.uniform(0.18, 0.34) * short
    angle = rng.uniform(0.0, np.pi)
    reach = np.hypot(a * np.cos(angle), b * np.sin(angle)), np.hypot(a * np.sin(angle),
                                                                      b * np.cos(angle))
    lo = np.asarray(ws.lower, float) + np.array(reach) + 0.05 * short
    hi = np.asarray(ws.upper, float) - np.array(reach) - 0.05 * short
    centre = rng.uniform(lo, np.maximum(lo, hi))
    t = np.linspace(0.0, 2 * np.pi, _OUTLINE_VERTICES, endpoint=False)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    ellipse = centre + np.column_stack([a * np.cos(t), b * np.sin(t)]) @ rot.T
    return [Piece(rectangle(*ws.lower, *ws.upper), 0, holes=(ellipse,)), Piece(ellipse, 1)]


def _l_shape(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    wx, wy = rng.uniform(0.25, 0.45, size=2)  # the L's arms' widths, share of each side
    flips = rng.uniform(size=2) < 0.5
    ell = np.array([[0, 0], [1, 0], [1, wy], [wx, wy], [wx, 1], [0, 1]], float)
    rest = np.array([[wx, wy], [1, wy], [1, 1], [wx, 1]], float)
    return [Piece(_unit(ws, _flip(ell, flips)), 0), Piece(_unit(ws, _flip(rest, flips)), 1)]


def _checker(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    cx, cy = rng.uniform(0.35, 0.65, size=2)
    out = []
    for i, (x0, x1) in enumerate(((0.0, cx), (cx, 1.0))):
        for j, (y0, y1) in enumerate(((0.0, cy), (cy, 1.0))):
            out.append(Piece(_unit(ws, rectangle(x0, y0, x1, y1)), (i + j) % 2))
    return out


def _stripes(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    n, n_materials = int(rng.integers(3, 6)), int(rng.integers(2, 4))
    angle = rng.uniform(0.0, np.pi)
    normal = np.array([np.cos(angle), np.sin(angle)])
    rect = rectangle(*ws.lower, *ws.upper)
    along = rect @ normal
    edges = np.linspace(along.min(), along.max(), n + 1)
    out = []
    for k in range(n):
        piece = clip_halfplane(rect, edges[k + 1] * normal, normal)
        piece = clip_halfplane(piece, edges[k] * normal, -normal)
        out.append(Piece(piece, k % n_materials))
    return out


def _u_shape(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    width = rng.uniform(0.4, 0.6)  # shares of the workspace's sides, all of them
    a = rng.uniform(0.05, 0.95 - width)
    b = a + width
    c = rng.uniform(0.55, 0.8)  # height of the U
    t = rng.uniform(0.2, 0.3) * (b - a)  # thickness of its arms
    d = rng.uniform(0.25, 0.45) * c  # thickness of its base
    u = np.array([[a, 0], [b, 0], [b, c], [b - t, c], [b - t, d], [a + t, d], [a + t, c],
                  [a, c]], float)
    rest = np.array([[0, 0], [a, 0], [a, c], [a + t, c], [a + t, d], [b - t, d], [b - t, c],
                     [b, c], [b, 0], [1, 0], [1, 1], [0, 1]], float)
    flips = rng.uniform(size=2) < 0.5
    return [Piece(_unit(ws, _flip(u, flips)), 0), Piece(_unit(ws, _flip(rest, flips)), 1)]


def _blob(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    short = float(min(ws.size))
    r0 = rng.uniform(0.25, 0.35) * short
    lobes, depth, phase = int(rng.integers(3, 6)), rng.uniform(0.25, 0.4), rng.uniform(0, 2 * np.pi)
    t = np.linspace(0.0, 2 * np.pi, _OUTLINE_VERTICES, endpoint=False)
    r = r0 * (1.0 + depth * np.sin(lobes * t + phase))
    margin = r0 * (1.0 + depth) + 0.05 * short
    lo, hi = np.asarray(ws.lower, float) + margin, np.asarray(ws.upper, float) - margin
    centre = rng.uniform(lo, np.maximum(lo, hi))
    star = centre + np.column_stack([r * np.cos(t), r * np.sin(t)])
    return [Piece(rectangle(*ws.lower, *ws.upper), 0, holes=(star,)), Piece(star, 1)]


def _non_convex(ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    return _u_shape(ws, rng) if rng.uniform() < 0.5 else _blob(ws, rng)


_FAMILIES: dict[str, Callable[[Workspace, np.random.Generator], list[Piece]]] = {
    "insert": _insert, "l-shape": _l_shape, "checker": _checker, "stripes": _stripes,
    "non-convex": _non_convex,
}


def _clean(poly: NDArray[np.float64]) -> NDArray[np.float64]:
    """The polygon without repeated consecutive vertices (a clip through a vertex repeats it)."""
    step = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
    return poly[step > 1e-9]


def layout_pieces(family: str, ws: Workspace, rng: np.random.Generator) -> list[Piece]:
    """The pieces of one layout of ``family`` over ``ws``: any of :data:`LAYOUT_FAMILIES` but
    ``cuts`` (:func:`cut_pieces`)."""
    if family not in _FAMILIES:
        raise InvalidArgumentError(f"`family` must be one of {list(_FAMILIES)}; got {family!r}")
    pieces = _FAMILIES[family](ws, rng)
    return [Piece(_clean(p.polygon), p.material, tuple(_clean(h) for h in p.holes)) for p in pieces]
