"""Sparse GP with inducing points on a regular grid: DTC/SGPR predictions in Kronecker form.

With inducing inputs u on a grid ``ua × ub`` and the separable kernel, the prior covariance of the
inducing values is K_uu = σₑ² (K_a ⊗ K_b), and the cross-covariance of a point p with them is the
Kronecker (for many points: Khatri–Rao) product k_u(p) = σₑ² k_a(p_a) ⊗ k_b(p_b). DTC needs only
M×M algebra (RW2006 §8.3.3; Quiñonero-Candela & Rasmussen 2005):

    mean(p) = k_u(p)ᵀ Σ⁻¹ K_uf Λ⁻¹ (z − z̄),          Σ = K_uu + K_uf Λ⁻¹ K_fu
    var(p)  = k(p, p) − k_u(p)ᵀ K_uu⁻¹ k_u(p) + k_u(p)ᵀ Σ⁻¹ k_u(p)

which are also the predictions of Titsias' (2009) SGPR. K_uu of a fine grid is numerically
singular (condition ~1e18), so everything is *whitened* by its Kronecker Cholesky factor
L = L_a ⊗ L_b, as in SGPR implementations: g(p) = L⁻¹ k̂_u(p) = (L_a⁻¹ k_a) ⊗ (L_b⁻¹ k_b) keeps the
Khatri–Rao structure, Σ = σₑ² L B Lᵀ with B = I + σₑ² Gᵀ Λ⁻¹ G (eigenvalues >= 1), and

    mean(p) = g(p)ᵀ B⁻¹ σₑ² Gᵀ Λ⁻¹ (z − z̄)
    var(p)  = σₑ² (1 − ‖g(p)‖² + g(p)ᵀ B⁻¹ g(p)).

With the grid finer than the kernel's resolution the Nyström residual 1 − ‖g‖² is at round-off
level and DTC equals the exact GP to that accuracy; the defaults below follow from that residual.
Axis ``a`` is the axis with more inducing nodes; the flattened inducing index is ``ia * mb + ib``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy.linalg import blas, lapack

from deformap.errors import InvalidArgumentError, NotPositiveDefiniteError
from deformap.gp._exact import cholesky_with_jitter
from deformap.gp._kernels import _se_1d

__all__ = ["GRID_MARGIN_FRACTION", "GRID_SPACING_FRACTION", "MAX_INDUCING"]

#: Default inducing spacing = σ_w × this. The SE spectrum exp(−σ_w²ω²/4) at the grid's Nyquist
#: frequency π/h is exp(−π²·9/4) ≈ 2e-10 for h = σ_w/3; the measured 1-D Nyström residual inside the
#: grid is 2e-10 (relative to σₑ²), i.e. the grid loses nothing a float64 Cholesky would keep.
GRID_SPACING_FRACTION = 1.0 / 3.0
#: Inducing nodes extend this many σ_w beyond the data's (and test points') bounding box. At
#: spacing σ_w/3, the 1-D Nyström residual at the box edge is 7e-9 σₑ² with a 1 σ_w margin
#: (1.5e-7 with 0.5 σ_w, 8e-10 with 2 σ_w): 1 σ_w keeps the edge as exact as the interior
#: needs while costing (1 + 2σ_w/L)² fewer nodes than 2 σ_w.
GRID_MARGIN_FRACTION = 1.0
#: Kernel factors below this (relative) are dropped when Gᵀ Λ⁻¹ G is assembled: along axis ``a``
#: each point's window covers the nodes within σ_w √ln(1/_TRUNCATION) of it.
_TRUNCATION = 1e-8
#: Largest M accepted: B takes 8·M² bytes (1.2 GB at this size).
MAX_INDUCING = 12_000
_GRID_CHUNK = 16  # test rows per block in the Kronecker variance contraction


@dataclass(kw_only=True)
class GridState:
    """A fitted grid GP: the inducing axes, the factors of K_a, K_b and B, and α̂ = B⁻¹ b."""

    nodes_a: NDArray[np.float64]
    nodes_b: NDArray[np.float64]
    a_is_x: bool
    factor: tuple[NDArray[np.float64], bool]
    alpha: NDArray[np.float64]  # (ma, mb)
    chol_a: tuple[NDArray[np.float64], bool]
    chol_b: tuple[NDArray[np.float64], bool]
    jitter_used: float
    _b_inv: NDArray[np.float64] | None = field(default=None, repr=False)

    @property
    def n_inducing(self) -> int:
        return self.nodes_a.size * self.nodes_b.size

    def b_inv(self) -> NDArray[np.float64]:
        """B⁻¹ (M, M), computed once from the Cholesky factor."""
        if self._b_inv is None:
            inv, info = lapack.dpotri(self.factor[0], lower=1)
            if info != 0:
                raise NotPositiveDefiniteError(f"inverting B failed (LAPACK info {info})")
            self._b_inv = _symmetrise_from_lower(inv)
        return self._b_inv


def _symmetrise_from_lower(mat: NDArray[np.float64], block: int = 256) -> NDArray[np.float64]:
    """Copy the lower triangle of square ``mat`` onto its upper triangle, in place, by blocks."""
    size = mat.shape[0]
    for i0 in range(0, size, block):
        i1 = min(i0 + block, size)
        diag = mat[i0:i1, i0:i1]
        diag[...] = np.tril(diag) + np.tril(diag, -1).T
        mat[i0:i1, i1:] = mat[i1:, i0:i1].T
    return mat


def inducing_axis(lo: float, hi: float, spacing: float, margin: float) -> NDArray[np.float64]:
    """Regular nodes from ``lo − margin`` to at least ``hi + margin`` with step ``spacing``."""
    start = lo - margin
    count = math.ceil((hi + margin - start) / spacing - 1e-9) + 1
    return np.asarray(start + spacing * np.arange(count), dtype=np.float64)


def fit_grid(
    xy: NDArray[np.float64],
    resid: NDArray[np.float64],
    noise_var: NDArray[np.float64],
    *,
    length_scale: float,
    signal_std: float,
    spacing: float,
    jitter: float,
    max_jitter: float,
) -> GridState:
    """Assemble B and b with the Khatri–Rao structure and factorise B."""
    margin = GRID_MARGIN_FRACTION * length_scale
    nodes = [inducing_axis(xy[:, d].min(), xy[:, d].max(), spacing, margin) for d in range(2)]
    m_total = nodes[0].size * nodes[1].size
    if m_total > MAX_INDUCING:
        raise InvalidArgumentError(
            f"the grid method would need {m_total} inducing points (> {MAX_INDUCING}) for this "
            f"data extent; increase `inducing_spacing` (now {spacing:g} m) or `length_scale`, "
            "or use method='exact'"
        )
    a_is_x = nodes[0].size >= nodes[1].size
    ax_a, ax_b = (0, 1) if a_is_x else (1, 0)
    ua, ub = nodes[ax_a], nodes[ax_b]
    chol_a, jit_a = cholesky_with_jitter(
        _se_1d(ua, ua, length_scale), jitter=jitter, max_jitter=max_jitter, what="K_a"
    )
    chol_b, jit_b = cholesky_with_jitter(
        _se_1d(ub, ub, length_scale), jitter=jitter, max_jitter=max_jitter, what="K_b"
    )
    weight = signal_std**2 / noise_var  # σe² Λ⁻¹, dimensionless
    ga = _whiten(_se_1d(xy[:, ax_a], ua, length_scale), chol_a)  # (n, ma)
    gb = _whiten(_se_1d(xy[:, ax_b], ub, length_scale), chol_b)  # (n, mb)
    system = np.eye(ua.size * ub.size)
    _add_data_term(system, ga, gb, weight, xy[:, ax_a], ua, spacing, length_scale)
    # B = I + σe² Gᵀ Λ⁻¹ G has eigenvalues >= 1: no jitter, and its inverse is well conditioned.
    factor = sla.cho_factor(system, lower=True, overwrite_a=True, check_finite=False)
    rhs = (ga * (weight * resid)[:, None]).T @ gb  # (ma, mb): σe² Gᵀ Λ⁻¹ r
    alpha = sla.cho_solve(factor, rhs.ravel(), check_finite=False).reshape(ua.size, ub.size)
    return GridState(
        nodes_a=ua,
        nodes_b=ub,
        a_is_x=a_is_x,
        factor=factor,
        alpha=alpha,
        chol_a=chol_a,
        chol_b=chol_b,
        jitter_used=max(jit_a, jit_b),
    )


def _add_data_term(
    system: NDArray[np.float64],
    ga: NDArray[np.float64],
    gb: NDArray[np.float64],
    weight: NDArray[np.float64],
    coord_a: NDArray[np.float64],
    ua: NDArray[np.float64],
    spacing: float,
    length_scale: float,
) -> None:
    """Add σe² Gᵀ Λ⁻¹ G to the lower triangle of ``system`` in place.

    Points are grouped by their window of axis-``a`` nodes (those where k_a > ``_TRUNCATION``;
    the whitened g_a decays as fast to the left and faster to the right); each group's rows are
    Khatri–Rao products over that window and the full ``b`` axis, so its contribution is one SYRK
    into a contiguous diagonal block of B.
    """
    ma, mb = ua.size, gb.shape[1]
    reach = math.ceil(length_scale * math.sqrt(math.log(1.0 / _TRUNCATION)) / spacing)
    width = min(2 * reach + 2, ma)
    cell = np.clip(np.floor((coord_a - ua[0]) / spacing).astype(np.int64), 0, ma - 1)
    start = np.clip(cell - reach, 0, ma - width)
    order = np.argsort(start, kind="stable")
    bounds = np.flatnonzero(np.diff(start[order])) + 1
    root_w = np.sqrt(weight)
    for group in np.split(order, bounds):
        s0 = int(start[group[0]])
        fa = ga[group, s0 : s0 + width] * root_w[group, None]
        rows = (fa[:, :, None] * gb[group][:, None, :]).reshape(group.size, width * mb)
        block = slice(s0 * mb, (s0 + width) * mb)
        # rows.T is Fortran-ordered, so SYRK reads it without a copy.
        system[block, block] += blas.dsyrk(1.0, rows.T, trans=0, lower=1)


def _whiten(
    k_1d: NDArray[np.float64], chol: tuple[NDArray[np.float64], bool]
) -> NDArray[np.float64]:
    """``(n, m)`` rows L⁻¹ k(p) of 1-D cross-covariances ``k_1d`` (n, m)."""
    return sla.solve_triangular(chol[0], k_1d.T, lower=True, check_finite=False).T


def predict_grid_points(
    state: GridState,
    points: NDArray[np.float64],
    *,
    length_scale: float,
    signal_std: float,
    return_std: bool,
    chunk: int = 512,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Mean (without the constant) and latent std at arbitrary ``(m, 2)`` points."""
    ax_a, ax_b = (0, 1) if state.a_is_x else (1, 0)
    ga = _whiten(_se_1d(points[:, ax_a], state.nodes_a, length_scale), state.chol_a)
    gb = _whiten(_se_1d(points[:, ax_b], state.nodes_b, length_scale), state.chol_b)
    mean = np.einsum("ij,ij->i", ga @ state.alpha, gb)
    if not return_std:
        return mean, None
    var = 1.0 - np.einsum("ij,ij->i", ga, ga) * np.einsum("ij,ij->i", gb, gb)
    low = state.factor[0]
    for s in range(0, points.shape[0], chunk):
        blk = slice(s, s + chunk)
        rows = (ga[blk, :, None] * gb[blk, None, :]).reshape(-1, state.n_inducing)
        v = sla.solve_triangular(low, rows.T, lower=True, check_finite=False)
        var[blk] += np.einsum("ij,ij->j", v, v)
    return mean, signal_std * np.sqrt(np.maximum(var, 0.0))


def predict_on_grid(
    state: GridState,
    xs: NDArray[np.float64],
    ys: NDArray[np.float64],
    *,
    length_scale: float,
    signal_std: float,
    return_std: bool,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Mean and latent std on the grid ``xs × ys`` as ``(ny, nx)`` images, in Kronecker form."""
    ta, tb = (xs, ys) if state.a_is_x else (ys, xs)
    ga = _whiten(_se_1d(ta, state.nodes_a, length_scale), state.chol_a)  # (na*, ma)
    gb = _whiten(_se_1d(tb, state.nodes_b, length_scale), state.chol_b)  # (nb*, mb)
    mean = ga @ state.alpha @ gb.T  # (na*, nb*)
    std = None
    if return_std:
        ma, mb = state.nodes_a.size, state.nodes_b.size
        b_inv = state.b_inv().reshape(ma * mb * ma, mb)  # rows (a, b, a'), column b'
        ga_pair = (ga[:, :, None] * ga[:, None, :]).reshape(ga.shape[0], ma * ma)
        var = np.empty((ga.shape[0], gb.shape[0]))
        for s in range(0, gb.shape[0], _GRID_CHUNK):
            gbk = gb[s : s + _GRID_CHUNK]
            # T[(a, a'), q] = Σ_{b, b'} g_b[q, b] B⁻¹[a, b, a', b'] g_b[q, b']: one GEMM over b',
            # then a weighted sum over b.
            half = (b_inv @ gbk.T).reshape(ma, mb, ma, -1)
            t = np.einsum("abcq,qb->acq", half, gbk, optimize=True).reshape(ma * ma, -1)
            var[:, s : s + _GRID_CHUNK] = ga_pair @ t
        var += 1.0 - np.outer(np.einsum("ij,ij->i", ga, ga), np.einsum("ij,ij->i", gb, gb))
        std = signal_std * np.sqrt(np.maximum(var, 0.0))
    if state.a_is_x:
        mean = mean.T
        std = None if std is None else std.T
    return mean, std
