"""The run's configuration: overrides, resuming with the run's own settings, seeds."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from deformap._config import dump_yaml
from deformap.errors import ConfigError, DeformapError
from deformap.run import (
    RunConfig,
    RunOverrides,
    apply_overrides,
    load_run_config,
    resume_run_config,
    run_generators,
)


def test_overrides_change_only_what_was_given() -> None:
    base = RunConfig(seed=2)
    assert apply_overrides(base, RunOverrides()) is base
    changed = apply_overrides(base, RunOverrides(scenario="homogeneous-60", max_pokes=3))
    assert changed.scenario == "homogeneous-60" and changed.exploration.max_pokes == 3
    assert changed.seed == 2 and changed.world == base.world
    assert dataclasses.replace(changed.exploration, max_pokes=base.exploration.max_pokes) == (
        base.exploration
    )
    with pytest.raises(DeformapError, match="`strategy` must be one of"):
        apply_overrides(base, RunOverrides(strategy="greedy"))


def test_resume_takes_the_runs_own_settings_and_refuses_others(tmp_path: Path) -> None:
    stored = RunConfig(scenario="homogeneous-60", seed=4)
    dump_yaml(stored, tmp_path / "config.yaml")
    assert resume_run_config(tmp_path) == stored
    assert resume_run_config(tmp_path, RunOverrides(seed=4, scenario="homogeneous-60")) == stored
    with pytest.raises(ConfigError, match=r"different settings \(seed\)"):
        resume_run_config(tmp_path, RunOverrides(seed=5))
    with pytest.raises(ConfigError, match=r"holds no config\.yaml"):
        resume_run_config(tmp_path / "nothing")


def test_yaml_round_trip_and_the_seed_alone_sets_the_streams(tmp_path: Path) -> None:
    config = RunConfig(seed=9)
    dump_yaml(config, tmp_path / "c.yaml")
    assert load_run_config(tmp_path / "c.yaml") == config
    assert load_run_config(None) == RunConfig()
    a, b = run_generators(9)
    c, d = run_generators(9)
    assert a.random() == c.random() and b.random() == d.random()
    assert not np.isclose(run_generators(9)[0].random(), run_generators(10)[0].random())
