"""Settings that would ask for absurd memory or time are refused before any work starts."""

from __future__ import annotations

import typing

import numpy as np
import pytest

from deformap._config import config_from_dict
from deformap._validation import SettingError
from deformap.environment import Workspace
from deformap.errors import ConfigError
from deformap.explore import (
    STRATEGIES,
    ExplorationConfig,
    SurfaceGPConfig,
    TouchGPConfig,
    check_exploration_budget,
)
from deformap.explore._acquisition import Strategy
from deformap.msm import ShapeMatchingConfig
from deformap.run import RunConfig
from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig, check_world_budget
from deformap.world import _config as world_config_module
from deformap.world import _world as world_module
from deformap.world._fem import graded_levels
from deformap.world._polygon import rectangle
from deformap.world._scenario import MAX_EXTENT_M, builtin_scenarios


def _scenario(width: float, depth: float, *, thickness: float = 0.05) -> Scenario:
    block = Block(name="foam", polygon=rectangle(0.0, 0.0, width, depth), hardness_n=110.0,
                  thickness_m=thickness)
    return Scenario(name="big", blocks=(block,),
                    workspace=Workspace(lower=(0.0, 0.0), upper=(width, depth)))


def test_defaults_and_builtin_scenarios_are_within_every_budget() -> None:
    for scenario in builtin_scenarios().values():
        check_world_budget(WorldConfig(), scenario)
        check_world_budget(WorldConfig.coarse(), scenario)
        for strategy in STRATEGIES:
            check_exploration_budget(ExplorationConfig(strategy=strategy), scenario.workspace)


def test_a_roi_whose_particle_system_would_not_fit_in_memory_is_refused() -> None:
    fine = SurfaceGPConfig(grid_spacing_m=0.001)
    ExplorationConfig(surface=fine)  # the 12 cm ROI at 1 mm still fits
    with pytest.raises(SettingError, match="MiB per band") as info:
        ExplorationConfig(surface=fine, touch=TouchGPConfig(roi_size_m=0.3))
    assert info.value.field == "touch.roi_size_m"
    with pytest.raises(ConfigError, match=r"^`config\.exploration\.touch\.roi_size_m` makes"):
        config_from_dict(RunConfig, {"exploration": {"surface": {"grid_spacing_m": 0.001},
                                                     "touch": {"roi_size_m": 0.3}}})
    # the same ROI is fine as a sheet (pinned, no layers under it): the band is what counts
    ExplorationConfig(surface=fine, touch=TouchGPConfig(roi_size_m=0.2),
                      shape_matching=ShapeMatchingConfig(contact="pinned"))


def test_a_roi_smaller_than_one_cluster_is_refused() -> None:
    with pytest.raises(SettingError, match=r"at least `shape_matching\.cluster_size` = 3") as info:
        ExplorationConfig(touch=TouchGPConfig(roi_size_m=0.005))  # one node at 5 mm
    assert info.value.field == "touch.roi_size_m"


def test_a_map_grid_too_fine_for_the_workspace_is_refused() -> None:
    fine = ExplorationConfig(surface=SurfaceGPConfig(grid_spacing_m=0.001))
    check_exploration_budget(fine, Workspace())  # 600 × 400 cells
    with pytest.raises(SettingError, match="4,000,000 map cells") as info:
        check_exploration_budget(fine, Workspace(upper=(2.0, 2.0)))
    assert info.value.field == "surface.grid_spacing_m"
    with pytest.raises(SettingError, match=r"`grid_spacing_m` must be >= 0\.001"):
        SurfaceGPConfig(grid_spacing_m=1e-4)


def test_planning_over_a_workspace_too_large_for_its_matrices_is_refused() -> None:
    big = Workspace(upper=(3.0, 3.0))
    for strategy in ("planned",):
        with pytest.raises(SettingError, match="22,801 cells") as info:
            check_exploration_budget(ExplorationConfig(strategy=strategy), big)
        assert info.value.field == "strategy"
    for strategy in ("max-variance", "paper"):  # no planner: the map grid alone counts
        check_exploration_budget(ExplorationConfig(strategy=strategy), big)


def test_a_mesh_too_fine_for_the_scenario_is_refused_before_the_world_is_built(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("the foam was meshed before the budget was checked")

    monkeypatch.setattr(world_module, "FoamModel", never)
    config = WorldConfig(element_size_m=0.001)
    with pytest.raises(SettingError, match="FEM unknowns") as info:
        SimulatedWorld(_scenario(2.0, 2.0), config=config, rng=np.random.default_rng(0))
    assert info.value.field == "element_size_m"
    with pytest.raises(SettingError, match=r"`element_size_m` must be >= 0\.001"):
        WorldConfig(element_size_m=1e-4)
    # thin, non-growing layers are counted too
    with pytest.raises(SettingError, match="FEM unknowns"):
        check_world_budget(WorldConfig(top_layer_m=0.001, layer_growth=1.0),
                           _scenario(1.0, 1.0, thickness=1.0))


@pytest.mark.parametrize(("thickness", "top", "growth"),
                         [(0.05, 0.005, 1.5), (0.05, 0.01, 1.5), (0.03, 0.005, 1.0),
                          (0.2, 0.001, 1.1), (0.05, 0.1, 2.0), (1.0, 0.001, 10.0)])
def test_the_layer_count_bound_holds(thickness: float, top: float, growth: float) -> None:
    actual = len(graded_levels(thickness, min(top, thickness), growth)) - 1
    bound = world_config_module._layer_count(thickness, top, growth)
    assert actual <= bound <= actual + 2


def test_a_scene_larger_than_a_table_top_is_refused() -> None:
    with pytest.raises(SettingError, match=r"`polygon` must span at most 10 m.*\(block 'foam'\)"):
        _scenario(MAX_EXTENT_M * 2, 0.4)
    wide = Block(name="foam", polygon=rectangle(0.0, 0.0, 5.0, 0.4), hardness_n=110.0)
    with pytest.raises(SettingError, match="`workspace` must span at most 10 m"):
        Scenario(name="far", blocks=(wide,), workspace=Workspace(upper=(20.0, 0.4)))
    with pytest.raises(SettingError, match=r"`thickness_m` must be <= 10; got 11.0 \(block 'x'\)"):
        Block(name="x", polygon=rectangle(0.0, 0.0, 0.1, 0.1), rigid=True, thickness_m=11.0)


def test_strategy_names_come_from_one_literal() -> None:
    assert STRATEGIES == typing.get_args(Strategy)
    assert typing.get_type_hints(ExplorationConfig)["strategy"] == Strategy
    with pytest.raises(SettingError, match="`strategy` must be one of"):
        ExplorationConfig(strategy="max_variance")  # type: ignore[arg-type]
