"""Convergence of the β search on deep dents, where clusters under the tip turn inside out.

On these the plain local–global step's residual first grows for a few tens of steps (the
clusters under the tip pass through det F = 0), then contracts; unguarded Anderson steps threw
the iterate back into the growing phase until ``max_iter`` (see :meth:`Equilibrium.solve`).
"""

from __future__ import annotations

import numpy as np

from deformap.msm import ParticleGrid, ShapeMatchingConfig, estimate_beta, simulate_poke
from deformap.testing import elastic_dent, hardness_to_modulus


def _deep_dent(n=25, spacing=0.005, force=3.0, tip=0.015, hardness=30.0):
    xs = 0.30 + (np.arange(n) - (n - 1) / 2) * spacing
    ys = 0.20 + (np.arange(n) - (n - 1) / 2) * spacing
    z = np.full((n, n), 0.05)
    zd, contact = elastic_dent(xs, ys, z, (0.30, 0.20), force_n=force, tip_radius_m=tip,
                               modulus_pa=hardness_to_modulus(hardness))
    gx, gy = np.meshgrid(xs, ys)
    noise = np.random.default_rng(0).normal(scale=1e-4, size=zd.shape)
    pts = np.column_stack([gx.ravel(), gy.ravel(), (zd + noise).ravel()])
    return xs, ys, z, pts, contact


def test_deep_dent_beta_search_converges():
    # before the safeguard: β = 0.95 of the sweep stalled at a residual of 5e-4 for 500 steps
    xs, ys, z, pts, contact = _deep_dent()
    est = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig())
    assert est.all_converged, est.betas[~est.converged]
    assert est.iterations.max() < 200
    assert 0.85 <= est.beta <= 0.97  # a 30 N foam: soft, high β


def test_deep_dent_equilibria_converge_from_rest():
    # before the safeguard: β = 0.95 stalled at a residual of 6e-3 (500 steps)
    xs, ys, z, _, contact = _deep_dent()
    g = ParticleGrid.from_heightmap(xs, ys, z)
    betas = np.array([0.9, 0.95])
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, betas, ShapeMatchingConfig())
    assert sim.converged.all(), sim.residual
    assert np.all(sim.residual < 1e-6)
