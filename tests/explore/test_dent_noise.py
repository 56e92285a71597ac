"""The dent's noise draws against the real thing: refitting the touch GP on fresh noise."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.explore._dent_noise import DENT_NOISE_SEED, dent_error_samples
from deformap.gp import GaussianRandomField, squared_exponential

XS = 0.30 + np.arange(-6, 7) * 0.005
YS = 0.20 + np.arange(-6, 7) * 0.005
KERNEL = {"length_scale_m": 0.01, "signal_std_m": 0.01}


def _camera_points(rng: np.random.Generator, n: int) -> np.ndarray:
    """Scattered points over the ROI, none in a hidden square around the centre."""
    xy = rng.uniform([XS[0], YS[0]], [XS[-1], YS[-1]], size=(3 * n, 2))
    hidden = np.all(np.abs(xy - [0.30, 0.20]) < 0.008, axis=1)
    return xy[~hidden][:n]


def test_draws_have_the_spread_of_a_gp_refitted_on_fresh_noise() -> None:
    rng = np.random.default_rng(0)
    xy = _camera_points(rng, 400)
    tactile = np.array([[0.30, 0.20], [0.302, 0.20], [0.30, 0.202]])
    noise_m = 0.002
    draws = dent_error_samples(XS, YS, xy, noise_m, tactile, 5e-4, n_samples=2000, **KERNEL)
    assert draws.shape == (2000, XS.size * YS.size)
    data = np.vstack([xy, tactile])
    sd = np.concatenate([np.full(len(xy), noise_m), np.full(len(tactile), 5e-4)])
    refits = []
    for _ in range(150):  # what the touch GP's mean does when only the noise changes
        gp = GaussianRandomField(length_scale=0.01, signal_std=0.01, noise_std=noise_m,
                                 method="exact")  # fmt: skip
        gp.fit(data, rng.normal(0.0, sd), noise_std=sd)
        refits.append(np.asarray(gp.predict_grid(XS, YS)).ravel())
    truth = np.std(refits, axis=0)
    model = draws.std(axis=0)
    inner = np.ones((YS.size, XS.size), bool)
    inner[[0, -1], :] = inner[:, [0, -1]] = False  # binning shifts the edge points inwards
    ratio = (model / truth).reshape(YS.size, XS.size)[inner]
    assert np.median(ratio) == pytest.approx(1.0, abs=0.12)
    assert np.all((ratio > 0.6) & (ratio < 1.6))
    # the tactile points pin the hidden centre; far from any data the noise fades
    centre = (YS.size // 2) * XS.size + XS.size // 2
    assert model[centre] < np.median(model)


def test_draws_are_deterministic_and_bad_input_is_refused() -> None:
    xy = _camera_points(np.random.default_rng(1), 200)
    one = dent_error_samples(XS, YS, xy, 0.002, np.zeros((0, 2)), 5e-4, n_samples=4, **KERNEL)
    two = dent_error_samples(XS, YS, xy, 0.002, np.zeros((0, 2)), 5e-4, n_samples=4, **KERNEL)
    np.testing.assert_array_equal(one, two)
    with pytest.raises(InvalidArgumentError, match="nothing was seen"):
        dent_error_samples(XS, YS, np.zeros((0, 2)), 0.002, np.zeros((0, 2)), 5e-4,
                           n_samples=4, **KERNEL)  # fmt: skip
    with pytest.raises(InvalidArgumentError, match="`n_samples`"):
        dent_error_samples(XS, YS, xy, 0.002, np.zeros((0, 2)), 5e-4, n_samples=1, **KERNEL)
    with pytest.raises(InvalidArgumentError, match="`points_noise_m`"):
        dent_error_samples(XS, YS, xy, 0.0, np.zeros((0, 2)), 5e-4, n_samples=4, **KERNEL)


def test_the_camera_noise_is_measured_robustly() -> None:
    from deformap.explore._dent import _robust_std

    rng = np.random.default_rng(2)
    residuals = rng.normal(0.0, 0.0016, size=4000)
    assert _robust_std(residuals) == pytest.approx(0.0016, rel=0.05)
    residuals[:200] = 0.05  # flying pixels and the dent's rim
    assert _robust_std(residuals) == pytest.approx(0.0016, rel=0.12)
    assert _robust_std(np.zeros(5)) == 1e-6 and _robust_std(np.zeros(0)) == 1e-6


def test_draws_are_the_dense_smoother_on_the_binned_points_and_the_reference_values() -> None:
    rng = np.random.default_rng(0)
    xy = rng.uniform([XS[0], YS[0]], [XS[-1], YS[-1]], size=(300, 2))
    tactile = np.array([[0.30, 0.20]])
    draws = dent_error_samples(XS, YS, xy, 0.002, tactile, 5e-4, n_samples=3, **KERNEL)
    # the same draws by the dense formula K*ₓ (K + Σ)⁻¹ ε over the binned nodes
    ix = np.rint((xy[:, 0] - XS[0]) / 0.005).astype(int)
    iy = np.rint((xy[:, 1] - YS[0]) / 0.005).astype(int)
    counts = np.bincount(iy * XS.size + ix, minlength=XS.size * YS.size)
    gx, gy = np.meshgrid(XS, YS)
    nodes = np.column_stack([gx.ravel(), gy.ravel()])
    data = np.vstack([nodes[counts > 0], tactile])
    sigma = np.concatenate([0.002 / np.sqrt(counts[counts > 0]), [5e-4]])
    eps = sigma[:, None] * np.random.default_rng(DENT_NOISE_SEED).standard_normal((len(data), 3))
    k = squared_exponential(data, data, length_scale=0.01, signal_std=0.01) + np.diag(sigma**2)
    want = squared_exponential(nodes, data, length_scale=0.01, signal_std=0.01) @ np.linalg.solve(
        k, eps)
    np.testing.assert_allclose(draws, want.T, rtol=1e-6, atol=1e-12)
    # reference values recorded before the smoother moved to deformap.gp
    np.testing.assert_allclose(draws[:, [0, 84, 168]], [
        [2.84683230e-03, 3.10594242e-05, -1.93929342e-03],
        [-6.53373005e-04, -8.88782277e-04, -1.28122519e-03],
        [-1.95187594e-04, 6.58626403e-04, 1.05702950e-03]], rtol=1e-8, atol=1e-14)
