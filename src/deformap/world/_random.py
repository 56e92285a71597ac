"""Seeded random heterogeneous worlds for benchmarks over many layouts.

The workspace is cut into 2–4 convex regions by straight cuts at random angles through random points
of the largest remaining piece (so regions are rarely axis-aligned), each piece keeping at least
``min_area_fraction`` of the area. Each region gets a hardness drawn uniformly from the foam range
(60–150 N by default, at least ``min_hardness_gap_n`` apart so that regions differ), and with
probability ``p_rigid`` one region is a rigid board instead.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_in_range, check_int
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.world._polygon import clip_halfplane, polygon_area, rectangle
from deformap.world._scenario import Block, Scenario

__all__ = ["random_scenario"]

_PALETTE = ("#f4d35e", "#ee964b", "#c8553d", "#7fb285", "#5b8e7d")


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


def random_scenario(
    rng: np.random.Generator,
    *,
    n_regions: int | None = None,
    hardness_range_n: tuple[float, float] = (60.0, 150.0),
    p_rigid: float = 0.25,
    thickness_m: float = 0.05,
    workspace: Workspace | None = None,
    min_area_fraction: float = 0.15,
    min_hardness_gap_n: float = 20.0,
) -> Scenario:
    """A random heterogeneous scenario.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only source of randomness: the same seed gives the same scenario.
    n_regions : int, optional
        2–4; drawn uniformly when not given.
    hardness_range_n : (2,) float, newtons
        Range of foam hardness.
    p_rigid : float
        Probability that one of the regions is a rigid board.
    """
    if not isinstance(rng, np.random.Generator):
        raise InvalidArgumentError(f"`rng` must be a numpy.random.Generator; got {type(rng)}")
    n = int(rng.integers(2, 5)) if n_regions is None else check_int("n_regions", n_regions)
    if not 2 <= n <= 4:
        raise InvalidArgumentError(f"`n_regions` must be 2, 3 or 4; got {n}")
    h_lo, h_hi = (float(v) for v in hardness_range_n)
    if not 0 < h_lo < h_hi:
        raise InvalidArgumentError(
            f"`hardness_range_n` must be (low, high) with 0 < low < high; got {hardness_range_n}"
        )
    check_in_range("p_rigid", p_rigid, 0.0, 1.0, closed_high=True)
    ws = workspace or Workspace()
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
                "lower `min_area_fraction`"
            )
    pieces.sort(key=lambda p: tuple(p.mean(axis=0)))
    for _ in range(1000):
        hardness = rng.uniform(h_lo, h_hi, size=n)
        if n < 2 or np.min(np.diff(np.sort(hardness))) >= min_hardness_gap_n:
            break
    rigid_index = int(rng.integers(n)) if rng.uniform() < p_rigid else -1
    blocks = []
    for k, poly in enumerate(pieces):
        if k == rigid_index:
            blocks.append(Block(name=f"region-{k}-rigid", polygon=poly, rigid=True,
                                thickness_m=thickness_m, color="#6b4f3a"))
        else:
            h = round(float(hardness[k]), 1)
            blocks.append(Block(name=f"region-{k}-{h:g}N", polygon=poly, hardness_n=h,
                                thickness_m=thickness_m, color=_PALETTE[k % len(_PALETTE)]))
    return Scenario(name="random", blocks=tuple(blocks), workspace=ws,
                    description=f"random world with {n} regions")
