"""The strategies on hand-built β-fields: ``level-set`` (straddle on the cut levels) where it
pokes, every strategy's stop, the planner's budget, and the names a config may give."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.environment import Workspace
from deformap.errors import ConfigError, InvalidArgumentError
from deformap.explore import STRATEGIES, ExplorationConfig, Mapper, check_exploration_budget
from deformap.explore._acquisition import boundary_score, choose_target
from deformap.explore._targets import BOUNDARY_SPACING_ROI
from deformap.run import load_run_config
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


def test_max_variance_pokes_a_corner_of_the_target_area_after_the_centre() -> None:
    # after the centre, the least-known reachable cells are the target area's corners
    mv = _mapper("max-variance", [((0.3, 0.2), 0.6)]).next_target(np.random.default_rng(0))
    assert mv is not None and mv.purpose == "variance"
    margin = 0.06  # half the ROI
    corners = np.array([[margin, margin], [0.6 - margin, margin], [margin, 0.4 - margin],
                        [0.6 - margin, 0.4 - margin]])  # fmt: skip
    assert np.min(np.linalg.norm(corners - mv.xy, axis=1)) < 0.01


def test_every_strategy_stops_under_the_threshold() -> None:
    for strategy in STRATEGIES:
        config = ExplorationConfig(strategy=strategy, field="beta", threshold=0.2)
        mapper = Mapper(WORKSPACE, config)
        mapper.add(synthetic_poke(np.array([0.3, 0.2]), 0.6, 0.03))
        rng = np.random.default_rng(0)
        for i in range(1, 30):
            target = mapper.next_target(rng)
            if target is None:
                break
            mapper.add(synthetic_poke(target.xy, 0.6, 0.03, index=i), target=target)
        assert target is None and mapper.max_variance() <= 0.2, strategy


def test_level_set_is_a_setting_and_needs_its_scorer() -> None:
    assert ExplorationConfig(strategy="level-set").strategy == "level-set"
    with pytest.raises(InvalidArgumentError, match="`scorer` is required by strategy 'level-set'"):
        choose_target("level-set", np.zeros((3, 2)), np.ones(3), 0.5, np.random.default_rng(0))
    with pytest.raises(InvalidArgumentError, match="`strategy` must be one of"):
        ExplorationConfig(strategy="level_set")  # type: ignore[arg-type]


def test_only_the_planned_strategy_is_held_to_the_planners_budget() -> None:
    big = Workspace(upper=(3.0, 3.0))
    with pytest.raises(SettingError, match="22,801 cells") as info:
        check_exploration_budget(ExplorationConfig(strategy="planned"), big)
    assert info.value.field == "strategy"
    for strategy in set(STRATEGIES) - {"planned"}:
        check_exploration_budget(ExplorationConfig(strategy=strategy), big)  # the map grid only


@pytest.mark.parametrize("retired", ["min-max-variance", "integrated-variance"])
def test_a_config_file_naming_a_retired_strategy_is_refused_in_one_line(
    tmp_path: Path, retired: str
) -> None:
    path = tmp_path / "old.yaml"
    path.write_text(f"exploration:\n  strategy: {retired}\n")
    with pytest.raises(ConfigError) as info:
        load_run_config(path)
    message = str(info.value)
    assert "\n" not in message
    assert message == (f"`old.yaml.exploration.strategy` must be one of {list(STRATEGIES)}; "
                       f"got {retired!r}")
    assert retired not in STRATEGIES
    assert set(STRATEGIES) == {"paper", "max-variance", "planned", "level-set"}
