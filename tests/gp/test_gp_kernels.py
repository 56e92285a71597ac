from __future__ import annotations

import numpy as np
import pytest

from deformap.gp import grid_points, squared_exponential


def test_kernel_is_the_papers_formula_without_factor_two() -> None:
    x1 = np.array([[0.0, 0.0], [0.03, 0.04]])
    x2 = np.array([[0.0, 0.0]])
    k = squared_exponential(x1, x2, length_scale=0.05, signal_std=0.2)
    # ‖Δ‖ = 5 cm = σ_w, so k = σe² e⁻¹ exactly.
    np.testing.assert_allclose(k[:, 0], [0.04, 0.04 * np.exp(-1.0)], rtol=1e-14)


def test_kernel_matches_sklearn_rbf_with_sqrt2_length_scale() -> None:
    kernels = pytest.importorskip("sklearn.gaussian_process.kernels")
    rng = np.random.default_rng(0)
    a, b = rng.uniform(0, 0.6, (7, 2)), rng.uniform(0, 0.6, (5, 2))
    ref = kernels.ConstantKernel(0.3**2) * kernels.RBF(0.04 / np.sqrt(2))
    np.testing.assert_allclose(
        squared_exponential(a, b, length_scale=0.04, signal_std=0.3),
        ref(a, b),
        rtol=1e-12,
        atol=1e-300,
    )


def test_grid_points_are_row_major_in_y() -> None:
    pts = grid_points([0.0, 0.1, 0.2], [1.0, 2.0])
    assert pts.shape == (6, 2)
    values = pts[:, 0] + 10 * pts[:, 1]
    image = values.reshape(2, 3)
    np.testing.assert_allclose(image[1, 2], 0.2 + 20.0)
    np.testing.assert_allclose(pts[3], [0.0, 2.0])
