"""The sparse linear part ``K_β`` of the local–global step: assembled once per ROI, one banded
Cholesky factorisation per β.

``K_β = I − M⁻¹ (Σ_c W_c + β Σ_c Π_c)`` restricted to the free particles (see
:mod:`deformap.msm._poke`). ``W_c`` (centre of mass) and ``Π_c`` (the mass-weighted least-squares
fit) are orthogonal projections in the inner product of the particle masses ``m``, so
``S_β = diag(m M) K_β = diag(m M) − diag(m) Σ_c (W_c + β Π_c)`` is symmetric, and positive
definite for β < 1 once a boundary is held fixed (``W_c + β Π_c ≤ I`` with equality only for a
common translation, which the fixed particles forbid). Ordered row by row with the layer index
innermost, the clusters only couple particles ``(k − 1)`` rows apart, so ``S_β`` is a band matrix
of half-width ``(k − 1)(n_x n_z + n_z) + n_z − 1``, and a dense banded Cholesky (LAPACK
``pbtrf``) factorises it several times faster than a general sparse LU, with no pivoting.
``S_β = S₀ − β S₁`` is affine in β, so both bands are assembled once and each β costs one
factorisation only. A matrix that is not positive definite (never expected) falls back to
SuperLU.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.linalg import LinAlgError, cho_solve_banded, cholesky_banded
from scipy.sparse.linalg import splu

from deformap.msm._clusters import Clusters

__all__ = ["StepMatrices"]

Array = NDArray[np.float64]


class StepMatrices:
    """``K_β`` of one ROI's body for any β: coupling to the fixed particles and factorisations.

    Parameters
    ----------
    clusters : Clusters
    fixed : grid-shaped bool
        Particles held at their given positions.
    """

    def __init__(self, clusters: Clusters, fixed: NDArray[np.bool_]):
        n = fixed.size
        self.free = np.flatnonzero(~fixed.ravel())
        self.fix = np.flatnonzero(fixed.ravel())
        idx = np.arange(n).reshape(fixed.shape)[None, ..., None].astype(float)
        members = clusters.gather(idx)[0, ..., 0].astype(np.int64)  # (C, km)
        kk = members.shape[1]
        rows = np.repeat(members[:, :, None], kk, axis=2).ravel()
        cols = np.repeat(members[:, None, :], kk, axis=1).ravel()
        wdat = np.broadcast_to(clusters.w[:, None, :], (members.shape[0], kk, kk)).ravel()
        minv = sp.diags(1.0 / clusters.count.ravel())
        wsum = (minv @ sp.csr_matrix((wdat, (rows, cols)), shape=(n, n))).tocsr()
        hat = clusters.hat
        self.rigid = hat is None
        psum = (sp.csr_matrix((n, n)) if hat is None else
                (minv @ sp.csr_matrix((hat.ravel(), (rows, cols)), shape=(n, n))).tocsr())
        free, fix = self.free, self.fix
        self.couple_w = wsum[free][:, fix].tocsr()
        self.couple_p = psum[free][:, fix].tocsr()
        # β-part of the constant term: M⁻¹ Σ_c (s − Π p⁰); zero when the features span s.
        if hat is None:
            self.fit_const = np.zeros((len(free), 3))
        else:
            c = clusters.s - np.einsum("cij,cjd->cid", hat, clusters.p0)
            summed = clusters.scatter(c[None])[0] / clusters.count[..., None]
            self.fit_const = summed.reshape(n, 3)[free]
        self._scale = (clusters.masses * clusters.count).ravel()[free]
        self._perm = _band_order(fixed)
        wff = wsum[free][:, free]
        pff = psum[free][:, free]
        d = sp.diags(self._scale)
        s0 = (d - d @ wff)[self._perm][:, self._perm]
        s1 = (d @ pff)[self._perm][:, self._perm]
        self._wff, self._pff = wff, pff
        self._bw = int(max(_half_bandwidth(s0), _half_bandwidth(s1)))
        self._band0, self._band1 = _upper_band(s0, self._bw), _upper_band(s1, self._bw)
        self._factors: dict[float, object] = {}

    def couple(self, beta_fit: float) -> sp.csr_matrix:
        """``(n_free, n_fix)`` block that carries the fixed particles into the free rows."""
        return self.couple_w + beta_fit * self.couple_p

    def solve(self, beta_fit: float, rhs: Array) -> Array:
        """``K_β⁻¹ rhs`` for ``rhs (n_free, 3)``; factorises ``K_β`` on first use and keeps it."""
        key = float(beta_fit)
        fac = self._factors.get(key)
        if fac is None:
            fac = self._factor(key)
            self._factors[key] = fac
        if isinstance(fac, np.ndarray):
            out = np.empty_like(rhs)
            out[self._perm] = cho_solve_banded((fac, False), (self._scale[:, None] * rhs)[
                self._perm], check_finite=False)
            return out
        return np.asarray(fac.solve(rhs))  # type: ignore[attr-defined]

    def _factor(self, beta_fit: float) -> object:
        band = self._band0 - beta_fit * self._band1
        try:
            return cholesky_banded(band, lower=False, check_finite=False)
        except LinAlgError:
            kff = sp.identity(len(self.free), format="csc") - (self._wff + beta_fit * self._pff)
            return splu(kff.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1,
                        options={"SymmetricMode": True})


def _band_order(fixed: NDArray[np.bool_]) -> NDArray[np.int64]:
    """Free-particle indices (positions in the free list) sorted row by row, layer innermost."""
    n = fixed.size
    grid = np.arange(n).reshape(fixed.shape)
    if grid.ndim == 3:  # (layers, ny, nx) → (ny, nx, layers)
        grid = grid.transpose(1, 2, 0)
    pos = np.full(n, -1, dtype=np.int64)
    free = ~fixed.ravel()
    pos[free] = np.arange(int(free.sum()))
    order = pos[grid.ravel()]
    return order[order >= 0]


def _half_bandwidth(m: sp.spmatrix) -> int:
    coo = m.tocoo()
    return int(np.max(np.abs(coo.row - coo.col))) if coo.nnz else 0


def _upper_band(m: sp.spmatrix, bw: int) -> Array:
    """LAPACK upper band storage ``ab[bw + i − j, j] = m[i, j]`` for ``i ≤ j``."""
    up = sp.triu(m).tocoo()
    ab = np.zeros((bw + 1, m.shape[0]))
    ab[bw + up.row - up.col, up.col] = up.data
    return ab
