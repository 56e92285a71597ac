from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig, Mapper, Target
from deformap.explore._acquisition import boundary_score, choose_target
from deformap.explore._config import BetaFieldConfig
from deformap.testing import synthetic_poke


def _cells() -> tuple[np.ndarray, np.ndarray]:
    xs = np.linspace(0, 1, 11)
    gx, gy = np.meshgrid(xs, xs)
    cells = np.column_stack([gx.ravel(), gy.ravel()])
    variance = np.exp(-np.sum((cells - [0.8, 0.3]) ** 2, axis=1) / 0.1)
    return cells, variance


def test_stops_when_nothing_exceeds_the_threshold() -> None:
    cells, variance = _cells()
    rng = np.random.default_rng(0)
    for strategy in ("paper", "max-variance"):
        assert choose_target(strategy, cells, variance, 2.0, rng) is None


def test_max_variance_picks_the_peak_and_paper_stays_above_threshold() -> None:
    cells, variance = _cells()
    np.testing.assert_allclose(
        choose_target("max-variance", cells, variance, 0.1, np.random.default_rng(0)), [0.8, 0.3]
    )
    rng = np.random.default_rng(1)
    picks = [choose_target("paper", cells, variance, 0.5, rng) for _ in range(30)]
    for xy in picks:
        i = np.flatnonzero(np.all(cells == xy, axis=1))[0]
        assert variance[i] > 0.5
    assert len({tuple(p) for p in picks}) > 1  # random, not always the peak
    again = [
        choose_target("paper", cells, variance, 0.5, np.random.default_rng(1)) for _ in range(1)
    ]
    np.testing.assert_array_equal(again[0], picks[0])


def test_planned_pokes_its_planners_first_target_and_retired_names_are_refused() -> None:
    cells, variance = _cells()
    first = np.array([0.2, 0.9])
    pick = choose_target("planned", cells, variance, 0.1, np.random.default_rng(0),
                         planner=lambda: first)
    np.testing.assert_allclose(pick, first)
    with pytest.raises(InvalidArgumentError, match="`planner` is required"):
        choose_target("planned", cells, variance, 0.1, np.random.default_rng(0))
    for name in ("greedy", "min-max-variance", "integrated-variance"):
        with pytest.raises(InvalidArgumentError, match="`strategy` must be one of"):
            choose_target(name, cells, variance, 0.1, np.random.default_rng(0))


def test_the_boundary_score_prefers_uncertain_cells_on_an_isopleth() -> None:
    mean = np.array([0.50, 0.50, 0.70, 0.30, 0.55])
    std = np.array([0.10, 0.20, 0.20, 0.20, 0.05])
    levels = np.array([0.35, 0.50])
    score = boundary_score(mean, std, levels)
    np.testing.assert_allclose(score, 1.96 * std - [0.0, 0.0, 0.2, 0.05, 0.05])
    assert int(np.argmax(score)) == 1  # on an isopleth and the least known there
    # one class, no isopleth: the least known cell
    np.testing.assert_array_equal(boundary_score(mean, std, np.array([])), std)


def test_boundary_settings_are_checked() -> None:
    with pytest.raises(InvalidArgumentError, match="`region_labels` must be one of"):
        ExplorationConfig(region_labels="voronoi")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`boundary_pokes` must be an integer >= 0"):
        ExplorationConfig(boundary_pokes=-1)


def _two_materials(config: ExplorationConfig,
                   check: Callable[[Mapper, np.ndarray], None]) -> list[np.ndarray]:
    """Map fake pokes on two materials split at x = 0.30 m (β 0.8 left, 0.5 right) from the
    centre; ``check(mapper, xy)`` before each boundary poke; the boundary pokes' places."""
    mapper = Mapper(Workspace(lower=(0.0, 0.0), upper=(0.6, 0.4)), config)
    rng = np.random.default_rng(0)
    target: Target | None = Target(np.array([0.3, 0.2]), "first")
    boundary = []
    while target is not None:
        xy_t = target.xy
        if target.purpose == "boundary":
            xy = np.array([p.xy for p in mapper.pokes])
            assert np.min(np.linalg.norm(xy - xy_t, axis=1)) >= 0.25 * config.touch.roi_size_m
            check(mapper, xy_t)
            boundary.append(xy_t)
        beta = 0.8 if xy_t[0] < 0.3 else 0.5
        poke = synthetic_poke(xy_t, beta, 0.03, index=len(mapper.pokes))
        added = mapper.add(poke, target=target)
        assert added.record.purpose == target.purpose
        target = mapper.next_target(rng)
    assert mapper.boundary_owed() == 0
    return boundary


def test_boundary_pokes_go_onto_the_isopleth_not_to_the_least_known_place() -> None:
    # at the former floor 0.015: the planner's pokes before the boundary pokes depend on the
    # noise it expects of a new poke (the floor far from the pokes), and at the default floor,
    # the β grid's 0.0029, its design leaves a boundary poke 8 cm or more off the edge
    config = ExplorationConfig(boundary_pokes=2, beta_field=BetaFieldConfig(noise_floor=0.015))

    def on_the_isopleth(mapper: Mapper, xy_t: np.ndarray) -> None:
        mean, var = mapper.beta_field.mean, mapper.beta_field.variance
        level = mapper.regions().levels
        assert level.size == 1
        at = int(np.argmin(np.sum((mapper.grid.cells_xy - xy_t) ** 2, axis=1)))
        # on the isopleth, where the least known reachable cell is not
        assert abs(mean.ravel()[at] - level[0]) < 0.02
        least_known = int(np.argmax(np.where(mapper.grid.target_mask, var.ravel(), -1.0)))
        assert abs(mean.ravel()[least_known] - level[0]) > 0.05

    boundary = _two_materials(config, on_the_isopleth)
    assert len(boundary) == 2
    assert all(abs(t[0] - 0.3) < 0.08 for t in boundary)  # near the true edge
