from __future__ import annotations

import numpy as np
import pytest

from deformap.gp._grid import _data_terms, inducing_axis
from deformap.gp._grid_basis import (
    FEATURE_TOLERANCE,
    axis_basis,
    chebyshev_degree,
    chebyshev_points,
    lagrange_weights,
)

W = 0.04


def _basis(lo: float, hi: float, spacing: float = W / 3):
    nodes = inducing_axis(lo, hi, spacing, W)
    basis, _ = axis_basis(lo, hi, nodes, length_scale=W, jitter=1e-10, max_jitter=1e-4, what="K")
    return basis


def test_compression_keeps_every_point_of_the_range_within_tolerance() -> None:
    basis = _basis(0.0, 0.6)
    t = np.random.default_rng(0).uniform(0.0, 0.6, 3000)
    g = basis.whitened(t)
    h = basis.features(t)
    residual = np.sum(g**2, axis=1) - np.sum(h**2, axis=1)
    assert np.max(residual) <= 2 * FEATURE_TOLERANCE
    assert basis.rank < basis.nodes.size  # a grid finer than the data's modes is compressed
    np.testing.assert_allclose(basis.proj.T @ basis.proj, np.eye(basis.rank), atol=1e-12)


def test_compression_rank_grows_with_the_range_not_with_the_grid() -> None:
    coarse, fine = _basis(0.0, 0.4), _basis(0.0, 0.4, spacing=W / 5)
    assert fine.nodes.size > coarse.nodes.size
    assert abs(fine.rank - coarse.rank) <= 1
    assert _basis(0.0, 0.6).rank > coarse.rank


@pytest.mark.parametrize("half_width", [W / 12, W / 6, W / 3])
def test_chebyshev_degree_bound_holds_and_is_tight(half_width: float) -> None:
    basis = _basis(0.0, 0.3)
    centre, tol = 0.15, 1e-9
    degree = chebyshev_degree(half_width, W, tol)
    t = centre + half_width * np.linspace(-1.0, 1.0, 401)

    def error(count: int) -> float:
        cheb = chebyshev_points(count)
        approx = lagrange_weights((t - centre) / half_width, cheb) @ basis.features(
            centre + half_width * cheb
        )
        return float(np.max(np.linalg.norm(approx - basis.features(t), axis=1)))

    assert error(degree) <= tol
    assert error(degree - 1) > tol / 100  # the bound is not wildly pessimistic


def test_lagrange_weights_reproduce_polynomials_and_nodes() -> None:
    cheb = chebyshev_points(7)
    t = np.concatenate([np.linspace(-1.0, 1.0, 11), cheb[[2]]])
    lag = lagrange_weights(t, cheb)
    for power in range(7):
        np.testing.assert_allclose(lag @ cheb**power, t**power, atol=1e-13)
    np.testing.assert_allclose(lag[-1], np.eye(7)[2], atol=1e-15)
    np.testing.assert_array_equal(lagrange_weights(t, chebyshev_points(1)), np.ones((12, 1)))


def test_interpolated_data_term_matches_the_khatri_rao_sum() -> None:
    rng = np.random.default_rng(4)
    xy = rng.uniform([0.0, 0.0], [0.3, 0.2], size=(400, 2))
    weight = rng.uniform(1.0, 30.0, 400)
    resid = rng.standard_normal(400)
    basis_a, basis_b = _basis(0.0, 0.3), _basis(0.0, 0.2)
    ha, hb = basis_a.features(xy[:, 0]), basis_b.features(xy[:, 1])
    rows = (ha[:, :, None] * hb[:, None, :]).reshape(400, -1)
    system, rhs = _data_terms(xy[:, 0], hb, weight, weight * resid, basis_a)
    scale = np.max(np.abs(system))
    np.testing.assert_allclose(system, rows.T @ (weight[:, None] * rows), rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(
        rhs.ravel(), rows.T @ (weight * resid), rtol=0, atol=1e-8 * np.max(np.abs(rhs))
    )


def test_data_term_with_all_points_on_one_line() -> None:
    xy = np.column_stack([np.full(50, 0.1), np.linspace(0.0, 0.2, 50)])
    basis_a, basis_b = _basis(0.1, 0.1), _basis(0.0, 0.2)
    assert basis_a.rank == 1
    hb = basis_b.features(xy[:, 1])
    system, _ = _data_terms(xy[:, 0], hb, np.ones(50), np.ones(50), basis_a)
    ha = basis_a.features(xy[:, 0])
    rows = (ha[:, :, None] * hb[:, None, :]).reshape(50, -1)
    np.testing.assert_allclose(system, rows.T @ rows, atol=1e-10 * np.max(np.abs(system)))
