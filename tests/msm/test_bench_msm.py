"""The β-sweep benchmark runs, checks batched against looped, and returns the agreed keys."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval._bench_msm import bench_beta_sweep
from deformap.msm import ShapeMatchingConfig


def test_bench_beta_sweep_small_grid():
    cfg = ShapeMatchingConfig(n_beta=10, layers=0)
    out = bench_beta_sweep(n_particles_side=9, rng=np.random.default_rng(0), config=cfg)
    assert set(out) == {"n_beta", "n_particles", "batched_s", "loop_s", "speedup"}
    assert out["n_particles"] == 81 and out["n_beta"] >= 10
    assert out["batched_s"] > 0 and out["loop_s"] > 0
    assert out["speedup"] == pytest.approx(out["loop_s"] / out["batched_s"])


def test_bench_refuses_bad_arguments():
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        bench_beta_sweep(n_particles_side=9, rng=0)
    with pytest.raises(InvalidArgumentError, match="`n_particles_side`"):
        bench_beta_sweep(n_particles_side=2, rng=np.random.default_rng(0))
