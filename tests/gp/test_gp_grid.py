from __future__ import annotations

import numpy as np
import pytest

from deformap.gp import AUTO_EXACT_MAX_POINTS, GaussianRandomField, grid_points

W, S, N = 0.03, 0.01, 0.002


@pytest.fixture(scope="module")
def fields_3000():
    """Exact and grid fields on 3,000 noisy points of a 30 × 20 cm surface, σ_w = 3 cm."""
    rng = np.random.default_rng(11)
    xy = rng.uniform([0.0, 0.0], [0.3, 0.2], size=(3000, 2))
    x, y = xy[:, 0], xy[:, 1]
    z = 0.05 + 0.01 * np.sin(x / 0.02) * np.cos(y / 0.03) + N * rng.standard_normal(3000)
    exact = GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method="exact")
    grid = GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method="grid")
    return exact.fit(xy, z), grid.fit(xy, z)


def test_grid_matches_exact_within_10um_and_1_percent(fields_3000) -> None:
    exact, grid = fields_3000
    xs, ys = np.arange(0.0025, 0.3, 0.005), np.arange(0.0025, 0.2, 0.005)
    m0, s0 = exact.predict_grid(xs, ys, return_std=True)
    m1, s1 = grid.predict_grid(xs, ys, return_std=True)
    assert m1.shape == (ys.size, xs.size)
    assert np.max(np.abs(m1 - m0)) <= 10e-6
    assert np.max(np.abs(s1 - s0) / s0) <= 0.01
    assert grid.method_ == "grid" and grid.n_inducing_ > 0


def test_grid_predict_agrees_with_predict_grid(fields_3000) -> None:
    _, grid = fields_3000
    xs, ys = np.linspace(-0.05, 0.35, 9), np.linspace(0.0, 0.2, 5)
    m_img, s_img = grid.predict_grid(xs, ys, return_std=True)
    m_pts, s_pts = grid.predict(grid_points(xs, ys), return_std=True)
    np.testing.assert_allclose(m_pts, m_img.ravel(), rtol=0, atol=1e-12)
    np.testing.assert_allclose(s_pts, s_img.ravel(), rtol=1e-8)


def test_grid_reverts_to_prior_far_away(fields_3000) -> None:
    _, grid = fields_3000
    mean, std = grid.predict(np.array([[1.5, 0.1], [0.1, -1.0]]), return_std=True)
    np.testing.assert_allclose(mean, grid.mean_, atol=1e-12)
    np.testing.assert_allclose(std, S, rtol=1e-9)


def test_grid_heteroscedastic_matches_exact() -> None:
    rng = np.random.default_rng(3)
    xy = rng.uniform(0.0, 0.1, size=(300, 2))
    z = np.sin(xy[:, 0] / 0.02) * S + N * rng.standard_normal(300)
    noise = rng.uniform(0.5, 5.0, 300) * N
    test = rng.uniform(0.0, 0.1, size=(100, 2))
    out = [
        GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method=m)
        .fit(xy, z, noise_std=noise)
        .predict(test, return_std=True)
        for m in ("exact", "grid")
    ]
    assert np.max(np.abs(out[1][0] - out[0][0])) <= 1e-6
    np.testing.assert_allclose(out[1][1], out[0][1], rtol=1e-3)


def test_auto_picks_exact_small_and_grid_large() -> None:
    rng = np.random.default_rng(0)
    for n, expected in ((AUTO_EXACT_MAX_POINTS, "exact"), (AUTO_EXACT_MAX_POINTS + 1, "grid")):
        xy = rng.uniform(0.0, 0.1, size=(n, 2))
        field = GaussianRandomField(length_scale=W, signal_std=S, noise_std=N)
        assert field.fit(xy, np.zeros(n)).method_ == expected


def test_grid_path_limits_blas_threads_and_restores_them(monkeypatch) -> None:
    threadpoolctl = pytest.importorskip("threadpoolctl")
    from deformap.gp import _grid

    def blas_threads() -> list[int]:
        return [
            p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"
        ]

    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        before = blas_threads()
        with _grid.grid_blas_threads():
            assert set(blas_threads()) == {1}
        assert blas_threads() == before
        monkeypatch.setattr(_grid, "GRID_BLAS_THREADS", None)
        with _grid.grid_blas_threads():
            assert blas_threads() == before


def test_grid_matches_exact_for_points_on_a_line() -> None:
    # One axis has a single coordinate: one compressed feature and one interpolation cell there.
    rng = np.random.default_rng(5)
    xy = np.column_stack([np.full(400, 0.05), rng.uniform(0.0, 0.2, 400)])
    z = S * np.sin(xy[:, 1] / 0.02) + N * rng.standard_normal(400)
    test = np.column_stack([rng.uniform(0.0, 0.1, 200), rng.uniform(0.0, 0.2, 200)])
    out = [
        GaussianRandomField(length_scale=W, signal_std=S, noise_std=N, method=m)
        .fit(xy, z)
        .predict(test, return_std=True)
        for m in ("exact", "grid")
    ]
    assert np.max(np.abs(out[1][0] - out[0][0])) <= 1e-8
    np.testing.assert_allclose(out[1][1], out[0][1], rtol=1e-5)
