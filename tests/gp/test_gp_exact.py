from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from deformap.errors import NotPositiveDefiniteError
from deformap.gp import GaussianRandomField

W, S, N = 0.04, 0.01, 0.001  # σ_w, σe, σn in metres


def test_parity_with_sklearn_mean_and_std(small_data) -> None:
    gpr_mod = pytest.importorskip("sklearn.gaussian_process")
    kernels = pytest.importorskip("sklearn.gaussian_process.kernels")
    xy, z = small_data
    kernel = kernels.ConstantKernel(S**2) * kernels.RBF(W / np.sqrt(2)) + kernels.WhiteKernel(N**2)
    ref = gpr_mod.GaussianProcessRegressor(kernel, optimizer=None, normalize_y=False, alpha=1e-14)
    ref.fit(xy, z - z.mean())
    test = np.random.default_rng(1).uniform([-0.05, -0.05], [0.25, 0.2], (200, 2))
    ref_mean, ref_std = ref.predict(test, return_std=True)
    ref_lml = ref.log_marginal_likelihood_value_

    field = GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method="exact")
    mean, std = field.fit(xy, z).predict(test, return_std=True)
    np.testing.assert_allclose(mean, ref_mean + z.mean(), rtol=0, atol=1e-9)
    # sklearn's std includes the WhiteKernel's noise; ours is the latent f's.
    np.testing.assert_allclose(np.sqrt(std**2 + N**2), ref_std, rtol=1e-6)
    np.testing.assert_allclose(field.log_marginal_likelihood_, ref_lml, rtol=1e-8)


def test_tiny_noise_interpolates(small_data) -> None:
    xy, z = small_data
    field = GaussianRandomField(length_scale=W, signal_std=S, noise_std=1e-7, method="exact")
    mean, std = field.fit(xy, z).predict(xy, return_std=True)
    np.testing.assert_allclose(mean, z, atol=1e-6)
    assert np.all(std < 1e-6)


def test_far_from_data_reverts_to_prior(small_data) -> None:
    xy, z = small_data
    field = GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method="exact")
    mean, std = field.fit(xy, z).predict(np.array([[2.0, 2.0], [-1.0, 0.1]]), return_std=True)
    np.testing.assert_allclose(mean, field.mean_, atol=1e-12)
    np.testing.assert_allclose(std, S, rtol=1e-9)
    assert field.mean_ == pytest.approx(z.mean())


coords = arrays(
    np.float64,
    st.tuples(st.integers(1, 25), st.just(2)),
    elements=st.floats(0.0, 0.2, allow_nan=False),
)


@settings(max_examples=25, deadline=None)
@given(
    xy=coords,
    w=st.floats(0.01, 0.1),
    noise=st.floats(1e-3, 1.0),
    method=st.sampled_from(["exact", "grid"]),
)
def test_posterior_std_never_exceeds_prior(xy, w, noise, method) -> None:
    z = np.sin(xy[:, 0] * 30) * S
    field = GaussianRandomField(length_scale=w, signal_std=S, noise_std=noise * S, method=method)
    test = np.random.default_rng(0).uniform(-0.05, 0.25, (50, 2))
    _, std = field.fit(xy, z).predict(np.vstack([test, xy]), return_std=True)
    assert np.all(std <= S * (1 + 1e-9))
    assert np.all(std >= 0)


@pytest.mark.parametrize("method", ["exact", "grid"])
def test_noisier_point_pulls_less(method) -> None:
    xy = np.array([[0.0, 0.0], [0.001, 0.0], [0.2, 0.2]])
    z = np.array([1.0, -1.0, 0.0]) * S
    field = GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method=method)
    equal = field.fit(xy, z).predict(np.array([[0.0005, 0.0]]))[0]
    noisy_first = field.fit(xy, z, noise_std=[10 * N, N, N]).predict(np.array([[0.0005, 0.0]]))[0]
    noisy_second = field.fit(xy, z, noise_std=[N, 10 * N, N]).predict(np.array([[0.0005, 0.0]]))[0]
    assert noisy_first < equal - 0.1 * S < 0
    assert noisy_second > equal + 0.1 * S
    # A constant per-point noise is the homoscedastic fit.
    same = field.fit(xy, z, noise_std=np.full(3, N)).predict(np.array([[0.0005, 0.0]]))[0]
    assert same == pytest.approx(equal, abs=1e-15)


def test_duplicate_noiseless_points_escalate_jitter_then_fail() -> None:
    xy = np.array([[0.0, 0.0], [0.0, 0.0], [0.01, 0.0]])
    z = np.array([0.0, 0.001, 0.0])
    # In float64 1 + 1e-18 == 1: the first try is exactly singular and must escalate.
    tiny = GaussianRandomField(
        length_scale=W, signal_std=S, noise_std=1e-12, method="exact", jitter=1e-18
    )
    tiny.fit(xy, z)
    assert 1e-18 < tiny.jitter_used_ <= 1e-4
    strict = GaussianRandomField(
        length_scale=W,
        signal_std=S,
        noise_std=1e-12,
        method="exact",
        jitter=1e-18,
        max_jitter=1e-17,
    )
    with pytest.raises(NotPositiveDefiniteError, match="increase `noise_std`"):
        strict.fit(xy, z)
