"""The posterior algebra without observed values: against the exact GP and the dense formulas."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.gp import (
    GaussianRandomField,
    PosteriorDesign,
    apply_smoother,
    squared_exponential,
    variance_after_adding,
)

KERN = {"length_scale": 0.15, "signal_std": 0.3}


def _dense_posterior(obs: np.ndarray, noise: np.ndarray, a: np.ndarray, b: np.ndarray
                     ) -> np.ndarray:  # fmt: skip
    """K(a, b) − K(a, x) (K(x, x) + Σ)⁻¹ K(x, b), RW2006 Eq. 2.24, by a dense solve."""
    k_xx = squared_exponential(obs, obs, **KERN) + np.diag(noise**2)
    return np.asarray(squared_exponential(a, b, **KERN) - squared_exponential(a, obs, **KERN)
                      @ np.linalg.solve(k_xx, squared_exponential(obs, b, **KERN)))


@pytest.fixture
def design() -> tuple[PosteriorDesign, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(4)
    obs, noise = rng.uniform(0, 0.5, (3, 2)), rng.uniform(0.02, 0.1, 3)
    cand, dom = rng.uniform(0, 0.5, (7, 2)), rng.uniform(0, 0.5, (40, 2))
    return (PosteriorDesign(obs, noise, cand, dom, candidate_noise_std=0.05, **KERN),
            obs, noise, cand, dom)


def test_posterior_of_a_design_is_the_dense_formula(design) -> None:
    d, obs, noise, cand, dom = design
    chosen = [4, 1]
    var_d, cov, var_c = d.posterior(chosen)
    x = np.vstack([obs, cand[chosen]])
    sigma = np.concatenate([noise, [0.05, 0.05]])
    np.testing.assert_allclose(var_d, np.diag(_dense_posterior(x, sigma, dom, dom)), atol=1e-12)
    np.testing.assert_allclose(cov, _dense_posterior(x, sigma, cand, dom), atol=1e-12)
    np.testing.assert_allclose(var_c, np.diag(_dense_posterior(x, sigma, cand, cand)), atol=1e-12)
    # the exact GP of the library gives the same variance (values play no part)
    gp = GaussianRandomField(noise_std=0.05, method="exact", **KERN)
    gp.fit(x, np.zeros(len(x)), noise_std=sigma)
    np.testing.assert_allclose(gp.predict(dom, return_std=True)[1] ** 2, var_d, atol=1e-10)
    assert np.all(var_d <= KERN["signal_std"] ** 2 + 1e-15)


def test_one_more_observation_is_the_design_with_it(design) -> None:
    d, *_ = design
    after = d.variance_after_adding([2])
    for j in (0, 3, 6):
        np.testing.assert_allclose(after[j], d.posterior([2, j])[0], atol=1e-12)
    var_d, cov, var_c = d.posterior([2])
    np.testing.assert_array_equal(after, variance_after_adding(var_d, cov, var_c, 0.05**2))


def test_no_observation_leaves_the_prior() -> None:
    d = PosteriorDesign(np.zeros((0, 2)), np.zeros(0), [[0.1, 0.1]], [[0.0, 0.0], [0.3, 0.3]],
                        candidate_noise_std=0.05, **KERN)
    var_d, cov, var_c = d.posterior([])
    np.testing.assert_array_equal(var_d, [0.09, 0.09])
    np.testing.assert_array_equal(var_c, [0.09])
    np.testing.assert_array_equal(cov, squared_exponential([[0.1, 0.1]], [[0.0, 0.0], [0.3, 0.3]],
                                                           **KERN))


def test_smoother_is_the_dense_posterior_mean() -> None:
    rng = np.random.default_rng(5)
    data, noise = rng.uniform(0, 0.3, (30, 2)), rng.uniform(0.01, 0.05, 30)
    query, values = rng.uniform(0, 0.3, (12, 2)), rng.normal(size=(30, 4))
    got = apply_smoother(data, noise, query, values, **KERN)
    # with the jitter the Cholesky factor starts from (1e-10 σe² on the diagonal)
    k = squared_exponential(data, data, **KERN) + np.diag(noise**2 + 1e-10 * 0.3**2)
    want = squared_exponential(query, data, **KERN) @ np.linalg.solve(k, values)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(apply_smoother(data, noise, query, values[:, 0], **KERN),
                               got[:, 0], rtol=1e-10, atol=1e-12)


def test_bad_input_is_named() -> None:
    with pytest.raises(InvalidArgumentError, match="`observed_noise_std` must be positive"):
        PosteriorDesign([[0, 0]], [0.0], [[0, 0]], [[0, 0]], candidate_noise_std=0.1, **KERN)
    d = PosteriorDesign([[0, 0]], [0.1], [[0, 0]], [[0, 0]], candidate_noise_std=0.1, **KERN)
    with pytest.raises(InvalidArgumentError, match="`chosen` must index the 1 candidates"):
        d.posterior([1])
    with pytest.raises(InvalidArgumentError, match=r"`covariance` must be \(candidates, domain\)"):
        variance_after_adding(np.ones(3), np.ones((2, 2)), np.ones(2), 0.1)
    with pytest.raises(InvalidArgumentError, match=r"`values` must be \(2,\) or \(2, k\)"):
        apply_smoother([[0, 0], [1, 1]], [0.1, 0.1], [[0, 0]], np.ones(3), **KERN)


def test_each_candidate_may_have_its_own_noise(design) -> None:
    d, obs, noise, cand, dom = design
    per = np.full(len(cand), 0.05)
    per[3] = 0.4  # a candidate whose observations are noisy
    e = PosteriorDesign(obs, noise, cand, dom, candidate_noise_std=per, **KERN)
    # the dense formula with each chosen candidate's own noise
    chosen = [3, 1]
    x = np.vstack([obs, cand[chosen]])
    sigma = np.concatenate([noise, per[chosen]])
    np.testing.assert_allclose(e.posterior(chosen)[0],
                               np.diag(_dense_posterior(x, sigma, dom, dom)), atol=1e-12)
    after, same = e.variance_after_adding([]), d.variance_after_adding([])
    np.testing.assert_array_equal(np.delete(after, 3, axis=0), np.delete(same, 3, axis=0))
    assert np.all(after[3] >= same[3] - 1e-15)  # the noisy candidate reduces less
    with pytest.raises(InvalidArgumentError, match="`candidate_noise_std` must be"):
        PosteriorDesign(obs, noise, cand, dom, candidate_noise_std=per[:3], **KERN)
    with pytest.raises(InvalidArgumentError, match="`noise_var` must be"):
        variance_after_adding(*e.posterior([]), -per)
