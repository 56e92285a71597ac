from __future__ import annotations

import numpy as np
import pytest

from deformap.gp import GPHyperparameters, fit_hyperparameters, log_marginal_likelihood
from deformap.gp._hyper import _lml_and_grad
from deformap.gp._kernels import _sqdist

TRUE = GPHyperparameters(length_scale=0.05, signal_std=0.01, noise_std=0.001)


def _draw(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A draw of the paper's GP with ``TRUE`` hyperparameters plus noise."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform([0.0, 0.0], [0.3, 0.2], size=(n, 2))
    k = TRUE.signal_std**2 * np.exp(-_sqdist(xy, xy) / TRUE.length_scale**2)
    low = np.linalg.cholesky(k + 1e-10 * TRUE.signal_std**2 * np.eye(n))
    f = low @ rng.standard_normal(n)
    return xy, 0.05 + f + TRUE.noise_std * rng.standard_normal(n)


def test_gradient_matches_finite_differences() -> None:
    xy, z = _draw(80, 1)
    theta = np.log([0.04, 0.012, 0.002])
    resid = z - z.mean()
    d2 = _sqdist(xy, xy)
    _, grad = _lml_and_grad(theta, d2, resid)
    step = 1e-6

    def lml(t):
        return _lml_and_grad(t, d2, resid)[0]

    numeric = [(lml(theta + step * e) - lml(theta - step * e)) / (2 * step) for e in np.eye(3)]
    np.testing.assert_allclose(grad, numeric, rtol=1e-5)


def test_public_lml_matches_the_fitted_field() -> None:
    from deformap.gp import GaussianRandomField

    xy, z = _draw(50, 2)
    lml = log_marginal_likelihood(xy, z, length_scale=0.04, signal_std=0.01, noise_std=0.002)
    field = GaussianRandomField(
        length_scale=0.04, signal_std=0.01, noise_std=0.002, method="exact", jitter=1e-15
    ).fit(xy, z)
    assert lml == pytest.approx(field.log_marginal_likelihood_, rel=1e-9)


def test_recovers_length_scale_of_a_known_gp() -> None:
    xy, z = _draw(400, 3)
    fit = fit_hyperparameters(xy, z, rng=np.random.default_rng(0), n_restarts=2)
    assert fit.length_scale == pytest.approx(TRUE.length_scale, rel=0.25)
    assert fit.noise_std == pytest.approx(TRUE.noise_std, rel=0.25)
    truth_lml = log_marginal_likelihood(
        xy, z, length_scale=TRUE.length_scale, signal_std=TRUE.signal_std, noise_std=TRUE.noise_std
    )
    assert fit.log_marginal_likelihood >= truth_lml - 1e-6


def test_same_seed_same_result_on_a_subset() -> None:
    xy, z = _draw(300, 4)
    a = fit_hyperparameters(xy, z, rng=np.random.default_rng(5), n_restarts=1, max_points=150)
    b = fit_hyperparameters(xy, z, rng=np.random.default_rng(5), n_restarts=1, max_points=150)
    assert a == b
    assert a.length_scale == pytest.approx(TRUE.length_scale, rel=0.5)


def test_init_is_used_as_first_start() -> None:
    xy, z = _draw(100, 6)
    fit = fit_hyperparameters(xy, z, rng=np.random.default_rng(0), init=TRUE, n_restarts=0)
    truth_lml = log_marginal_likelihood(
        xy, z, length_scale=TRUE.length_scale, signal_std=TRUE.signal_std, noise_std=TRUE.noise_std
    )
    assert fit.log_marginal_likelihood >= truth_lml
