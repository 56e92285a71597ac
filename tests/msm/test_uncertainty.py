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
