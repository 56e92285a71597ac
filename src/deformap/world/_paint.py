"""Seeded appearance families: how the pieces of a random layout are painted.

Each family gives every piece of a layout (:class:`~deformap.world._layouts.Piece`) an
:class:`~deformap.world._appearance.Appearance`:

* ``plain``: one look everywhere (the default grey; nothing drawn).
* ``informative``: each material its own look (its own colour, a texture drawn for it).
* ``textured``: materials differ by texture only, their colours within a few percent of one mean.
* ``shared``: as ``informative``, but two materials share one look.
* ``split``: as ``informative``, but the largest piece is painted in two looks, split by a line
  through it: a look boundary that is no material boundary.
* ``misleading``: two looks split by one line across the workspace, whatever the materials.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Literal, get_args

import numpy as np

from deformap.environment import Workspace
from deformap.world._appearance import Appearance, Split, parse_color
from deformap.world._layouts import Piece
from deformap.world._polygon import points_in_polygon, polygon_area

__all__ = ["APPEARANCE_FAMILIES", "AppearanceFamily", "paint_pieces"]

AppearanceFamily = Literal["plain", "informative", "textured", "shared", "split", "misleading"]
APPEARANCE_FAMILIES: tuple[str, ...] = get_args(AppearanceFamily)

# eight colours far apart in hue and lightness, so that no two looks of a world are mistaken
_COLOURS = ("#e6c229", "#d1495b", "#2e86ab", "#66a182", "#8d6a9f", "#f18f01", "#3b3b58", "#c5d86d")
# six textures that tell apart at a camera's millimetre pixels
_TEXTURES = (
    Appearance(texture="plain"),
    Appearance(texture="noise", scale_m=0.004, amplitude=0.2),
    Appearance(texture="noise", scale_m=0.02, amplitude=0.25),
    Appearance(texture="stripes", scale_m=0.012, amplitude=0.25),
    Appearance(texture="photo", photo="brick", scale_m=0.15, amplitude=0.35),
    Appearance(texture="photo", photo="gravel", scale_m=0.1, amplitude=0.35),
)


def _looks(rng: np.random.Generator, n: int) -> list[Appearance]:
    """``n`` looks with distinct colours, each with a texture drawn for it."""
    colours = rng.permutation(len(_COLOURS))[:n]
    textures = rng.integers(len(_TEXTURES), size=n)
    return [replace(_TEXTURES[t], color=parse_color(_COLOURS[c]), seed=int(rng.integers(2**31)),
                    angle_deg=float(rng.uniform(0.0, 180.0)))
            for c, t in zip(colours, textures, strict=True)]


def _textured(rng: np.random.Generator, n: int) -> list[Appearance]:
    base = np.array(parse_color(_COLOURS[int(rng.integers(len(_COLOURS)))]))
    textures = rng.permutation(len(_TEXTURES))[:n]
    out = []
    for t in textures:
        r, g, b = (float(c) for c in np.clip(base + rng.uniform(-0.03, 0.03, size=3), 0.0, 1.0))
        out.append(replace(_TEXTURES[t], color=(r, g, b),
                           seed=int(rng.integers(2**31)), angle_deg=float(rng.uniform(0, 180))))
    return out


def _inside_point(piece: Piece, rng: np.random.Generator) -> tuple[float, float]:
    """A point of ``piece``, drawn near the middle of its bounding box where it can."""
    lo, hi = piece.polygon.min(axis=0), piece.polygon.max(axis=0)
    share = np.concatenate([rng.uniform(0.3, 0.7, size=(64, 2)),
                            rng.uniform(0.05, 0.95, size=(256, 2))])
    tries = lo + share * (hi - lo)
    inside = points_in_polygon(tries, piece.polygon)
    for hole in piece.holes:
        inside &= ~points_in_polygon(tries, hole)
    point = tries[np.argmax(inside)] if np.any(inside) else piece.polygon.mean(axis=0)
    return float(point[0]), float(point[1])


def paint_pieces(family: str, pieces: list[Piece], ws: Workspace, rng: np.random.Generator
                 ) -> list[Appearance | None]:
    """The look of each piece under ``family`` (module docstring), drawn from ``rng``."""
    n_materials = 1 + max(p.material for p in pieces)
    if family == "plain":
        return [None] * len(pieces)
    if family == "misleading":
        first, second = _looks(rng, 2)
        lo, hi = np.asarray(ws.lower, float), np.asarray(ws.upper, float)
        through = lo + rng.uniform(0.3, 0.7, size=2) * (hi - lo)
        split = Split(through=(float(through[0]), float(through[1])),
                      normal_deg=float(rng.uniform(0.0, 360.0)), look=second)
        return [replace(first, split=split)] * len(pieces)
    if family == "textured":
        by_material = _textured(rng, n_materials)
    else:
        by_material = _looks(rng, n_materials + 1)  # one spare look for `split`
    if family == "shared" and n_materials >= 2:
        a, b = rng.choice(n_materials, size=2, replace=False)
        by_material[int(b)] = by_material[int(a)]
    looks: list[Appearance | None] = [by_material[p.material] for p in pieces]
    if family == "split":
        k = int(np.argmax([abs(polygon_area(p.polygon)) - sum(abs(polygon_area(h))
                                                               for h in p.holes)
                           for p in pieces]))
        split = Split(through=_inside_point(pieces[k], rng),
                      normal_deg=float(rng.uniform(0.0, 360.0)), look=by_material[-1])
        looks[k] = replace(by_material[pieces[k].material], split=split)
    return looks
