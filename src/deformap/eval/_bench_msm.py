"""Benchmark of the β estimation: the estimate against a naive per-β loop, same run.

Both compute the converged poke and E(β) of every β :func:`deformap.msm.estimate_beta` visits, on
a Hertz dent of a 60 N foam with 0.1 mm of seeded noise: the estimate sets the ROI up once, starts
each β from the last and shares factorisations; the loop simulates each β from rest with its own
set-up, to the same tolerance, sharing only the calibrated stiffness.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from deformap._validation import check_int
from deformap.errors import InvalidArgumentError
from deformap.mechanics import elastic_dent, hardness_to_youngs_modulus
from deformap.msm import (
    ParticleGrid,
    ShapeMatchingConfig,
    estimate_beta,
    matching_error,
    simulate_poke,
)

__all__ = ["bench_beta_sweep"]

_SPACING_M = 0.005
_NOISE_M = 1e-4
_TIGHT_ATOL_M = 1e-6
_LOOSE_ATOL_M = 3e-6


def bench_beta_sweep(*, n_particles_side: int = 40, rng: np.random.Generator,
                     config: ShapeMatchingConfig | None = None) -> dict[str, Any]:
    """Time a converged β estimation on ``n_particles_side``² particles (0.5 cm apart), batched
    and per-β, with ``config`` (default: the library's with 3×3 clusters); ``rng`` draws the
    noise. Returns ``{"n_beta", "n_particles", "batched_s", "loop_s", "speedup"}``."""
    n = check_int("n_particles_side", n_particles_side, minimum=5)
    if not isinstance(rng, np.random.Generator):
        raise InvalidArgumentError(f"`rng` must be a numpy.random.Generator; got {type(rng)}")
    cfg = config or ShapeMatchingConfig(cluster_size=3)
    xs, ys, z, pts, contact = dent_problem(n, rng)
    t0 = time.perf_counter()
    est = estimate_beta(xs, ys, z, pts, contact, cfg)
    batched = time.perf_counter() - t0
    grid = ParticleGrid.from_heightmap(xs, ys, z)
    tree = cKDTree(pts)
    t0 = time.perf_counter()
    loop_errors = per_beta_loop(grid, tree, contact, est, cfg)
    loop = time.perf_counter() - t0
    # both sides stop within ``sweep_tol`` of the fixed point from different starts, so loosely
    # solved β agree to about a micrometre of E and tightly solved ones far better
    atol = np.where(est.tolerances > cfg.tol, _LOOSE_ATOL_M, _TIGHT_ATOL_M)
    if np.any(np.abs(np.asarray(loop_errors) - est.errors) > atol):
        raise RuntimeError("the per-β loop disagrees with the estimate by more than "
                           f"{_TIGHT_ATOL_M * 1e6:g} µm (β solved to `tol`) or "
                           f"{_LOOSE_ATOL_M * 1e6:g} µm (to `sweep_tol`)")
    return {"n_beta": int(est.betas.size), "n_particles": n * n, "batched_s": batched,
            "loop_s": loop, "speedup": loop / batched}


def dent_problem(n: int, rng: np.random.Generator) -> tuple[Any, Any, Any, Any, Any]:
    """``xs, ys`` (n,), rest heights ``z`` (n, n), noisy ``points`` (n², 3) of the Hertz dent of a
    60 N foam under 0.5 N, and the ``contact``; metres."""
    xs = 0.30 + (np.arange(n) - (n - 1) / 2) * _SPACING_M
    ys = 0.20 + (np.arange(n) - (n - 1) / 2) * _SPACING_M
    z = np.full((n, n), 0.05)
    zd, contact = elastic_dent(xs, ys, z, (0.30, 0.20), force_n=0.5, tip_radius_m=0.01,
                               modulus_pa=hardness_to_youngs_modulus(60.0))
    gx, gy = np.meshgrid(xs, ys)
    pts = np.column_stack([gx.ravel(), gy.ravel(), (zd + rng.normal(scale=_NOISE_M,
                                                                    size=zd.shape)).ravel()])
    return xs, ys, z, pts, contact


def per_beta_loop(grid: ParticleGrid, tree: cKDTree, contact: Any, est: Any,
                  cfg: ShapeMatchingConfig) -> list[float]:
    """E(β) for each β of ``est`` (an :func:`estimate_beta` result), one simulation per β, each
    from rest with its own set-up, to the tolerance the estimate used for it; ``tree`` holds the
    observed points."""
    errors = []
    for beta, tol in zip(est.betas, est.tolerances, strict=True):
        sim = simulate_poke(grid.rest, grid.masses, grid.fixed, contact, np.array([beta]),
                            dataclasses.replace(cfg, tol=tol, sweep_tol=max(tol, cfg.sweep_tol)),
                            stiffness_n_per_m=est.stiffness_n_per_m)
        errors.append(float(matching_error(sim.positions, tree)[0]))
    return errors
