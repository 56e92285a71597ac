"""Static equilibrium of a shape-matching body under a poke, for many β at once.

Position-based dynamics steps ``x ← x + α (g(x) − x) + h² f / m``; its steady state, the fixed
point ``x_i − g_i(x) = f_i / k`` with ``k = α m / h²`` (N/m), is solved for directly.

The goal of particle ``i`` in cluster ``c`` is
``g_i^c = t_c + (1 − β) R_c s_i + β (s_i + Π_c (x − p⁰))``, linear in ``x`` except for the rotation
``R_c = polar(A_pq)``. Moving the linear part to the left gives, for the free particles,

    K_β x = (1 − β) M⁻¹ Σ_c R_c s^c + b_β,    K_β = I − M⁻¹ (Σ_c W_c + β Σ_c Π_c),

with ``M`` the number of clusters holding each particle, ``W_c`` the centre-of-mass rows and
``b_β`` the fixed particles' and the force's terms. ``K_β`` is factorised once per β
(:mod:`deformap.msm._linsys`); each iteration recomputes the rotations and back-substitutes (local–
global like projective dynamics, Bouaziz et al. 2014), accelerated by Anderson mixing.

References
----------
Bouaziz, S. et al. (2014). Projective dynamics: fusing constraint projections for fast simulation.
ACM TOG 33(4).
Walker, H. F., Ni, P. (2011). Anderson acceleration for fixed-point iterations. SIAM J. Numer.
Anal. 49(4), 1715–1735.
Johnson, K. L. (1985). Contact Mechanics, §4.2 (Hertz contact of a sphere on a half-space).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap.mechanics import TactileContact, hertz_indentation
from deformap.msm._clusters import Clusters
from deformap.msm._config import ShapeMatchingConfig
from deformap.msm._linsys import StepMatrices

__all__ = ["Equilibrium", "PokeSimulation", "force_weights"]

logger = logging.getLogger(__name__)
Array = NDArray[np.float64]

_ROT_BATCH = 4  # β per rotation batch: larger batches' temporaries fall out of cache
_MAX_WAIT_LOG2 = 6  # after n rejected Anderson steps, 2^min(n, 6) − 1 plain steps follow


@dataclass(frozen=True, kw_only=True)
class PokeSimulation:
    """Equilibria of one poke for ``betas (B,)``: surface ``positions (B, ny, nx, 3)`` metres, each
    β's ``iterations``, ``residual`` (last relative update) and ``converged`` flag
    (:meth:`Equilibrium.solve`), and the calibrated spring ``stiffness_n_per_m``."""

    betas: Array
    positions: Array
    iterations: NDArray[np.int64]
    residual: Array
    converged: NDArray[np.bool_]
    stiffness_n_per_m: float | None = None


def force_weights(rest: Array, fixed: NDArray[np.bool_], contact: TactileContact,
                  spacing: float) -> Array:
    """``(ny, nx)`` shares of the force, summing to 1, on the free particles under the tip: Hertz's
    ``√(1 − d²/ρ²)``, ``ρ = max(tip radius, spacing)`` so that some particle carries the load."""
    rho = max(contact.tip_radius_m, spacing)
    d2 = np.sum((rest[..., :2] - contact.contact_point[:2]) ** 2, axis=-1)
    w = np.sqrt(np.clip(1.0 - d2 / rho**2, 0.0, None))
    w[fixed] = 0.0
    return w / w.sum()


class Equilibrium:
    """``K_β`` for a set of β on one ROI, and the local–global fixed-point iteration; ``system``
    may be shared between equilibria of one ROI."""

    def __init__(self, clusters: Clusters, fixed: NDArray[np.bool_], betas: Array, *,
                 system: StepMatrices | None = None, max_split: float = 0.0,
                 load_scale: Array | None = None):
        self.cl, self.betas = clusters, np.asarray(betas, dtype=float)
        self.load_scale = (np.ones_like(self.betas) if load_scale is None
                           else np.asarray(load_scale, dtype=float))
        self.system = StepMatrices(clusters, fixed) if system is None else system
        self.free, self.fix = self.system.free, self.system.fix
        if self.system.rigid:
            self.rot_weight, self.fit_weight = np.ones_like(self.betas), np.zeros_like(self.betas)
        else:
            self.rot_weight, self.fit_weight = 1.0 - self.betas, self.betas.copy()
        # the factorisation each β steps with, and the splitting's contraction bound
        self.factor_beta = np.empty_like(self.fit_weight)
        for j in np.argsort(self.fit_weight, kind="stable"):
            self.factor_beta[j] = self.system.prepare(self.fit_weight[j], max_split)
        self.split = (self.fit_weight - self.factor_beta) / (1.0 - self.factor_beta)

    def _map(self, x: Array, x_free: Array, active: NDArray[np.int64]) -> Array:
        """One local–global step ``G(x)`` for the free particles of the ``active`` β."""
        cl = self.cl
        out = np.empty((len(active), len(self.free), 3))
        for lo in range(0, len(active), _ROT_BATCH):
            part = active[lo : lo + _ROT_BATCH]
            xa = x[part].reshape(len(part), *cl.shape, 3)
            rot = np.take(cl.rotation_term(xa).reshape(len(part), -1, 3), self.free, axis=1)
            for a, j in enumerate(part, start=lo):
                out[a] = self.system.solve(
                    self.fit_weight[j], self.rot_weight[j] * rot[a - lo] + self.const[j],
                    factor_beta=self.factor_beta[j], x=x_free[j])
        return out

    def solve(self, x_fixed: Array, force: Array, stiffness: float, tol: float, max_iter: int,
              spacing: float, memory: int = 6, x0: Array | None = None,
              ) -> tuple[Array, NDArray[np.int64], Array, NDArray[np.bool_]]:
        """Iterate ``x ← G(x)`` to its fixed point for every β from ``x0 (B, *grid, 3)`` (default
        rest), ``x_fixed (n_fix, 3)``, ``force (n, 3)`` newtons: positions ``(B, *grid, 3)``,
        iterations, residuals ``max‖G(x) − x‖ / max‖G(x) − p⁰‖`` and converged flags.

        Anderson type II (``memory`` steps, Walker & Ni 2011), safeguarded: an extrapolation whose
        residual exceeds its origin's is replaced by the plain step from there with a fresh
        history, and ``n`` rejections in a row add ``2^min(n, 6) − 1`` plain steps. A β stepping
        with a smaller β's factorisation (contraction ``ρ``) stops at ``tol (1 − ρ)``.
        """
        cl, nb = self.cl, len(self.betas)
        rest = cl.rest.reshape(-1, 3)
        self.const = np.empty((nb, len(self.free), 3))
        pull_w, pull_p = self.system.pull(x_fixed)
        load = np.take(force, self.free, axis=0) / stiffness
        for j in range(nb):
            self.const[j] = (self.fit_weight[j] * (self.system.fit_const + pull_p)
                             + pull_w + self.load_scale[j] * load)
        # flat indices: np.take on flattened rows is several times faster than fancy indexing
        flat_free, flat_fix = self.system.flat_free, self.system.flat_fix
        x = np.broadcast_to(rest, (nb, *rest.shape)).copy()
        x_rows = x.reshape(nb, -1)  # a view: x is contiguous
        if x0 is not None:
            x_rows[:, flat_free] = np.take(np.asarray(x0).reshape(nb, -1), flat_free, axis=1)
        x_rows[:, flat_fix] = np.asarray(x_fixed).reshape(-1)
        # the free positions, kept in step with ``x``
        x_free = np.take(x, self.free, axis=1)
        rest_free = np.take(rest, self.free, axis=0)
        nf = len(self.free) * 3
        iters, resid = np.zeros(nb, dtype=np.int64), np.full(nb, np.inf)
        hist_f, hist_g = np.zeros((nb, memory, nf)), np.zeros((nb, memory, nf))
        prev_f, prev_g = np.zeros((nb, nf)), np.zeros((nb, nf))
        # residual at the last accepted point; whether the current point is an extrapolation
        accepted_r, mixed = np.full(nb, np.inf), np.zeros(nb, dtype=bool)
        # history length, plain steps still to take before mixing again, consecutive rejections
        n_hist, wait, rejected = (np.zeros(nb, dtype=np.int64) for _ in range(3))
        active = np.arange(nb)
        floor = 1e-6 * spacing
        stop = tol * (1.0 - self.split)
        for it in range(1, max_iter + 1):
            g = self._map(x, x_free, active)
            f = (g - x_free[active]).reshape(len(active), -1)
            step = np.sqrt(np.max(_row_norm2(f.reshape(g.shape)), axis=1))
            disp = np.sqrt(np.max(_row_norm2(g - rest_free), axis=1))
            r = step / np.maximum(disp, floor)
            grew = r > accepted_r[active]
            resid[active], iters[active] = r, it
            done = r < stop[active]
            x_new = g.reshape(len(active), -1).copy()
            for a, j in enumerate(active.tolist()):
                if done[a]:
                    continue
                if mixed[j] and grew[a]:
                    # safeguard: take the plain step from the last accepted point instead
                    x_new[a] = prev_g[j]
                    n_hist[j], mixed[j] = 1, False
                    rejected[j] += 1
                    wait[j] = 2 ** min(int(rejected[j]), _MAX_WAIT_LOG2) - 1
                    continue
                if mixed[j]:
                    rejected[j] = 0
                accepted_r[j] = r[a]
                mixed[j] = bool(n_hist[j]) and not grew[a] and not wait[j]
                wait[j] = max(int(wait[j]) - 1, 0)
                if mixed[j]:
                    slot = (n_hist[j] - 1) % memory
                    hist_f[j, slot] = f[a] - prev_f[j]
                    hist_g[j, slot] = g[a].ravel() - prev_g[j]
                    m = min(n_hist[j], memory)
                    df, dg = hist_f[j, :m], hist_g[j, :m]
                    gram = df @ df.T
                    gamma = np.linalg.lstsq(gram + 1e-14 * np.trace(gram) * np.eye(m),
                                            df @ f[a], rcond=None)[0]
                    x_new[a] -= gamma @ dg
                    n_hist[j] += 1
                else:
                    n_hist[j] = 1
                prev_f[j], prev_g[j] = f[a], g[a].ravel()
            new = np.where(done[:, None, None], g, x_new.reshape(g.shape))
            x_free[active] = new
            for a, j in enumerate(active.tolist()):
                x_rows[j, flat_free] = new[a].reshape(-1)
            active = active[~done]
            if active.size == 0:
                break
        converged = resid < stop
        if not np.all(converged):
            logger.warning("shape matching did not converge for β = %s within %d iterations",
                           self.betas[~converged], max_iter)
        return x.reshape(nb, *cl.shape, 3), iters, resid, converged


def _row_norm2(v: Array) -> Array:
    """Squared norms ``(..., n)`` of the rows of ``v (..., n, 3)``."""
    return np.asarray(np.einsum("...i,...i->...", v, v))


# positions (B, *body, 3), iterations, residuals and converged flags of Equilibrium.solve
Solution = tuple[Array, NDArray[np.int64], Array, NDArray[np.bool_]]


def calibrate_stiffness(eq0: Equilibrium, x_fixed: Array, weights: Array, contact: TactileContact,
                        config: ShapeMatchingConfig, spacing: float,
                        ) -> tuple[float, Solution | None]:
    """Spring stiffness ``k`` (N/m) at which the β = 0 body ``eq0`` dents like the reference
    half-space, and its solve (``None`` if 8 steps did not match): ``k ← k δ(k) / δ_Hertz`` until
    the force-weighted depth matches Hertz's (Johnson 1985) to 0.1 %, solves to ``coarse_tol``."""
    f_mag = contact.force_n
    force = weights.reshape(-1, 1) * contact.force[None, :]
    rest = eq0.cl.rest.reshape(-1, 3)
    delta_ref = hertz_indentation(f_mag, contact.tip_radius_m, config.reference_modulus_pa,
                                  config.poisson_ratio)
    k = f_mag / delta_ref  # a first guess: one particle carrying the whole load
    x0 = None
    for _ in range(8):
        solution = eq0.solve(x_fixed, force, k, config.coarse_tol, config.max_iter, spacing, x0=x0)
        x = solution[0]
        depth = float(np.sum(weights.ravel() * ((x[0].reshape(-1, 3) - rest) @ contact.direction)))
        ratio = depth / delta_ref
        if abs(ratio - 1.0) < 1e-3:
            return k, solution
        k *= ratio  # depth ∝ 1/k nearly: the scaled equilibrium starts the next solve
        x0 = rest + (x.reshape(1, -1, 3) - rest) / ratio
    return k, None
