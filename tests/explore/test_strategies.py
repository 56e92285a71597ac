"""The strategies of issue 16, item 4: ``level-set`` (straddle on the cut levels) and
``integrated-variance`` (integrated posterior variance reduction), on hand-built β-fields."""

from __future__ import annotations

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig, Mapper, check_exploration_budget
from deformap.explore._acquisition import boundary_score, choose_target
from deformap.explore._targets import BOUNDARY_SPACING_ROI, expected_noise
from deformap.testing import synthetic_poke

WORKSPACE = Workspace(lower=(0.0, 0.0), upper=(0.6, 0.4))


def _mapper(strategy: str, pokes: list[tuple[tuple[float, float], float]]) -> Mapper:
    """A β-field mapper with ``pokes`` (place, β) at the noise floor."""
    mapper = Mapper(WORKSPACE, ExplorationConfig(strategy=strategy, field="beta"))  # type: ignore[arg-type]
    for i, (xy, beta) in enumerate(pokes):
        mapper.add(synthetic_poke(np.array(xy), beta, 0.03, index=i))
    return mapper


def _cell(mapper: Mapper, xy: np.ndarray) -> int:
    return int(np.argmin(np.sum((mapper.grid.cells_xy - xy) ** 2, axis=1)))


# two materials split at x = 0.30 m: β 0.8 on the left, 0.5 on the right
TWO_SIDES = [((0.1, 0.2), 0.8), ((0.2, 0.3), 0.8), ((0.45, 0.2), 0.5), ((0.5, 0.3), 0.5)]


def test_level_set_pokes_where_the_cut_is_least_certain() -> None:
    mapper = _mapper("level-set", TWO_SIDES)
    target = mapper.next_target(np.random.default_rng(0))
    assert target is not None and target.purpose == "variance"
    field, cells = mapper.beta_field, mapper.grid.cells_xy
    mean, std = field.mean.ravel(), np.sqrt(field.variance.ravel())
    levels = mapper.regions().levels
    assert levels.size == 1  # two classes, one isopleth
    # the rule: the largest straddle score among reachable cells a quarter ROI from every poke
    pokes = np.array([xy for xy, _ in TWO_SIDES])
    spacing = BOUNDARY_SPACING_ROI * mapper.config.touch.roi_size_m
    far = np.min(np.linalg.norm(cells[:, None] - pokes[None], axis=2), axis=1) >= spacing
    allowed = mapper.grid.target_mask & far
    score = boundary_score(mean, std, levels)
    best = np.flatnonzero(allowed)[np.argmax(score[allowed])]
    np.testing.assert_allclose(target.xy, cells[best])
    at = _cell(mapper, target.xy)
    # on the boundary's straddle band (its side of the level not yet known at 95 %), near the
    # true edge
    assert abs(mean[at] - levels[0]) < 1.96 * std[at]
    assert abs(target.xy[0] - 0.3) < 0.1


def test_level_set_with_one_class_looks_where_the_field_is_least_known() -> None:
    one = [((0.3, 0.2), 0.6), ((0.1, 0.1), 0.61)]
    mapper = _mapper("level-set", one)
    assert mapper.regions().n_regions == 1
    target = mapper.next_target(np.random.default_rng(0))
    assert target is not None
    var = mapper.beta_field.variance.ravel()
    reachable = np.where(mapper.grid.target_mask, var, -1.0)
    assert var[_cell(mapper, target.xy)] == pytest.approx(reachable.max())


def _brute_force_reduction(mapper: Mapper) -> np.ndarray:
    """Variance summed over the planner's domain before less after a poke at each planner
    candidate, each posterior solved afresh with the candidate among the data (RW2006 Eq. 2.26)."""
    cfg = mapper.config.beta_field
    pokes = mapper.beta_field.pokes
    cand, dom = mapper.grid.plan_candidates, mapper.grid.plan_domain
    noise_new = expected_noise(cand, pokes, mapper.config)

    def k(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d2 = np.sum((a[:, None] - b[None]) ** 2, axis=2)
        return cfg.signal_std**2 * np.exp(-d2 / cfg.length_scale_m**2)

    def total_variance(xy: np.ndarray, noise: np.ndarray) -> float:
        gram = k(xy, xy) + np.diag(noise**2)
        kd = k(xy, dom)
        return float(np.sum(cfg.signal_std**2 - np.sum(kd * np.linalg.solve(gram, kd), axis=0)))

    before = total_variance(pokes.xy, pokes.noise)
    return np.array([before - total_variance(np.vstack([pokes.xy, c]),
                                             np.append(pokes.noise, n))
                     for c, n in zip(cand, noise_new, strict=True)])  # fmt: skip


def test_integrated_variance_pokes_where_the_summed_variance_falls_most() -> None:
    mapper = _mapper("integrated-variance", [((0.3, 0.2), 0.6), ((0.12, 0.1), 0.6)])
    target = mapper.next_target(np.random.default_rng(0))
    assert target is not None
    reduction = _brute_force_reduction(mapper)
    np.testing.assert_allclose(target.xy, mapper.grid.plan_candidates[np.argmax(reduction)])


def test_integrated_variance_does_not_chase_the_corner_max_variance_pokes() -> None:
    # after the centre, the least-known reachable cells are the target area's corners; a poke
    # there informs the fewest cells, so the summed variance falls more from further in
    iv = _mapper("integrated-variance", [((0.3, 0.2), 0.6)]).next_target(np.random.default_rng(0))
    mv = _mapper("max-variance", [((0.3, 0.2), 0.6)]).next_target(np.random.default_rng(0))
    assert iv is not None and mv is not None
    margin = 0.06  # half the ROI
    corners = np.array([[margin, margin], [0.6 - margin, margin], [margin, 0.4 - margin],
                        [0.6 - margin, 0.4 - margin]])  # fmt: skip
    assert np.min(np.linalg.norm(corners - mv.xy, axis=1)) < 0.01
    assert np.min(np.linalg.norm(corners - iv.xy, axis=1)) > 0.03


def test_every_strategy_stops_under_the_threshold() -> None:
    for strategy in ("level-set", "integrated-variance"):
        config = ExplorationConfig(strategy=strategy, field="beta", threshold=0.2)  # type: ignore[arg-type]
        mapper = Mapper(WORKSPACE, config)
        mapper.add(synthetic_poke(np.array([0.3, 0.2]), 0.6, 0.03))
        rng = np.random.default_rng(0)
        for i in range(1, 30):
            target = mapper.next_target(rng)
            if target is None:
                break
            mapper.add(synthetic_poke(target.xy, 0.6, 0.03, index=i), target=target)
        assert target is None and mapper.max_variance() <= 0.2


def test_the_new_names_are_settings_and_a_scored_strategy_needs_its_scorer() -> None:
    for strategy in ("level-set", "integrated-variance"):
        assert ExplorationConfig(strategy=strategy).strategy == strategy  # type: ignore[arg-type]
        with pytest.raises(InvalidArgumentError, match=f"`scorer` is required by strategy "
                                                       f"'{strategy}'"):
            choose_target(strategy, np.zeros((3, 2)), np.ones(3), 0.5, np.random.default_rng(0))
    with pytest.raises(InvalidArgumentError, match="`strategy` must be one of"):
        ExplorationConfig(strategy="level_set")  # type: ignore[arg-type]


def test_integrated_variance_is_held_to_the_planners_budget() -> None:
    big = Workspace(upper=(3.0, 3.0))
    with pytest.raises(SettingError, match="22,801 cells") as info:
        check_exploration_budget(ExplorationConfig(strategy="integrated-variance"), big)
    assert info.value.field == "strategy"
    check_exploration_budget(ExplorationConfig(strategy="level-set"), big)  # the map grid only
