"""Overlapping k×k clusters of a particle grid and Müller's shape-matching goals, batched over β.

Every ``k × k`` window of the ``(ny, nx)`` particle grid is a cluster, so there are
``(ny − k + 1) × (nx − k + 1)`` of them. Cluster sums are taken on strided window views of the
grid (a box filter), and the sum of a per-(cluster, member) quantity back onto the particles is
``k²`` shifted slice additions (the box filter's transpose), all batched over a leading β axis.

Two details differ from a literal reading of Müller et al. (2005), both so that the invariants
the method promises hold exactly:

* The linear/quadratic fit is written incrementally, ``A q = s + Π (x − p⁰)`` where ``Π`` is the
  cluster's (mass-weighted, least-squares) projection onto its feature span. With an exact inverse
  this *is* Müller's ``A = A_pq A_qq⁻¹``; with the regularised (truncated) inverse it keeps the rest
  shape an exact fixed point for every β.
* The quadratic features ``sx², sy², …`` are centred on the cluster (mass-weighted mean removed),
  as the linear ones ``s`` already are; with ``t`` the centre of mass, an uncentred quadratic term
  would need an intercept that the goal ``T q̃ + t`` does not have, and β = 1 would then not
  reproduce a quadratic deformation.

References
----------
Müller, M., Heidelberger, B., Teschner, M., Gross, M. (2005). Meshless deformations based on
shape matching. ACM Transactions on Graphics 24(3), 471–478.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

__all__ = ["Clusters", "polar_rotation"]

Array = NDArray[np.float64]


def polar_rotation(a: Array) -> Array:
    """Rotation factor ``R`` of the polar decomposition ``A = R S`` of ``(..., 3, 3)`` matrices.

    Batched SVD ``A = U Σ Vᵀ``, ``R = U diag(1, 1, det(U Vᵀ)) Vᵀ``: always a proper rotation
    (det R = +1), also for the rank-2 ``A_pq`` of a flat cluster, where the missing direction is
    completed as the cross product of the other two.
    """
    u, _, vt = np.linalg.svd(a)
    det = np.linalg.det(u @ vt)
    u[..., :, 2] *= np.where(det < 0.0, -1.0, 1.0)[..., None]
    return u @ vt


class Clusters:
    """Rest-shape data of all clusters, computed once per ROI.

    The particles lie on an index grid of shape ``grid`` (``(ny, nx)`` for a surface sheet or
    ``(nz, ny, nx)`` for a layered body); a cluster is every window of shape ``window`` of it.

    Parameters
    ----------
    rest : (*grid, 3) float, metres
    masses : grid-shaped float
    window : tuple of int
        Cluster window, e.g. ``(k, k)`` or ``(2, k, k)``.
    mode : {"rigid", "linear", "quadratic"}
    regularization : float
        Relative eigenvalue cut-off of the moment matrix (see ``ShapeMatchingConfig``).
    """

    def __init__(self, rest: Array, masses: Array, window: tuple[int, ...], mode: str,
                 regularization: float):
        self.window, self.mode, self.shape = tuple(window), mode, tuple(masses.shape)
        self.cshape = tuple(n - w + 1 for n, w in zip(self.shape, self.window, strict=True))
        self.n_clusters = int(np.prod(self.cshape))
        self.n_members = int(np.prod(self.window))
        self.rest = rest
        mw = self._windows(masses[None, ..., None])[0, ..., 0]  # (C, km)
        self.w = mw / mw.sum(axis=1, keepdims=True)
        p0 = self._windows(rest[None])[0]  # (C, km, 3)
        self.p0 = p0
        self.t0 = np.einsum("cj,cjd->cd", self.w, p0)
        self.s = p0 - self.t0[:, None, :]
        self.ws = self.w[..., None] * self.s
        ones = np.ones((1, self.n_clusters, self.n_members, 1))
        self.count = self.scatter(ones)[0, ..., 0]
        self.hat = None if mode == "rigid" else self._hat_matrices(regularization)

    # -- window gather / scatter -------------------------------------------------------------
    def _windows(self, x: Array) -> Array:
        """``(B, *grid, d)`` → ``(B, C, km, d)`` copies of every window."""
        nd = len(self.shape)
        v = sliding_window_view(x, self.window, axis=tuple(range(1, nd + 1)))
        b, d = x.shape[0], x.shape[-1]
        return np.ascontiguousarray(
            v.reshape(b, self.n_clusters, d, self.n_members).transpose(0, 1, 3, 2)
        )

    def gather(self, x: Array) -> Array:
        """Particle positions ``(B, *grid, 3)`` → cluster members ``(B, C, km, 3)``."""
        return self._windows(x)

    def scatter(self, vals: Array) -> Array:
        """Sum ``(B, C, km, d)`` per-(cluster, member) values onto particles ``(B, *grid, d)``."""
        b, d = vals.shape[0], vals.shape[-1]
        v = vals.reshape(b, *self.cshape, *self.window, d)
        out = np.zeros((b, *self.shape, d))
        nd = len(self.shape)
        for off in np.ndindex(*self.window):
            dst = (slice(None),) + tuple(slice(o, o + c) for o, c in zip(off, self.cshape,
                                                                          strict=True))
            src = (slice(None),) + (slice(None),) * nd + off
            out[dst] += v[src]
        return out

    # -- shape matching ----------------------------------------------------------------------
    def features(self) -> tuple[Array, Array | None]:
        """Centred features ``(C, km, 3)`` ``s / L`` and, in quadratic mode, ``(C, km, 6)`` the
        quadratic terms ``sx², sy², sz², sx sy, sy sz, sz sx`` of ``s / L`` (centred)."""
        radius = np.sqrt(np.einsum("cj,cjd->c", self.w, self.s**2))
        q = self.s / np.maximum(radius, np.finfo(float).tiny)[:, None, None]
        if self.mode != "quadratic":
            return q, None
        x, y, z = q[..., 0], q[..., 1], q[..., 2]
        quad = np.stack([x * x, y * y, z * z, x * y, y * z, z * x], axis=-1)
        quad -= np.einsum("cj,cjf->cf", self.w, quad)[:, None, :]
        return q, quad

    def _projection(self, q: Array, cutoff: Array) -> Array:
        """``Π[i, j] = q_iᵀ A_qq⁺ q_j w_j`` with eigenvalues of ``A_qq`` below ``cutoff`` dropped."""
        aqq = np.einsum("cj,cjf,cjg->cfg", self.w, q, q)
        lam, vec = np.linalg.eigh(aqq)
        keep = lam > cutoff[:, None]
        inv = np.where(keep, 1.0 / np.where(keep, lam, 1.0), 0.0)
        aqq_pinv = np.einsum("cfe,ce,cge->cfg", vec, inv, vec)
        return np.einsum("cif,cfg,cjg,cj->cij", q, aqq_pinv, q, self.w)

    def _hat_matrices(self, regularization: float) -> Array:
        """``(C, km, km)`` weighted least-squares projections onto the feature span.

        The linear features are fitted first and the quadratic ones only on what the linear fit
        leaves (Gram–Schmidt by blocks), so that truncating an ill-determined quadratic direction
        never spoils the exact fit of rigid and affine motions. Both blocks drop eigenvalues below
        ``regularization`` times the largest linear moment.
        """
        q, quad = self.features()
        lam_max = np.linalg.eigvalsh(np.einsum("cj,cjf,cjg->cfg", self.w, q, q))[:, -1]
        cutoff = regularization * lam_max
        hat = self._projection(q, cutoff)
        if quad is not None:
            hat = hat + self._projection(quad - hat @ quad, cutoff)
        return hat

    def rotations(self, xc: Array) -> Array:
        """``(B, C, 3, 3)`` rotations ``R = polar(A_pq)``, ``A_pq = Σ m r sᵀ`` of members ``xc``."""
        return polar_rotation(np.swapaxes(xc, -1, -2) @ self.ws)

    def cluster_goals(self, xc: Array, betas: Array) -> Array:
        """Goals ``g_i^c`` ``(B, C, km, 3)`` of members ``xc (B, C, km, 3)`` for ``betas (B,)``."""
        t = np.einsum("cj,bcjd->bcd", self.w, xc)
        rs = self.s @ np.swapaxes(self.rotations(xc), -1, -2)
        if self.hat is None:
            return t[:, :, None, :] + rs
        beta = betas[:, None, None, None]
        du = xc - self.p0[None]
        fit = self.s[None] + self.hat @ du
        return t[:, :, None, :] + (1.0 - beta) * rs + beta * fit

    def goals(self, x: Array, betas: Array) -> Array:
        """Particle goals ``(B, *grid, 3)``: the mean of ``g_i^c`` over the clusters holding ``i``."""
        g = self.cluster_goals(self.gather(x), betas)
        return self.scatter(g) / self.count[None, ..., None]
