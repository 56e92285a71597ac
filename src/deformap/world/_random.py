"""Seeded random heterogeneous worlds for benchmarks over many layouts.

A layout family (:mod:`deformap.world._layouts`) cuts the workspace into pieces, each made of one
of a few materials. Each material gets a hardness drawn uniformly from the foam range, at least
``min_hardness_gap_n`` apart, and with probability ``p_rigid`` one material is a rigid board
instead. An appearance family (:mod:`deformap.world._paint`) paints the pieces, from a generator
spawned from the one given, so that the layout and the materials are the same whatever the family.
"""

from __future__ import annotations

import numpy as np

from deformap._validation import check_in_range, check_int
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.world._layouts import LAYOUT_FAMILIES, Piece, cut_pieces, layout_pieces
from deformap.world._paint import APPEARANCE_FAMILIES, paint_pieces
from deformap.world._scenario import Block, Scenario

__all__ = ["random_scenario"]

_PALETTE = ("#f4d35e", "#ee964b", "#c8553d", "#7fb285", "#5b8e7d")
_RIGID_COLOR = "#6b4f3a"


def _hardnesses(rng: np.random.Generator, n: int, low: float, high: float, gap: float
                ) -> np.ndarray:
    for _ in range(1000):
        hardness = rng.uniform(low, high, size=n)
        if n < 2 or np.min(np.diff(np.sort(hardness))) >= gap:
            break
    return hardness


def random_scenario(rng: np.random.Generator, *, family: str = "cuts", n_regions: int | None = None,
                    hardness_range_n: tuple[float, float] = (60.0, 150.0), p_rigid: float = 0.25,
                    thickness_m: float = 0.05, workspace: Workspace | None = None,
                    min_area_fraction: float = 0.15, min_hardness_gap_n: float = 20.0,
                    appearance: str = "plain") -> Scenario:
    """A random heterogeneous scenario (module docstring), the same for the same ``rng`` state.

    ``family`` is one of :data:`deformap.world.LAYOUT_FAMILIES`; ``n_regions`` (2–4, drawn when
    not given) and ``min_area_fraction`` (the smallest piece's share of the area) are for
    ``cuts`` only. ``appearance`` is one of :data:`deformap.world.APPEARANCE_FAMILIES`; the
    default, ``plain``, draws nothing.
    """
    if not isinstance(rng, np.random.Generator):
        raise InvalidArgumentError(f"`rng` must be a numpy.random.Generator; got {type(rng)}")
    if family not in LAYOUT_FAMILIES:
        raise InvalidArgumentError(
            f"`family` must be one of {list(LAYOUT_FAMILIES)}; got {family!r}")
    if n_regions is not None and family != "cuts":
        raise InvalidArgumentError(
            f"`n_regions` is for the 'cuts' family only; got {n_regions} with {family!r}")
    h_lo, h_hi = (float(v) for v in hardness_range_n)
    if not 0 < h_lo < h_hi:
        raise InvalidArgumentError(
            f"`hardness_range_n` must be (low, high) with 0 < low < high; got {hardness_range_n}")
    check_in_range("p_rigid", p_rigid, 0.0, 1.0)
    if appearance not in APPEARANCE_FAMILIES:
        raise InvalidArgumentError(
            f"`appearance` must be one of {list(APPEARANCE_FAMILIES)}; got {appearance!r}")
    ws = workspace or Workspace()
    if family == "cuts":
        n = int(rng.integers(2, 5)) if n_regions is None else check_int("n_regions", n_regions)
        if not 2 <= n <= 4:
            raise InvalidArgumentError(f"`n_regions` must be 2, 3 or 4; got {n}")
        pieces = [Piece(p, k) for k, p in enumerate(cut_pieces(ws, rng, n, min_area_fraction))]
    else:
        pieces = layout_pieces(family, ws, rng)
    n_materials = 1 + max(p.material for p in pieces)
    if n_materials > 1 and (h_hi - h_lo) < min_hardness_gap_n * (n_materials - 1):
        raise InvalidArgumentError(
            f"`hardness_range_n` {hardness_range_n} cannot hold {n_materials} hardnesses "
            f"{min_hardness_gap_n:g} N apart; widen it or lower `min_hardness_gap_n`")
    hardness = _hardnesses(rng, n_materials, h_lo, h_hi, min_hardness_gap_n)
    rigid_material = int(rng.integers(n_materials)) if rng.uniform() < p_rigid else -1
    looks = paint_pieces(appearance, pieces, ws, rng.spawn(1)[0] if appearance != "plain" else rng)
    blocks = []
    for k, (piece, look) in enumerate(zip(pieces, looks, strict=True)):
        m = piece.material
        if m == rigid_material:
            blocks.append(Block(name=f"region-{k}-rigid", polygon=piece.polygon,
                                holes=piece.holes, rigid=True, thickness_m=thickness_m,
                                color=_RIGID_COLOR, appearance=look))
        else:
            h = round(float(hardness[m]), 1)
            blocks.append(Block(name=f"region-{k}-{h:g}N", polygon=piece.polygon,
                                holes=piece.holes, hardness_n=h, thickness_m=thickness_m,
                                color=_PALETTE[m % len(_PALETTE)], appearance=look))
    painted = "" if appearance == "plain" else f", painted {appearance}"
    return Scenario(name=f"random-{family}", blocks=tuple(blocks), workspace=ws,
                    description=f"random {family} world: {len(pieces)} pieces of "
                                f"{n_materials} materials{painted}")
