from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.msm._uncertainty import bootstrap_beta_std

BETAS = np.arange(50) / 50


def _distances(center: float, depth: float, noise: float, seed: int = 0) -> np.ndarray:
    """Per-particle distances whose mean is a parabola in β with its minimum at ``center``."""
    rng = np.random.default_rng(seed)
    base = 1e-3 + depth * (BETAS - center) ** 2
    per_particle = rng.normal(0.0, noise, size=(1, 24, 24)) * (1 + 0 * BETAS[:, None, None])
    wobble = rng.normal(0.0, noise, size=(BETAS.size, 24, 24))
    return base[:, None, None] + per_particle + wobble


def test_a_clear_minimum_is_tight_and_a_flat_curve_is_wide() -> None:
    sharp = bootstrap_beta_std(BETAS, _distances(0.4, 5e-3, 1e-5), tile=4, resolution=0.01)
    flat = bootstrap_beta_std(BETAS, _distances(0.4, 0.0, 1e-4), tile=4, resolution=0.01)
    assert sharp < 0.03
    assert flat > 0.15  # every β is as good: the picks spread over [0, 1)


def test_more_noise_means_more_uncertainty_and_the_result_is_deterministic() -> None:
    stds = [bootstrap_beta_std(BETAS, _distances(0.6, 1e-4, noise), tile=4, resolution=0.01)
            for noise in (1e-6, 3e-5, 3e-4)]
    assert stds[0] <= stds[1] <= stds[2] and stds[2] > stds[0]
    again = bootstrap_beta_std(BETAS, _distances(0.6, 1e-4, 3e-5), tile=4, resolution=0.01)
    assert again == stds[1]


def test_floor_and_bad_input() -> None:
    exact = np.broadcast_to(((BETAS - 0.5) ** 2)[:, None, None], (50, 6, 6)).copy()
    assert bootstrap_beta_std(BETAS, exact, tile=2, resolution=0.01) == pytest.approx(
        0.01 / np.sqrt(12))
    with pytest.raises(InvalidArgumentError, match="`distances`"):
        bootstrap_beta_std(BETAS, exact[:3], tile=2, resolution=0.01)
    with pytest.raises(InvalidArgumentError, match="strictly increasing"):
        bootstrap_beta_std(BETAS[::-1], exact, tile=2, resolution=0.01)
    with pytest.raises(InvalidArgumentError, match="`tile`"):
        bootstrap_beta_std(BETAS, exact, tile=0, resolution=0.01)



def test_observation_noise_spread_grows_with_the_noise() -> None:
    from msm_cases import dent_case

    from deformap.msm import ShapeMatchingConfig, estimate_beta

    xs, ys, z, pts, contact = dent_case(110, n=13)
    cfg = ShapeMatchingConfig()
    rng = np.random.default_rng(3)
    spreads = []
    for noise in (1e-7, 3e-4, 1e-3):
        samples = rng.normal(0.0, noise, size=(24, pts.shape[0]))
        spreads.append(estimate_beta(xs, ys, z, pts, contact, cfg, height_samples=samples).beta_std)
    assert spreads[0] == pytest.approx(cfg.beta_resolution / np.sqrt(12))  # below resolution
    assert spreads[0] < spreads[1] < spreads[2]
    again = estimate_beta(xs, ys, z, pts, contact, cfg, height_samples=samples).beta_std
    assert again == spreads[2]


def test_sample_spread_equals_the_brute_force_with_exact_nearest_points() -> None:
    """The candidate-neighbour shortcut gives the argmins a fresh k-d tree per sample gives."""
    from msm_cases import dent_case
    from scipy.spatial import cKDTree

    from deformap.msm import ParticleGrid, ShapeMatchingConfig, simulate_poke
    from deformap.msm._beta import matching_error
    from deformap.msm._uncertainty import _argmins, sample_beta_std

    xs, ys, z, pts, contact = dent_case(110, n=13)
    grid = ParticleGrid.from_heightmap(xs, ys, z)
    betas = np.arange(0.5, 0.96, 0.02)
    sim = simulate_poke(grid.rest, grid.masses, grid.fixed, contact, betas, ShapeMatchingConfig())
    samples = np.random.default_rng(5).normal(0.0, 5e-4, size=(16, pts.shape[0]))
    curves = []
    for row in samples:
        moved = pts.copy()
        moved[:, 2] += row
        curves.append(matching_error(sim.positions, cKDTree(moved)))
    expected = max(float(np.std(_argmins(betas, np.array(curves)), ddof=1)), 0.01 / np.sqrt(12))
    got = sample_beta_std(betas, sim.positions, pts, samples, resolution=0.01)
    assert got == pytest.approx(expected, abs=1e-12)
    assert got > 0.01  # the noise does move β̂ here: the comparison is not trivially 0 = 0


def test_sample_spread_bad_input() -> None:
    from deformap.msm._uncertainty import sample_beta_std

    pos = np.zeros((3, 4, 4, 3))
    obs = np.zeros((16, 3))
    with pytest.raises(InvalidArgumentError, match="`height_samples`"):
        sample_beta_std(np.array([0.0, 0.5, 0.9]), pos, obs, np.zeros((1, 16)), resolution=0.01)
    with pytest.raises(InvalidArgumentError, match="`height_samples`"):
        sample_beta_std(np.array([0.0, 0.5, 0.9]), pos, obs, np.zeros((4, 15)), resolution=0.01)
    with pytest.raises(InvalidArgumentError, match="`positions`"):
        sample_beta_std(np.array([0.0, 0.5]), pos, obs, np.zeros((4, 16)), resolution=0.01)
    with pytest.raises(InvalidArgumentError, match="strictly increasing"):
        sample_beta_std(np.array([0.0, 0.5, 0.5]), pos, obs, np.zeros((4, 16)), resolution=0.01)


def test_argmins_find_the_vertex_between_uneven_samples() -> None:
    from deformap.msm._uncertainty import _argmins

    betas = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.61, 0.62, 0.7, 0.8, 0.9])
    u = -np.log1p(-betas)
    truth = np.array([0.05, 0.45, 0.615, 0.66, 0.85])
    curves = (u[None, :] + np.log1p(-truth)[:, None]) ** 2  # parabolas in u, vertex at truth
    np.testing.assert_allclose(_argmins(betas, curves), truth, atol=1e-12)
    # a minimum at the rigid end stays there; a flat run of ties stays between its samples
    assert _argmins(betas, (u[None, :] + 0.0) ** 2)[0] == pytest.approx(0.0, abs=1e-12)
    flat = np.where(np.abs(betas - 0.3) < 0.15, 0.0, 1.0)[None, :]
    assert 0.2 <= _argmins(betas, flat)[0] <= 0.4
