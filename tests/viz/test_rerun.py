"""The 3D recording: a timeline with the observation, each press and the β-field as it grows."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parents[1] / "explore"))


def test_record_run_writes_a_recording_rerun_can_read(tmp_path) -> None:
    pytest.importorskip("rerun")
    from test_own_environment import TwoFoamTable  # type: ignore[import-not-found]

    from deformap.explore import BetaFieldConfig, ExplorationConfig, SurfaceGPConfig, explore
    from deformap.viz import record_run

    env = TwoFoamTable(np.random.default_rng(1))
    config = ExplorationConfig(
        max_pokes=2, strategy="max-variance", first_target=(0.06, 0.08),
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
        beta_field=BetaFieldConfig(length_scale_m=0.06),
    )  # fmt: skip
    result = explore(env, config, rng=np.random.default_rng(0))
    path = record_run(tmp_path / "run.rrd", result, initial_points=env.observe().points)
    assert path.stat().st_size > 50_000
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    entities = {str(chunk.entity_path) for chunk in reader.stream()}
    for entity in ("/world/observation", "/world/press/dent", "/maps/beta", "/metrics/beta"):
        assert entity in entities, (entity, sorted(entities))
