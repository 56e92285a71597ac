"""The sparse linear part ``K_β = I − M⁻¹ (Σ_c W_c + β Σ_c Π_c)`` of the local–global step
(:mod:`deformap.msm._poke`), assembled once per ROI, one banded Cholesky factorisation per β.

``W_c``, ``Π_c`` are mass-orthogonal projections, so ``S_β = diag(m M) K_β = S₀ − β S₁`` is
symmetric, positive definite for β < 1, and banded when ordered row by row, layer innermost. A β
may step with a smaller β′'s factorisation through ``S_β = S_β′ − (β − β′) S₁``. A matrix that
is not positive definite (never expected) falls back to SuperLU.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.linalg import LinAlgError, cholesky_banded, get_lapack_funcs
from scipy.sparse.linalg import splu

from deformap.errors import InvalidArgumentError
from deformap.msm._clusters import Clusters

__all__ = ["StepMatrices"]

Array = NDArray[np.float64]


class StepMatrices:
    """``K_β`` of one ROI's body for any β: coupling to the ``fixed`` particles, factorisations."""

    def __init__(self, clusters: Clusters, fixed: NDArray[np.bool_]):
        n = fixed.size
        is_fixed = fixed.ravel()
        self.free = np.flatnonzero(~is_fixed)
        self.fix = np.flatnonzero(is_fixed)
        # the same as indices into flattened (n, 3) positions
        self.flat_free = (3 * self.free[:, None] + np.arange(3)).ravel()
        self.flat_fix = (3 * self.fix[:, None] + np.arange(3)).ravel()
        nf = len(self.free)
        hat = clusters.hat
        self.rigid = hat is None
        count = clusters.count.ravel()
        mass = clusters.masses.ravel()
        # every nonzero (i, j) of diag(m) Σ_c W_c and diag(m) Σ_c Π_c, each once
        i, j, vw, vp = _pair_sums(clusters)
        pos = np.full(n, -1, dtype=np.int64)
        pos[self.free] = np.arange(nf)
        pos[self.fix] = np.arange(len(self.fix))
        # coupling of the free rows to the fixed particles, M⁻¹ Σ_c (W_c + β Π_c)
        fc = ~is_fixed[i] & is_fixed[j]
        r, c, inv_mm = pos[i[fc]], pos[j[fc]], 1.0 / (mass * count)[i[fc]]
        shape = (nf, len(self.fix))
        self.couple_w = sp.csr_matrix((vw[fc] * inv_mm, (r, c)), shape=shape)
        self.couple_p = sp.csr_matrix((vp[fc] * inv_mm, (r, c)), shape=shape)
        # β-part of the constant term: M⁻¹ Σ_c (s − Π p⁰); zero when the features span s.
        if hat is None:
            self.fit_const = np.zeros((nf, 3))
        else:
            summed = clusters.scatter((clusters.s - hat @ clusters.p0)[None])[0]
            self.fit_const = (summed / clusters.count[..., None]).reshape(n, 3)[self.free]
        self._scale = (mass * count)[self.free]
        self._perm = _band_order(fixed)
        self._unperm = np.argsort(self._perm)
        self._band_scale = self._scale[self._perm]
        # upper triangles of S₀ = diag(m M) − diag(m) Σ_c W_c and S₁ = diag(m) Σ_c Π_c, band order
        band_pos = np.full(n, -1, dtype=np.int64)
        band_pos[self.free[self._perm]] = np.arange(nf)
        ff = ~is_fixed[i] & ~is_fixed[j]
        br, bc = band_pos[i[ff]], band_pos[j[ff]]
        up = br <= bc
        br, bc = br[up], bc[up]
        self._bw = int(np.max(bc - br)) if bc.size else 0
        # the bands' nonzeros as flat indices into LAPACK's band array: S[i, j] = band[bw + i − j, j]
        self._band_shape = (self._bw + 1, nf)
        diag = self._bw + (self._bw + 1) * np.arange(nf)
        at = np.concatenate([(self._bw + br - bc) + (self._bw + 1) * bc, diag])
        self._band_at, slot = np.unique(at, return_inverse=True)
        zeros = np.zeros(nf)
        self._band_v0 = np.bincount(slot, np.concatenate([-vw[ff][up], self._scale[self._perm]]),
                                    minlength=self._band_at.size)
        self._band_v1 = np.bincount(slot, np.concatenate([vp[ff][up], zeros]),
                                    minlength=self._band_at.size)
        self._factors: dict[float, object] = {}
        # factorisations kept (None: all); the least recently used is dropped, its array reused
        self.max_factors: int | None = None
        self._s1_mat: sp.csr_matrix | sp.dia_matrix | None = None
        self._pull: tuple[Array, Array, Array] | None = None
        self._pbtrs = get_lapack_funcs("pbtrs", (np.empty((1, 1)),))

    def pull(self, x_fixed: Array) -> tuple[Array, Array]:
        """``couple_w @ x_fixed`` and ``couple_p @ x_fixed`` (the fixed term is ``w + β p``), cached."""
        last = self._pull
        if last is None or not np.array_equal(last[0], x_fixed):
            x = np.array(x_fixed, dtype=float)
            last = self._pull = (x, np.asarray(self.couple_w @ x), np.asarray(self.couple_p @ x))
        return last[1], last[2]

    def prepare(self, beta_fit: float, max_split: float = 0.0) -> float:
        """The β′ whose factorisation ``beta_fit`` steps with: the largest factorised β′ ≤
        ``beta_fit`` with ``(beta_fit − β′) / (1 − β′) ≤ max_split``, else ``beta_fit`` (factorised)."""
        key = float(beta_fit)
        below = [b for b in self._factors if b <= key and (key - b) / (1.0 - b) <= max_split]
        if key in self._factors or not below:
            self._factor_of(key)
            return key
        return max(below)

    def solve(self, beta_fit: float, rhs: Array, *, factor_beta: float | None = None,
              x: Array | None = None) -> Array:
        """``K_β⁻¹ rhs`` for ``rhs (n_free, 3)``; with ``factor_beta = β′ < beta_fit`` and the free
        positions ``x``, the split step ``K_β′⁻¹ (rhs + (β − β′) M⁻¹ Σ_c Π_c x)``: the same fixed
        point, contraction at most ``(β − β′) / (1 − β′)`` (``S₁ ≥ 0``, ``S_β > 0``)."""
        beta = float(beta_fit)
        key = beta if factor_beta is None else float(factor_beta)
        fac = self._factor_of(key)
        # np.take: several times faster than fancy indexing on (n, 3) rows
        scaled = np.take(rhs, self._perm, axis=0)
        scaled *= self._band_scale[:, None]
        if key != beta:
            if x is None or key > beta:
                raise InvalidArgumentError(
                    "a split step needs `factor_beta` <= `beta_fit` and the positions `x`")
            s1, xp = self._s1(), np.take(x, self._perm, axis=0)
            # per column: faster than scipy's multi-vector product (same sums, same order)
            for d in range(scaled.shape[1]):
                scaled[:, d] += (beta - key) * (s1 @ xp[:, d])
        if isinstance(fac, np.ndarray):
            sol, info = self._pbtrs(fac, scaled, lower=0)
            if info != 0:
                raise LinAlgError(f"banded Cholesky solve failed (LAPACK info {info})")
        else:
            sol = fac.solve(scaled)  # type: ignore[attr-defined]
        return np.take(sol, self._unperm, axis=0)

    def band(self, beta_fit: float, out: Array | None = None) -> Array:
        """``S_β = S₀ − β S₁`` in LAPACK's upper band storage ``(bw + 1, n_free)`` (into ``out``)."""
        if out is None:
            out = np.zeros(self._band_shape, order="F")
        else:
            out.fill(0.0)
        flat = out.T.reshape(-1)  # a view: out.T is row-major
        flat[self._band_at] = self._band_v0 - beta_fit * self._band_v1
        return out

    def _factor_of(self, beta_fit: float) -> object:
        fac = self._factors.pop(beta_fit, None)
        if fac is None:
            reuse = None
            if self.max_factors is not None and len(self._factors) >= max(self.max_factors, 1):
                old = self._factors.pop(next(iter(self._factors)))  # least recently used
                if isinstance(old, np.ndarray):
                    reuse = old
            fac = self._factor(beta_fit, reuse)
        self._factors[beta_fit] = fac  # the most recently used last
        return fac

    def _s1(self) -> sp.csr_matrix | sp.dia_matrix:
        """``S₁`` in band order, full and sparse: by diagonals when they are few (faster), else CSR."""
        if self._s1_mat is None:
            bw, n = self._bw, self._band_shape[1]
            nz = self._band_v1 != 0.0
            r, j = np.divmod(self._band_at[nz], bw + 1)[::-1]
            i = j - (bw - r)  # band[bw + i − j, j] = S[i, j], i ≤ j
            v = self._band_v1[nz]
            off = i != j
            rows = np.concatenate([i, j[off]])
            cols = np.concatenate([j, i[off]])
            csr = sp.csr_matrix((np.concatenate([v, v[off]]), (rows, cols)), shape=(n, n))
            offsets = np.unique(cols - rows)
            dense = offsets.size * n  # the entries of the diagonal storage
            if dense <= 2 * max(csr.nnz, 1):
                with warnings.catch_warnings():  # scipy warns over 100 diagonals, any fill
                    warnings.simplefilter("ignore", sp.SparseEfficiencyWarning)
                    self._s1_mat = csr.todia()
            else:
                self._s1_mat = csr
        return self._s1_mat

    def _factor(self, beta_fit: float, reuse: Array | None = None) -> object:
        band = self.band(beta_fit, reuse)
        try:
            return cholesky_banded(band, overwrite_ab=True, lower=False, check_finite=False)
        except LinAlgError:  # ``band`` was overwritten by the failed factorisation
            return _SparseFallback(self.band(beta_fit), self._bw)


class _SparseFallback:
    """SuperLU of the symmetric band matrix (in band order), solving like ``cho_solve_banded``."""

    def __init__(self, band: Array, bw: int):
        n = band.shape[1]
        diags = [band[bw - k, k:] for k in range(bw + 1)]
        upper = sp.diags(diags, list(range(bw + 1)), shape=(n, n))
        full = (upper + sp.triu(upper, k=1).T).tocsc()
        self._lu = splu(full, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1,
                        options={"SymmetricMode": True})

    def solve(self, rhs: Array) -> Array:
        return np.asarray(self._lu.solve(rhs))


def _pair_sums(clusters: Clusters) -> tuple[NDArray[np.int64], NDArray[np.int64], Array, Array]:
    """Particle pairs ``(i, j)`` sharing a cluster, each once, with ``Σ_c m_i W_c[i, j]`` and
    ``Σ_c m_i Π_c[i, j]`` (zeros if rigid), accumulated per offset of the member pair."""
    shape, window, cshape = clusters.shape, clusters.window, clusters.cshape
    members = np.array(list(np.ndindex(*window)))  # (km, nd) offsets in the window
    n_m, nd = members.shape
    deltas = (members[None, :, :] - members[:, None, :]).reshape(-1, nd)
    uniq, which = np.unique(deltas, axis=0, return_inverse=True)
    which = which.reshape(n_m, n_m)  # which[a, b]: the offset of the pair (a, b)
    sum_w = np.zeros((len(uniq), *shape))
    sum_p = np.zeros((len(uniq), *shape))
    # member-major copies: each (a, b) slice below is then contiguous
    w = np.ascontiguousarray(np.moveaxis(clusters.w.reshape(*cshape, n_m), -1, 0))
    hat = None
    if clusters.hat is not None:
        hat = np.ascontiguousarray(np.moveaxis(clusters.hat.reshape(*cshape, n_m, n_m),
                                               (-2, -1), (0, 1)))
    for a in range(n_m):
        rows = tuple(slice(o, o + c) for o, c in zip(members[a], cshape, strict=True))
        m_a = clusters.masses[rows]
        for b in range(n_m):
            sum_w[which[a, b]][rows] += m_a * w[b]
            if hat is not None:
                sum_p[which[a, b]][rows] += m_a * hat[a, b]
    index = np.arange(int(np.prod(shape))).reshape(shape)
    parts = []
    for k, delta in enumerate(uniq.tolist()):
        src = tuple(slice(max(0, -d), n - max(0, d)) for d, n in zip(delta, shape, strict=True))
        dst = tuple(slice(max(0, d), n - max(0, -d)) for d, n in zip(delta, shape, strict=True))
        parts.append((index[src].ravel(), index[dst].ravel(), sum_w[k][src].ravel(),
                      sum_p[k][src].ravel()))
    i, j, vw, vp = (np.concatenate(p) for p in zip(*parts, strict=True))
    keep = vw != 0.0  # pairs that share no cluster (e.g. the corners of the offset box)
    return i[keep], j[keep], vw[keep], vp[keep]


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
