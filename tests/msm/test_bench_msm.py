"""The β-sweep benchmark: the estimate and the naive per-β loop it is timed against compute the
same thing (the same E(β) on the same β, so the same β̂), and the timings it reports are real."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from deformap.errors import InvalidArgumentError
from deformap.eval._bench_msm import bench_beta_sweep, dent_problem, per_beta_loop
from deformap.msm import ParticleGrid, ShapeMatchingConfig, estimate_beta


def test_the_loop_the_benchmark_times_finds_the_estimates_beta() -> None:
    cfg = ShapeMatchingConfig(n_beta=10, layers=0)
    xs, ys, z, pts, contact = dent_problem(9, np.random.default_rng(0))
    est = estimate_beta(xs, ys, z, pts, contact, cfg)
    grid = ParticleGrid.from_heightmap(xs, ys, z)
    loop = np.asarray(per_beta_loop(grid, cKDTree(pts), contact, est, cfg))
    assert loop.shape == est.errors.shape and est.betas.size >= cfg.n_beta
    # each β from rest on its own against the estimate's warm starts: the same E(β) to within the
    # solver tolerance (a micrometre at most), so the same minimiser
    np.testing.assert_allclose(loop, est.errors, rtol=0, atol=3e-6)
    assert est.betas[int(np.argmin(loop))] == pytest.approx(est.beta)


def test_bench_beta_sweep_reports_real_timings_of_the_betas_it_solved() -> None:
    cfg = ShapeMatchingConfig(n_beta=10, layers=0)
    out = bench_beta_sweep(n_particles_side=9, rng=np.random.default_rng(0), config=cfg)
    assert set(out) == {"n_beta", "n_particles", "batched_s", "loop_s", "speedup"}
    xs, ys, z, pts, contact = dent_problem(9, np.random.default_rng(0))
    est = estimate_beta(xs, ys, z, pts, contact, cfg)
    assert out["n_particles"] == 81 and out["n_beta"] == est.betas.size
    for key in ("batched_s", "loop_s", "speedup"):
        assert math.isfinite(out[key]) and out[key] > 0, key
    # the loop really simulates every β from rest, each with its own set-up: well over a
    # millisecond per β (about 17 ms each on the 2-core development machine)
    assert out["loop_s"] > 1e-3 * out["n_beta"]


def test_bench_refuses_bad_arguments() -> None:
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        bench_beta_sweep(n_particles_side=9, rng=0)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`n_particles_side`"):
        bench_beta_sweep(n_particles_side=2, rng=np.random.default_rng(0))
