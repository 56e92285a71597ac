"""Choosing the world's physics: settings, configuration files, the budget, and a whole
exploration under each stiffening physics (:mod:`deformap.world._stiffening`,
:mod:`deformap.world._stiffening_fem`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.environment import Workspace
from deformap.errors import ConfigError
from deformap.explore import BetaFieldConfig, ExplorationConfig, SurfaceGPConfig, explore
from deformap.run import load_run_config
from deformap.testing import coarse_world
from deformap.world import PHYSICS, Block, Scenario, WorldConfig, check_world_budget
from deformap.world._polygon import rectangle

SQUARE = np.array([[0.0, 0.0], [0.6, 0.0], [0.6, 0.4], [0.0, 0.4]])


def test_the_default_physics_is_the_fem_and_older_files_load(tmp_path: Path) -> None:
    assert WorldConfig().physics == "linear-fem"
    assert PHYSICS == ("linear-fem", "stiffening-foam", "stiffening-fem")
    old = tmp_path / "old.yaml"
    old.write_text("world:\n  element_size_m: 0.01\n")  # written before `physics` existed
    assert load_run_config(old).world.physics == "linear-fem"
    new = tmp_path / "new.yaml"
    new.write_text("world:\n  physics: stiffening-foam\n  densification_strain: 0.9\n")
    world = load_run_config(new).world
    assert world.physics == "stiffening-foam" and world.densification_strain == 0.9


@pytest.mark.parametrize(("settings", "message"), [
    ({"physics": "hyperelastic"}, r"`physics` must be one of \['linear-fem', 'stiffening-foam', "
                                  r"'stiffening-fem'\]; got 'hyperelastic'"),
    ({"densification_strain": 1.5}, r"`densification_strain` must be <= 1"),
    ({"densification_strain": 0.0}, r"`densification_strain` must be > 0"),
    ({"stiffening_exponent": -1.0}, r"`stiffening_exponent` must be >= 0"),
])
def test_bad_physics_settings_are_refused_in_one_line(settings, message) -> None:
    with pytest.raises(SettingError, match=message) as info:
        WorldConfig(**settings)
    assert "\n" not in str(info.value)


def test_a_bad_physics_in_a_file_names_its_path(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("world:\n  physics: rubber\n")
    with pytest.raises(ConfigError, match=r"world\.physics"):
        load_run_config(bad)


def test_the_budget_bounds_the_foundation_grid() -> None:
    scenario = Scenario(name="s", blocks=(Block(name="b", polygon=SQUARE, hardness_n=60.0),))
    check_world_budget(WorldConfig(physics="stiffening-foam"), scenario)
    # the press grid grows with log(block / tip): only an absurd tip would reach the limit, and
    # a tip below a micrometre is refused by its own bound first
    with pytest.raises(SettingError, match="must be >= 1e-06") as info:
        WorldConfig(physics="stiffening-foam", tip_radius_m=1e-200)
    assert info.value.field == "tip_radius_m"
    big = Scenario(name="s", workspace=Workspace(lower=(0.0, 0.0), upper=(10.0, 10.0)),
                   blocks=(Block(name="b", polygon=rectangle(0.0, 0.0, 10.0, 10.0),
                                 hardness_n=60.0),))
    check_world_budget(WorldConfig(physics="stiffening-foam", tip_radius_m=1e-6,
                                   element_size_m=0.1, top_layer_m=0.05), big)


@pytest.mark.parametrize("physics", ["stiffening-foam", "stiffening-fem"])
def test_a_coarse_world_under_a_stiffening_physics_is_explored_end_to_end(physics) -> None:
    world = coarse_world("heterogeneous-60-110-rigid", seed=3, physics=physics)
    config = ExplorationConfig(
        max_pokes=2, first_target=(0.1, 0.2), appearance="off",  # the physics under test, not the look
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.05),
        beta_field=BetaFieldConfig(length_scale_m=0.1))
    result = explore(world, config, rng=np.random.default_rng(0))
    assert len(result.pokes) == 2 and not world.is_pressing
    # the 60 N foam at the first target: a finite modulus of its order (the estimator's contact
    # model is not these physics', and the coarse mesh's E is far off: see the README), the
    # rigid board read rigid, each later poke compared with the truth where it landed
    first = result.pokes[0].record.stiffness
    assert first is not None and not first.rigid and first.modulus_pa is not None
    true = float(world.ground_truth_modulus(np.array([0.1]), np.array([0.2]))[0, 0])
    assert 0.5 * true < first.modulus_pa < 3.0 * true
    for poke in result.pokes[1:]:
        assert poke.record.stiffness is not None
        truth = float(world.ground_truth_modulus(np.array([poke.xy[0]]), np.array([poke.xy[1]]))[0, 0])
        assert poke.record.stiffness.rigid == math.isinf(truth)
    assert all(math.isfinite(p.record.beta) for p in result.pokes)
