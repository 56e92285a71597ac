"""Sparse GP with inducing points on a regular grid: DTC/SGPR predictions in Kronecker form.

With inducing inputs on a grid ``ua × ub`` and the separable kernel, K_uu = σₑ² (K_a ⊗ K_b) and
k_u(p) = σₑ² k_a(p_a) ⊗ k_b(p_b) (Khatri–Rao for many points). DTC needs only M×M algebra (RW2006
§8.3.3; Quiñonero-Candela & Rasmussen 2005; the predictions of Titsias' 2009 SGPR):

    mean(p) = k_u(p)ᵀ Σ⁻¹ K_uf Λ⁻¹ (z − z̄),          Σ = K_uu + K_uf Λ⁻¹ K_fu
    var(p)  = k(p, p) − k_u(p)ᵀ K_uu⁻¹ k_u(p) + k_u(p)ᵀ Σ⁻¹ k_u(p)

K_uu of a fine grid is numerically singular, so everything is whitened by its Kronecker Cholesky
factor L = L_a ⊗ L_b and compressed per axis to the modes the data excite (``_grid_basis``):
h(p) = h_a(p_a) ⊗ h_b(p_b) with h = Qᵀ L⁻¹ k, B = I + σₑ² Hᵀ Λ⁻¹ H (eigenvalues >= 1), and

    mean(p) = h(p)ᵀ B⁻¹ σₑ² Hᵀ Λ⁻¹ (z − z̄)
    var(p)  = σₑ² (1 − ‖h(p)‖² + h(p)ᵀ B⁻¹ h(p)).

On a grid finer than the kernel's resolution the Nyström residual 1 − ‖g‖² is at round-off and
DTC equals the exact GP. Axis ``a`` has more nodes; the flat feature index is ``ia * rb + ib``.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy.linalg import blas, lapack

from deformap.errors import InvalidArgumentError, NotPositiveDefiniteError
from deformap.gp._grid_basis import (
    FEATURE_TOLERANCE,
    AxisBasis,
    axis_basis,
    chebyshev_degree,
    chebyshev_points,
    lagrange_weights,
)

__all__ = ["GRID_BLAS_THREADS", "GRID_MARGIN_FRACTION", "GRID_SPACING_FRACTION", "MAX_INDUCING"]

Array = NDArray[np.float64]

_LOG = logging.getLogger(__name__)

#: Default inducing spacing = σ_w × this: the SE spectrum exp(−σ_w²ω²/4) at the grid's Nyquist
#: frequency π/h is exp(−π²·9/4) ≈ 2e-10, so the grid loses nothing a float64 Cholesky would keep.
GRID_SPACING_FRACTION = 1.0 / 3.0
#: Inducing nodes extend this many σ_w beyond the data's box: the edge's Nyström residual stays low.
GRID_MARGIN_FRACTION = 1.0
#: Largest number of grid nodes accepted (B is at most this size, 8·M² bytes = 1.2 GB).
MAX_INDUCING = 12_000
#: BLAS threads on the grid path (None: unchanged; needs threadpoolctl): its many mid-sized BLAS
#: calls each wait for all their threads.
GRID_BLAS_THREADS: int | None = 1
_BLOCK_BYTES = 32 * 2**20  # bound on the intermediate of one block of cells in the data term
_CELL_WIDTHS = tuple(k / 6.0 for k in range(1, 13))  # candidates (× σ_w) for _cell_layout


@functools.cache
def _thread_controller() -> Any:
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:
        return None
    return ThreadpoolController()  # after numpy and scipy are loaded: it finds their BLAS


@contextlib.contextmanager
def grid_blas_threads() -> Iterator[None]:
    """Limit BLAS to ``GRID_BLAS_THREADS`` threads for the duration (see there)."""
    controller = None if GRID_BLAS_THREADS is None else _thread_controller()
    if controller is None:
        yield
        return
    with controller.limit(limits=GRID_BLAS_THREADS, user_api="blas"):
        yield


@dataclass(kw_only=True)
class GridState:
    """A fitted grid GP: the two axis bases, the factor of B, α̂ = B⁻¹ b and the ma·mb nodes."""

    axis_a: AxisBasis
    axis_b: AxisBasis
    a_is_x: bool
    factor: tuple[Array, bool]
    alpha: Array  # (ra, rb)
    jitter_used: float
    n_inducing: int
    _b_inv: Array | None = field(default=None, repr=False)

    def b_inv_blocks(self) -> Array:
        """``(ra (ra + 1) / 2, rb²)``: the (rb, rb) blocks B⁻¹[(a, ·), (a', ·)] for a ≥ a'
        (``tril_indices(ra)`` order) flattened, computed once; the others are their transposes."""
        if self._b_inv is None:
            inv, info = lapack.dpotri(self.factor[0], lower=1)  # fills the lower triangle only
            if info != 0:
                raise NotPositiveDefiniteError(f"inverting B failed (LAPACK info {info})")
            ra, rb = self.axis_a.rank, self.axis_b.rank
            rows, cols = np.tril_indices(ra)
            blocks = inv.reshape(ra, rb, ra, rb)[rows, :, cols, :]  # (pairs, rb, rb)
            diag = blocks[rows == cols]
            blocks[rows == cols] = np.tril(diag) + np.swapaxes(np.tril(diag, -1), 1, 2)
            self._b_inv = blocks.reshape(rows.size, rb * rb)
        return self._b_inv


def inducing_axis(lo: float, hi: float, spacing: float, margin: float) -> Array:
    """Regular nodes from ``lo − margin`` to at least ``hi + margin`` with step ``spacing``."""
    start = lo - margin
    count = math.ceil((hi + margin - start) / spacing - 1e-9) + 1
    return np.asarray(start + spacing * np.arange(count), dtype=np.float64)


def fit_grid(xy: Array, resid: Array, noise_var: Array, *, length_scale: float, signal_std: float,
             spacing: float, jitter: float, max_jitter: float) -> GridState:
    """Assemble B and b with the Khatri–Rao structure and factorise B."""
    margin = GRID_MARGIN_FRACTION * length_scale
    nodes = [inducing_axis(xy[:, d].min(), xy[:, d].max(), spacing, margin) for d in range(2)]
    m_total = nodes[0].size * nodes[1].size
    if m_total > MAX_INDUCING:
        raise InvalidArgumentError(
            f"the grid method would need {m_total} inducing points (> {MAX_INDUCING}) for this "
            f"data extent; increase `inducing_spacing` (now {spacing:g} m) or `length_scale`, "
            "or use method='exact'")
    a_is_x = nodes[0].size >= nodes[1].size
    ax_a, ax_b = (0, 1) if a_is_x else (1, 0)
    opts = {"length_scale": length_scale, "jitter": jitter, "max_jitter": max_jitter}
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    basis_a, jit_a = axis_basis(lo[ax_a], hi[ax_a], nodes[ax_a], what="K_a", **opts)
    basis_b, jit_b = axis_basis(lo[ax_b], hi[ax_b], nodes[ax_b], what="K_b", **opts)
    weight = signal_std**2 / noise_var  # σe² Λ⁻¹, dimensionless
    hb = basis_b.features(xy[:, ax_b])
    system, rhs = _data_terms(xy[:, ax_a], hb, weight, weight * resid, basis_a)
    system[np.diag_indices_from(system)] += 1.0
    # B = I + σe² Hᵀ Λ⁻¹ H has eigenvalues >= 1: no jitter, and its inverse is well conditioned.
    factor = sla.cho_factor(system, lower=True, overwrite_a=True, check_finite=False)
    alpha = sla.cho_solve(factor, rhs.ravel(), check_finite=False).reshape(rhs.shape)
    return GridState(axis_a=basis_a, axis_b=basis_b, a_is_x=a_is_x, factor=factor, alpha=alpha,
                     jitter_used=max(jit_a, jit_b), n_inducing=m_total)


def _cell_layout(span: float, n: int, ra: int, rb: int, length_scale: float) -> tuple[int, int]:
    """``(cells, nodes per cell R)`` of least flops, 2n (R·rb)² + 2 (ra·rb)² R per cell, over
    ``_CELL_WIDTHS``; R at half the tolerance (the covariance moves by twice the feature error)."""
    best: tuple[float, int, int] | None = None
    for width in _CELL_WIDTHS:
        cells = max(1, math.ceil(span / (width * length_scale) - 1e-9))
        degree = chebyshev_degree(span / cells / 2.0, length_scale, FEATURE_TOLERANCE / 2.0)
        flops = 2.0 * n * (degree * rb) ** 2 + 2.0 * (ra * rb) ** 2 * degree * cells
        if best is None or flops < best[0]:
            best = (flops, cells, degree)
    assert best is not None
    return best[1], best[2]


def _data_terms(coord_a: Array, hb: Array, weight: Array, weighted_resid: Array,
                basis_a: AxisBasis) -> tuple[Array, Array]:
    """σe² Hᵀ Λ⁻¹ H (M, M) and σe² Hᵀ Λ⁻¹ r (ra, rb) for points at ``coord_a`` (n,) with ``hb``.

    Points are binned into cells along ``a``; within a cell h_a(t) = Σ_r ℓ_r(t) h_a(ξ_r) over its
    Chebyshev nodes ξ, so its share is (H_c ⊗ I) E_c (H_c ⊗ I)ᵀ, E_c = Σᵢ wᵢ (ℓᵢ ℓᵢᵀ) ⊗ (h_b,ᵢ
    h_b,ᵢᵀ), and no per-point outer product of length M is formed.
    """
    n, rb = hb.shape
    ra = basis_a.rank
    lo, hi = float(coord_a.min()), float(coord_a.max())
    cells, degree = _cell_layout(hi - lo, n, ra, rb, basis_a.length_scale)
    _LOG.debug("grid GP: %d×%d features, %d cells × %d Chebyshev nodes", ra, rb, cells, degree)
    width = (hi - lo) / cells
    cell = np.zeros(n, np.intp)
    if width > 0.0:
        cell = np.minimum(((coord_a - lo) / width).astype(np.intp), cells - 1)
    centres = lo + width * (np.arange(cells) + 0.5)
    cheb = chebyshev_points(degree)
    h_nodes = basis_a.features((centres[:, None] + 0.5 * width * cheb).ravel())
    h_nodes = h_nodes.reshape(cells, degree, ra)  # features at every cell's Chebyshev nodes
    scaled = np.zeros(n) if width == 0.0 else (coord_a - centres[cell]) / (0.5 * width)
    lag = lagrange_weights(scaled, cheb)
    order = np.argsort(cell, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(cell, minlength=cells))])
    lag, root_hb = lag[order], hb[order] * np.sqrt(weight[order])[:, None]
    resid_hb = hb[order] * weighted_resid[order, None]
    system = np.zeros((ra * rb, ra * rb))
    rhs = np.zeros((ra, rb))  # Σ_p (w r)_p ĥ_a,p ⊗ h_b,p
    step = max(1, _BLOCK_BYTES // (degree * rb * ra * rb * 8))
    for c0 in range(0, cells, step):
        block = range(c0, min(c0 + step, cells))
        gram = np.empty((len(block), degree * rb, degree * rb))
        for i, c in enumerate(block):
            seg = slice(bounds[c], bounds[c + 1])
            rows = (lag[seg, :, None] * root_hb[seg, None, :]).reshape(-1, degree * rb)
            # a full GEMM, not SYRK: the next step reads all of E_c, which SYRK leaves half empty
            np.matmul(rows.T, rows, out=gram[i])
            rhs += h_nodes[c].T @ (lag[seg].T @ resid_hb[seg])
        _spread_cells(system, gram, h_nodes[c0 : block.stop])
    return system, rhs


def _spread_cells(system: Array, gram: Array, h_nodes: Array) -> None:
    """Add Σ_c (H_c ⊗ I) E_c (H_c ⊗ I)ᵀ to ``system`` (M, M) in place, from the E_c in ``gram``
    (cells, R·rb, R·rb) and the H_c in ``h_nodes`` (cells, R, ra)."""
    cells, degree, ra = h_nodes.shape
    rb = gram.shape[1] // degree
    # half[c, r', b', a, b] = Σ_r E_c[r', b', r, b] H_c[r, a]
    half = np.matmul(
        h_nodes.transpose(0, 2, 1)[:, None], gram.reshape(cells, degree * rb, degree, rb))
    # B[(a', b'), (a, b)] += Σ_{c, r'} H_c[r', a'] half[c, r', b', a, b] as Bᵀ += halfᵀ H, in place
    target = system.reshape(ra, rb * ra * rb).T
    out = blas.dgemm(1.0, half.reshape(cells * degree, rb * ra * rb).T,
                     np.asfortranarray(h_nodes.reshape(cells * degree, ra)), beta=1.0, c=target,
                     overwrite_c=1)  # fmt: skip
    if not np.shares_memory(out, system):  # the wrapper copied after all
        target[...] = out


def predict_grid_points(state: GridState, points: Array, *, signal_std: float, return_std: bool,
                        chunk: int = 512) -> tuple[Array, Array | None]:  # fmt: skip
    """Mean (without the constant) and latent std at arbitrary ``(m, 2)`` points."""
    ax_a, ax_b = (0, 1) if state.a_is_x else (1, 0)
    ha = state.axis_a.features(points[:, ax_a])
    hb = state.axis_b.features(points[:, ax_b])
    mean = np.einsum("ij,ij->i", ha @ state.alpha, hb)
    if not return_std:
        return mean, None
    var = 1.0 - np.einsum("ij,ij->i", ha, ha) * np.einsum("ij,ij->i", hb, hb)
    low = state.factor[0]
    for s in range(0, points.shape[0], chunk):
        blk = slice(s, s + chunk)
        rows = (ha[blk, :, None] * hb[blk, None, :]).reshape(-1, low.shape[0])
        v = sla.solve_triangular(low, rows.T, lower=True, check_finite=False)
        var[blk] += np.einsum("ij,ij->j", v, v)
    return mean, signal_std * np.sqrt(np.maximum(var, 0.0))


def predict_on_grid(state: GridState, xs: Array, ys: Array, *, signal_std: float,
                    return_std: bool) -> tuple[Array, Array | None]:  # fmt: skip
    """Mean and latent std on the grid ``xs × ys`` as ``(ny, nx)`` images, in Kronecker form."""
    ta, tb = (xs, ys) if state.a_is_x else (ys, xs)
    ha = state.axis_a.features(ta)  # (na*, ra)
    hb = state.axis_b.features(tb)  # (nb*, rb)
    mean = ha @ state.alpha @ hb.T  # (na*, nb*)
    std = None
    if return_std:
        ra, rb = state.axis_a.rank, state.axis_b.rank
        # T[q, (a, a')] = Σ_{b, b'} h_b[q, b] h_b[q, b'] B⁻¹[a, b, a', b'] for a ≥ a', then
        # var[p, q] = Σ_{a, a'} h_a[p, a] h_a[p, a'] T[q, (a, a')], pairs a > a' counted twice
        rows, cols = np.tril_indices(ra)
        pairs_a = ha[:, rows] * ha[:, cols] * np.where(rows == cols, 1.0, 2.0)
        pairs_b = (hb[:, :, None] * hb[:, None, :]).reshape(hb.shape[0], rb * rb)
        var = pairs_a @ (pairs_b @ state.b_inv_blocks().T).T
        var += 1.0 - np.outer(np.einsum("ij,ij->i", ha, ha), np.einsum("ij,ij->i", hb, hb))
        std = signal_std * np.sqrt(np.maximum(var, 0.0))
    if state.a_is_x:
        mean = mean.T
        std = None if std is None else std.T
    return mean, std
