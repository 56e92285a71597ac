"""Overlapping k×k clusters of a particle grid and Müller's shape-matching goals, batched over β.

Every window of the particle grid is a cluster; cluster sums are box filters, batched over β.
Unlike a literal reading of Müller et al. (2005), so that its invariants hold exactly, the fit is
``A q = s + Π (x − p⁰)`` with ``Π`` the mass-weighted projection onto the feature span (the rest
shape stays a fixed point under truncation), and the quadratic features are centred like ``s``
(so β = 1 reproduces a quadratic deformation).
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

from deformap.msm._polar import fast_polar_rotation, polar_components

__all__ = ["Clusters"]

Array = NDArray[np.float64]


def _cut(axis: int, start: int, stop: int) -> tuple[slice, ...]:
    return (slice(None),) * axis + (slice(start, stop),)


class Clusters:
    """Rest-shape data of the clusters, one per ``window`` (e.g. ``(2, k, k)``), of particles
    ``rest (*grid, 3)``, ``masses (*grid)``; ``mode``, ``regularization`` as in the config."""

    def __init__(self, rest: Array, masses: Array, window: tuple[int, ...], mode: str,
                 regularization: float):
        self.window, self.mode, self.shape = tuple(window), mode, tuple(masses.shape)
        self.cshape = tuple(n - w + 1 for n, w in zip(self.shape, self.window, strict=True))
        self.n_clusters = int(np.prod(self.cshape))
        self.n_members = int(np.prod(self.window))
        self.rest, self.masses = rest, masses
        mw = self.gather(masses[None, ..., None])[0, ..., 0]  # (C, km)
        self.w = mw / mw.sum(axis=1, keepdims=True)
        self.p0 = p0 = self.gather(rest[None])[0]  # (C, km, 3)
        self.t0 = np.einsum("cj,cjd->cd", self.w, p0)
        self.s = p0 - self.t0[:, None, :]
        self.ws = self.w[..., None] * self.s
        ones = np.ones((1, self.n_clusters, self.n_members, 1))
        self.count = self.scatter(ones)[0, ..., 0]
        # eigen-decomposition of the rest moment Σ w s sᵀ: the planar frames and the linear fit
        self._moment = np.linalg.eigh(np.swapaxes(self.ws, 1, 2) @ self.s)
        self.hat = None if mode == "rigid" else self._hat_matrices(regularization)
        self._planar_frames()

    def gather(self, x: Array) -> Array:
        """Particle values ``(B, *grid, d)`` → copies of every window ``(B, C, km, d)``."""
        nd = len(self.shape)
        v = sliding_window_view(x, self.window, axis=tuple(range(1, nd + 1)))
        b, d = x.shape[0], x.shape[-1]
        v = v.reshape(b, self.n_clusters, d, self.n_members)
        return np.ascontiguousarray(v.transpose(0, 1, 3, 2))

    def scatter(self, vals: Array) -> Array:
        """Sum ``(B, C, km, d)`` per-(cluster, member) values onto particles ``(B, *grid, d)``."""
        b, d = vals.shape[0], vals.shape[-1]
        v = vals.reshape(b, *self.cshape, *self.window, d)
        out = np.zeros((b, *self.shape, d))
        nd = len(self.shape)
        for off in np.ndindex(*self.window):
            shifted = (slice(o, o + c) for o, c in zip(off, self.cshape, strict=True))
            dst = (slice(None), *shifted)
            src = (slice(None),) + (slice(None),) * nd + off
            out[dst] += v[src]
        return out

    def features(self) -> tuple[Array, Array | None]:
        """Features ``(C, km, 3)`` ``q = s / L`` and, if quadratic, ``(C, km, 6)`` the centred
        ``qx², qy², qz², qx qy, qy qz, qz qx``."""
        q = self.s / np.maximum(self._radius(), np.finfo(float).tiny)[:, None, None]
        if self.mode != "quadratic":
            return q, None
        x, y, z = q[..., 0], q[..., 1], q[..., 2]
        quad = np.stack([x * x, y * y, z * z, x * y, y * z, z * x], axis=-1)
        quad -= (self.w[:, None, :] @ quad)
        return q, quad

    def _radius(self) -> Array:
        """RMS radius ``√(Σ w |s|²)`` of each cluster (the trace of its rest moment)."""
        return np.asarray(np.sqrt(np.maximum(np.sum(self._moment[0], axis=1), 0.0)))

    def _projection(self, q: Array, cutoff: Array, eig: tuple[Array, Array] | None = None) -> Array:
        """``Π[i, j] = q_iᵀ A_qq⁺ q_j w_j``, dropping eigenvalues of ``A_qq`` below ``cutoff``
        (``eig``: the eigen-decomposition of ``A_qq`` if already known)."""
        wq = self.w[..., None] * q
        lam, vec = np.linalg.eigh(np.swapaxes(wq, 1, 2) @ q) if eig is None else eig
        keep = lam > cutoff[:, None]
        inv = np.where(keep, 1.0 / np.where(keep, lam, 1.0), 0.0)
        aqq_pinv = (vec * inv[:, None, :]) @ np.swapaxes(vec, 1, 2)
        return np.asarray(q @ aqq_pinv @ np.swapaxes(wq, 1, 2))

    def _hat_matrices(self, regularization: float) -> Array:
        """``(C, km, km)`` weighted projections onto the linear features, then the quadratic ones on
        what the linear fit leaves (block Gram–Schmidt: rigid and affine fits stay exact), each
        dropping eigenvalues below ``regularization`` times the largest linear moment."""
        _, quad = self.features()
        lam = self._moment[0]
        hat = self._projection(self.s, regularization * lam[:, -1], self._moment)
        if quad is not None:
            cutoff = regularization * lam[:, -1] / np.maximum(self._radius(),
                                                              np.finfo(float).tiny) ** 2
            hat = hat + self._projection(quad - hat @ quad, cutoff)
        return hat

    def box_sum(self, field: Array) -> Array:
        """Window sums ``(B, *cshape, d)`` of a particle field ``(B, *grid, d)`` (separable)."""
        out = field
        for axis, (w, c) in enumerate(zip(self.window, self.cshape, strict=True), start=1):
            acc = out[_cut(axis, 0, c)].copy()
            for o in range(1, w):
                acc += out[_cut(axis, o, o + c)]
            out = acc
        return out

    def box_spread(self, field: Array) -> Array:
        """Transpose of :meth:`box_sum`: ``(B, *cshape, d)`` → particle sums ``(B, *grid, d)``."""
        out = field
        for axis, (w, c) in enumerate(zip(self.window, self.cshape, strict=True), start=1):
            shape = list(out.shape)
            shape[axis] = c + w - 1
            acc = np.empty(shape)
            acc[_cut(axis, 0, c)] = out  # the first shift copied, not added to zeros
            acc[_cut(axis, c, c + w - 1)] = 0.0
            for o in range(1, w):
                acc[_cut(axis, o, o + c)] += out
            out = acc
        return out

    def _prepare_box(self) -> None:
        # coordinates relative to the rest centroid keep Σ m x p⁰ᵀ − M t t⁰ᵀ free of cancellation
        self._origin = self.rest.reshape(-1, 3).mean(axis=0)
        p0 = (self.rest - self._origin).reshape(*self.shape, 3)
        self._p0c = p0
        self._mp0 = self.masses[..., None] * p0
        self._mass_c = self.box_sum(self.masses[None, ..., None])[0]  # (*cshape, 1)
        self._t0c = self.box_sum(self._mp0[None])[0] / self._mass_c  # (*cshape, 3)
        self._p0c_t = np.ascontiguousarray(np.moveaxis(p0, -1, 0))
        self._t0c_t = np.ascontiguousarray(np.moveaxis(self._t0c, -1, 0))

    def rotation_term(self, x: Array) -> Array:
        """``(1/M_i) Σ_{c∋i} R_c s_i^c`` ``(B, *grid, 3)`` at ``x (B, *grid, 3)`` by box sums
        (``A_pq = Σ m x p⁰ᵀ / M − t t⁰ᵀ``) and spreads (``(Σ_c R_c) p⁰_i − Σ_c R_c t⁰_c``)."""
        if not hasattr(self, "_p0c"):
            self._prepare_box()
        if not np.any(self.planar):
            return self._rotation_term_components(x)
        xm = (x - self._origin) * self.masses[None, ..., None]
        b = x.shape[0]
        field = np.empty((*xm.shape[:-1], 12))
        for d in range(3):
            field[..., 3 * d : 3 * d + 3] = xm[..., d : d + 1] * self._p0c[None]
        field[..., 9:] = xm
        sums = self.box_sum(field) / self._mass_c[None]
        t = sums[..., 9:]
        apq = sums[..., :9].reshape(*sums.shape[:-1], 3, 3) - t[..., :, None] * self._t0c[
            None, ..., None, :]
        rot = self._polar(apq.reshape(b, self.n_clusters, 3, 3)).reshape(apq.shape)
        per_cluster = np.empty((b, *self.cshape, 12))
        per_cluster[..., :9] = rot.reshape(b, *self.cshape, 9)
        per_cluster[..., 9:] = np.einsum("...de,...e->...d", rot, self._t0c[None])
        spread = self.box_spread(per_cluster)
        total_r = spread[..., :9].reshape(b, *self.shape, 3, 3)
        out = np.einsum("...de,...e->...d", total_r, self._p0c[None]) - spread[..., 9:]
        return np.asarray(out / self.count[None, ..., None])

    def _rotation_term_components(self, x: Array) -> Array:
        """:meth:`rotation_term` with every field component-major, ``(12, B, *grid)``."""
        b, shape, cshape = x.shape[0], self.shape, self.cshape
        p0 = self._p0c_t  # (3, *grid)
        xm = np.moveaxis(x - self._origin, -1, 0) * self.masses  # (3, B, *grid)
        field = np.empty((12, b, *shape))
        field[:9] = (xm[:, None] * p0[None, :, None]).reshape(9, b, *shape)
        field[9:] = xm
        sums = self.box_sum(field.reshape(12 * b, *shape, 1)).reshape(12, b, *cshape)
        sums /= self._mass_c[..., 0]
        t = sums[9:]
        apq = sums[:9] - (t[:, None] * self._t0c_t[None, :, None]).reshape(9, b, *cshape)
        rot = polar_components(apq.reshape(9, -1)).reshape(3, 3, b, *cshape)
        per_cluster = np.empty((12, b, *cshape))
        per_cluster[:9] = rot.reshape(9, b, *cshape)
        per_cluster[9:] = np.sum(rot * self._t0c_t[None, :, None], axis=1)
        spread = self.box_spread(per_cluster.reshape(12 * b, *cshape, 1)).reshape(12, b, *shape)
        out = np.sum(spread[:9].reshape(3, 3, b, *shape) * p0[None, :, None], axis=1)
        out -= spread[9:]
        out /= self.count
        return np.moveaxis(out, 0, -1)

    def _planar_frames(self) -> None:
        """Rest normal ``n`` and in-plane axes ``u × v = n`` of the exactly planar clusters."""
        lam, vec = self._moment
        self.planar = lam[:, 0] <= 1e-12 * lam[:, 2]
        self.normal = vec[:, :, 0]
        self.u_axis = vec[:, :, 1]
        self.v_axis = np.cross(self.normal, self.u_axis)

    def _polar(self, apq: Array) -> Array:
        """Polar rotations of ``(B, C, 3, 3)`` matrices; a planar cluster's ``A`` (``A n = 0``) gets
        ``ĉ nᵀ ‖A‖``, ``c = (A u) × (A v)`` added: full rank, same rotation."""
        if np.any(self.planar):
            p = self.planar
            a = apq[:, p]
            c = np.cross(a @ self.u_axis[p][..., None], a @ self.v_axis[p][..., None], axis=-2)
            norm_c = np.linalg.norm(c, axis=-2, keepdims=True)
            scale = np.sqrt(np.sum(a * a, axis=(-2, -1)))[..., None, None]
            c = c / np.maximum(norm_c, np.finfo(float).tiny) * scale
            apq = apq.copy()
            apq[:, p] = a + c * self.normal[p][:, None, :]
        return fast_polar_rotation(apq)

    def rotations(self, xc: Array) -> Array:
        """``(B, C, 3, 3)`` rotations ``R = polar(A_pq)``, ``A_pq = Σ m r sᵀ`` of members ``xc``."""
        return self._polar(np.swapaxes(xc, -1, -2) @ self.ws)

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
        """Particle goals ``(B, *grid, 3)``: the mean of ``g_i^c`` over the clusters of ``i``."""
        g = self.cluster_goals(self.gather(x), betas)
        return self.scatter(g) / self.count[None, ..., None]
