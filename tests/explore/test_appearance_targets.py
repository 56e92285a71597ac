"""Targets under the appearance prior: once the variance is under T_h, where the pokes make the
looks the likelier hypothesis, no dent is placed across an edge between two looks (it would read
between two materials); where they do not, and above T_h, every place may be poked."""

from __future__ import annotations

import dataclasses

import numpy as np

from deformap.cloud import PointCloud
from deformap.environment import Workspace
from deformap.explore import BetaField, BetaFieldConfig, ExplorationConfig, MapGrid, PokeSet
from deformap.explore._appearance import AppearanceImage, build_appearance
from deformap.explore._appearance_prior import AppearancePrior
from deformap.explore._targets import BOUNDARY_SPACING_ROI, choose_next, footprint_inside

XS = np.arange(0.0025, 0.3, 0.005)
YS = np.arange(0.0025, 0.2, 0.005)
EDGE_X = 0.15
RED, BLUE = (0.8, 0.2, 0.2), (0.2, 0.3, 0.8)
# a high T_h: the variance rule is met, so the next poke is a boundary poke
CONFIG = ExplorationConfig(field="beta", threshold=0.5, boundary_pokes=1)
RADIUS = BOUNDARY_SPACING_ROI * CONFIG.touch.roi_size_m / 2
XY = [(0.06, 0.06), (0.07, 0.14), (0.23, 0.06), (0.24, 0.14)]


def _prior() -> AppearancePrior:
    """An image red left of ``EDGE_X`` and blue beyond (four points a cell, a camera's noise)."""
    gx, gy = np.meshgrid(np.arange(0.00125, 0.3, 0.0025), np.arange(0.00125, 0.2, 0.0025))
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    cols = np.where(pts[:, :1] < EDGE_X, np.array(RED), np.array(BLUE))
    cols = np.clip(cols + 0.01 * np.random.default_rng(0).standard_normal(cols.shape), 0.0, 1.0)
    image = build_appearance(PointCloud(pts, cols), XS, YS, np.zeros((YS.size, XS.size)),
                             BOUNDARY_SPACING_ROI * CONFIG.touch.roi_size_m)  # fmt: skip
    assert isinstance(image, AppearanceImage)
    return AppearancePrior(image, XS, YS)


def _next(values, prior: AppearancePrior | None) -> tuple[np.ndarray, float]:
    """The boundary poke after pokes at ``XY`` reading ``values``, and P(w > 0) (0 blind)."""
    grid = MapGrid.build(Workspace(lower=(0.0, 0.0), upper=(0.3, 0.2)), CONFIG)
    assert np.allclose(grid.xs, XS) and np.allclose(grid.ys, YS)
    pokes = PokeSet(np.array(XY), np.asarray(values, float), np.full(len(XY), 0.02))
    field = BetaField(pokes, XS, YS, BetaFieldConfig(length_scale_m=0.05)).with_prior(prior)
    target = choose_next(grid, field, CONFIG, np.random.default_rng(0), boundary_owed=1)
    assert target is not None and target.purpose == "boundary"
    looked = 0.0
    if field.models is not None:
        w, p = field.models.posterior.weight_distribution()
        looked = float(p[w > 0].sum())
    return target.xy, looked


def test_a_footprint_is_inside_its_segment_only_a_radius_from_every_other_segment() -> None:
    spacing = 0.005
    looks = np.where(XS[None, :] < EDGE_X, 0, 1) * np.ones((YS.size, 1), dtype=np.int64)
    inside = footprint_inside(looks, spacing, 0.015)
    to_edge = np.abs(XS - EDGE_X)  # the edge lies between two cells
    assert np.all(inside[:, to_edge >= 0.015]) and not np.any(inside[:, to_edge < 0.015])
    # the workspace's border is no edge, and one segment has no edge at all
    assert inside[0, 0] and inside[-1, -1]
    assert footprint_inside(np.zeros((4, 5), dtype=np.int64), spacing, 0.015).all()
    # two segments of one look are one: only the edge to the third, unlike look counts
    three = np.where(XS[None, :] < 0.1, 0, looks + 1) * np.ones((YS.size, 1), dtype=np.int64)
    alike = np.array([[True, True, False], [True, True, False], [False, False, True]])
    assert not footprint_inside(three, spacing, 0.015)[:, np.abs(XS - 0.1) < 0.015].all()
    assert np.array_equal(footprint_inside(three, spacing, 0.015, alike), inside)


def test_where_the_pokes_favour_the_looks_the_boundary_poke_keeps_its_dent_off_the_edge() -> None:
    prior = _prior()
    values = [0.2, 0.21, 0.8, 0.79]
    blind_xy, _ = _next(values, None)
    # the blind map's least certain boundary is the classes' edge, within a dent of the looks'
    assert abs(blind_xy[0] - EDGE_X) < RADIUS
    xy, looked = _next(values, prior)
    assert looked > 0.5
    assert abs(xy[0] - EDGE_X) >= RADIUS


def test_where_the_pokes_contradict_the_looks_every_place_may_be_poked() -> None:
    # one look, two materials: the blind map is the likelier, and its least certain boundary,
    # across the looks' edge, is open to the boundary poke
    prior = _prior()
    values = [0.2, 0.8, 0.2, 0.8]
    xy, looked = _next(values, prior)
    assert looked <= 0.5
    blind_xy, _ = _next(values, None)
    assert np.allclose(xy, blind_xy, atol=0.005)


def test_above_the_threshold_the_targets_are_left_as_the_strategy_chose_them() -> None:
    # max-variance under the prior: the least known place is the looks' edge, where the model
    # average's two hypotheses disagree most; above T_h it is poked as chosen
    config = dataclasses.replace(CONFIG, threshold=0.001, strategy="max-variance")
    grid = MapGrid.build(Workspace(lower=(0.0, 0.0), upper=(0.3, 0.2)), config)
    xy = np.array([(0.083, 0.115), (0.055, 0.145), (0.063, 0.085), (0.243, 0.126)])
    pokes = PokeSet(xy, np.array([0.2, 0.21, 0.19, 0.8]), np.full(4, 0.02))
    field = BetaField(pokes, XS, YS, BetaFieldConfig(length_scale_m=0.05)).with_prior(_prior())
    assert field.models is not None
    w, p = field.models.posterior.weight_distribution()
    assert p[w > 0].sum() > 0.5
    target = choose_next(grid, field, config, np.random.default_rng(0), boundary_owed=1)
    assert target is not None and target.purpose == "variance"
    assert abs(target.xy[0] - EDGE_X) < RADIUS
