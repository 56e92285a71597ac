"""A foam layer on the rigid table as a stiffening two-parameter foundation, and the sphere's
force-controlled contact with it solved by Newton's method (the physics of
:mod:`deformap.world._stiffening`).

Layer (Vlasov & Leontiev 1966; Vallabhan & Das 1988): a block of thickness ``H`` deforms as
``u = (0, 0, −w(x, y) φ(z))``, ``φ`` from 0 at the table to 1 at the top, which gives the Pasternak
energy ``Π[w] = ∫ Φ(w) dA + ½ G_p ∫ |∇w|² dA`` with ``Φ'(w) = p(w) = ∫ σ(w φ') φ' dz`` (32-point
Gauss–Legendre; small-strain spring ``k = M ∫ φ'² dz``, ``M`` the constrained modulus) and
``G_p = G ∫ φ² dz``. The mode shape is ``φ = sinh(γ z / H) / sinh γ`` with
``(γ / H)² = (G / M) ∫ |∇w|² dA / ∫ w² dA`` on the solved surface; ``ℓ = sqrt(G_p / k)`` is how far
a dent spreads. Stiffening (Gibson & Ashby 1997, ch. 5): ``σ(ε) = M ε / (1 − ε / ε_d)^m`` for
``ε ≥ 0``, linear in extension.

Contact: a surface point at distance ``r`` may not pass the sphere's cap,
``w ≥ δ − (R − sqrt(R² − r²))``; the press commands ``F``, so ``Π[w] − F δ`` is minimised over
``w`` and ``δ`` on a tensor grid of bilinear elements (lumped spring, consistent shear) by Newton's
method with a primal–dual active set (Hintermüller, Ito & Kunisch 2002), steps shortened so that no
strain reaches ``ε_d``.

References
----------
Vlasov, V. Z., Leontiev, N. N. (1966). Beams, Plates and Shells on Elastic Foundations.
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids, 2nd ed., Cambridge University Press, ch. 5.
Vallabhan, C. V. G., Das, Y. C. (1988). Beams on elastic foundations. J. Eng. Mech. 114(12).
Hintermüller, M., Ito, K., Kunisch, K. (2002). Primal-dual active set. SIAM J. Optim. 13(3).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from deformap.world._scenario import Block

__all__ = ["MAX_NEWTON_STEPS", "FoundationGrid", "FoundationLayer", "NewtonResult", "solve_press"]

log = logging.getLogger(__name__)

MAX_NEWTON_STEPS = 80  # a press that needs more is reported (logged) as not converged


@dataclass(frozen=True, kw_only=True)
class FoundationLayer:
    """The foundation of one foam block (module docstring): its small-strain modulus, Poisson
    ratio and thickness, ``ε_d``, ``m`` (0: linear), the mode shape's ``γ`` (``decay``; 0:
    ``φ = z / H``) and ``shear`` (False: ``G_p = 0``, a Winkler foundation)."""

    modulus_pa: float
    poisson_ratio: float
    thickness_m: float
    densification_strain: float = 0.95
    stiffening_exponent: float = 1.0
    decay: float = 0.0
    shear: bool = True

    @property
    def constrained_modulus_pa(self) -> float:
        nu = self.poisson_ratio
        return self.modulus_pa * (1 - nu) / ((1 + nu) * (1 - 2 * nu))

    @property
    def shear_modulus_pa(self) -> float:
        return self.modulus_pa / (2 * (1 + self.poisson_ratio))

    def mode(self, z: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``φ(z)`` and ``φ'(z)`` [1/m] at heights ``z`` above the table."""
        h, g = self.thickness_m, self.decay
        if g < 1e-6:
            return z / h, np.full_like(z, 1.0 / h)
        return np.sinh(g * z / h) / np.sinh(g), g / h * np.cosh(g * z / h) / np.sinh(g)

    def _moments(self) -> tuple[float, float]:
        """``∫ φ'² dz`` [1/m] and ``∫ φ² dz`` [m] over the thickness."""
        h, g = self.thickness_m, self.decay
        if g < 1e-6:
            return 1.0 / h, h / 3.0
        s2 = math.sinh(g) ** 2
        half = math.sinh(2 * g) / (4 * g)
        return g * g / h * (half + 0.5) / s2, h * (half - 0.5) / s2

    @property
    def spring_pa_per_m(self) -> float:
        """Small-strain spring modulus ``k = M ∫ φ'² dz`` [Pa/m]."""
        return self.constrained_modulus_pa * self._moments()[0]

    @property
    def shear_n_per_m(self) -> float:
        """Pasternak shear parameter ``G_p = G ∫ φ² dz`` [N/m] (0 without shear)."""
        return self.shear_modulus_pa * self._moments()[1] if self.shear else 0.0

    @property
    def influence_length_m(self) -> float:
        """``ℓ = sqrt(G_p / k)``; 0 without shear."""
        return math.sqrt(self.shear_n_per_m / self.spring_pa_per_m)

    @property
    def max_deflection_m(self) -> float:
        """The deflection at which the quadrature's highest strain reaches ``ε_d`` (inf when
        linear)."""
        if self.stiffening_exponent == 0.0:
            return math.inf
        slope = self.mode(_through_thickness(self.thickness_m)[0])[1]
        return self.densification_strain / float(np.max(slope))

    def decay_for(self, w: NDArray[np.float64], grid: FoundationGrid) -> float:
        """Vallabhan & Das's ``γ`` for the surface deflection ``w`` on ``grid``."""
        ratio = float(w @ (grid.laplacian @ w)) / float(np.sum(grid.area * w * w))
        return self.thickness_m * math.sqrt(self.shear_modulus_pa
                                            / self.constrained_modulus_pa * ratio)

    def pressure(self, w: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Spring pressure ``p(w)`` [Pa] and ``dp/dw`` [Pa/m], elementwise."""
        if self.stiffening_exponent == 0.0:
            return self.spring_pa_per_m * w, np.full_like(w, self.spring_pa_per_m)
        z, weight = _through_thickness(self.thickness_m)
        slope = self.mode(z)[1]  # (q,)
        eps = w[:, None] * slope  # (n, q) strains
        m, ed = self.stiffening_exponent, self.densification_strain
        big_m = self.constrained_modulus_pa
        squeeze = np.where(eps > 0.0, 1.0 - eps / ed, 1.0)
        sigma = big_m * eps * squeeze**-m
        dsigma = big_m * (squeeze**-m + np.where(eps > 0.0, eps * m / ed * squeeze**(-m - 1), 0.0))
        return (sigma * slope) @ weight, (dsigma * slope**2) @ weight


def _through_thickness(thickness_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """32 Gauss–Legendre heights and weights over ``[0, H]``."""
    x, wt = np.polynomial.legendre.leggauss(32)
    return 0.5 * thickness_m * (x + 1.0), 0.5 * thickness_m * wt


@dataclass(frozen=True, kw_only=True)
class FoundationGrid:
    """A tensor grid of bilinear cells over part of one block (nodes outside it dropped)."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    used: NDArray[np.int64]  # flat ids (j * nx + i) of the nodes that belong to active cells
    xy: NDArray[np.float64]  # (n, 2) of the used nodes
    area: NDArray[np.float64]  # (n,) lumped area per node
    laplacian: sp.csr_matrix  # (n, n) ∫ ∇φ_i · ∇φ_j

    @classmethod
    def build(cls, block: Block, x: NDArray[np.float64], y: NDArray[np.float64]
              ) -> FoundationGrid:
        """The grid of nodes ``x × y`` whose cells (centres) lie in ``block``."""
        nx, ny = x.size, y.size
        hx, hy = np.diff(x), np.diff(y)
        cx, cy = np.meshgrid(0.5 * (x[1:] + x[:-1]), 0.5 * (y[1:] + y[:-1]))
        active = block.contains(np.column_stack([cx.ravel(), cy.ravel()]))
        jj, ii = np.divmod(np.flatnonzero(active), nx - 1)
        corners = np.column_stack([jj * nx + ii, jj * nx + ii + 1,
                                   (jj + 1) * nx + ii, (jj + 1) * nx + ii + 1])  # i + 2 j
        ax, ay = hx[ii], hy[jj]
        k1 = np.array([[1.0, -1.0], [-1.0, 1.0]])
        m1 = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
        # bilinear rectangle: Ke = M_y ⊗ K_x + K_y ⊗ M_x (1-D stiffness k1 / h, mass m1 h)
        ke = (np.einsum("c,ab,de->cadbe", ay / ax, m1, k1)
              + np.einsum("c,ab,de->cadbe", ax / ay, k1, m1)).reshape(-1, 4, 4)
        rows = np.repeat(corners, 4, axis=1).ravel()
        cols = np.tile(corners, (1, 4)).ravel()
        full = sp.csr_matrix((ke.ravel(), (rows, cols)), shape=(nx * ny, nx * ny))
        area_full = np.zeros(nx * ny)
        np.add.at(area_full, corners.ravel(), np.repeat(ax * ay / 4.0, 4))
        used = np.flatnonzero(area_full > 0.0)
        gx, gy = np.meshgrid(x, y)
        xy = np.column_stack([gx.ravel()[used], gy.ravel()[used]])
        return cls(x=x, y=y, used=used, xy=xy, area=area_full[used],
                   laplacian=full[used][:, used].tocsr())


@dataclass(frozen=True, kw_only=True)
class NewtonResult:
    """The solved press on one grid: deflections, the tip's sink, the contact, convergence."""

    w: NDArray[np.float64]  # (n,) deflection of the grid's nodes, metres, positive down
    depth_m: float
    active: NDArray[np.bool_]  # nodes in contact with the tip
    contact_force_n: NDArray[np.float64]  # (n,) nodal contact forces (0 off the contact)
    residual_n: float  # largest out-of-balance force (free nodes, and total against F)
    iterations: int
    converged: bool


def solve_press(layer: FoundationLayer, grid: FoundationGrid, center: NDArray[np.float64],
                force_n: float, tip_radius_m: float, depth_guess_m: float,
                start: tuple[NDArray[np.float64], NDArray[np.bool_]] | None = None,
                max_steps: int = MAX_NEWTON_STEPS) -> NewtonResult:
    """Force-controlled sphere contact on the foundation by Newton's method with active sets.

    Unknowns: the deflections off the contact and the tip's sink ``δ`` (on the contact
    ``w = δ − c``); the residual is the gradient of ``Π − F δ``, the Jacobian the reduced tangent
    stiffness (symmetric positive definite while ``ε < ε_d``). ``start`` is a first
    ``(w, active)``; default: the nodes under the tip sunk ``depth_guess_m`` in contact.
    """
    r2 = np.sum((grid.xy - center) ** 2, axis=1)
    cap = np.full(r2.size, np.inf)
    under = r2 < tip_radius_m**2
    cap[under] = tip_radius_m - np.sqrt(tip_radius_m**2 - r2[under])
    w_max = layer.max_deflection_m * (1.0 - 1e-6)
    gp = layer.shear_n_per_m
    n = r2.size
    # start strictly inside the densification limit (a start from another mode shape may not be)
    if start is None:
        active, w = cap <= depth_guess_m, np.zeros(n)
    else:
        w, active = np.minimum(start[0], 0.9 * w_max), start[1] & np.isfinite(cap)
    delta = min(max(depth_guess_m, float(np.max(w, initial=0.0))), 0.9 * w_max)
    active[np.argmin(cap)] = True
    w = np.where(active, delta - cap, w)
    tol = 1e-9 * force_n
    converged, residual, iteration = False, math.inf, 0

    def internal(w: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        sigma, dsigma = layer.pressure(w)
        return grid.area * sigma + gp * (grid.laplacian @ w), grid.area * dsigma

    f, _ = internal(w)
    while iteration < max_steps:
        iteration += 1
        free = np.flatnonzero(~active)
        # w = T x + w0 with x = (w_free, δ): T picks the free nodes and spreads δ on the contact
        t = sp.csr_matrix((np.ones(n), (np.r_[free, np.flatnonzero(active)],
                                        np.r_[np.arange(free.size),
                                              np.full(n - free.size, free.size)])),
                          shape=(n, free.size + 1))
        f, spring = internal(w)
        grad = t.T @ f - np.r_[np.zeros(free.size), force_n]
        jac = (t.T @ (sp.diags(spring) + gp * grid.laplacian) @ t).tocsc()
        # symmetric positive definite: a symmetric fill-reducing ordering, diagonal pivots
        step = -splu(jac, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}).solve(grad)
        dw = t @ step
        rising = dw > 0  # shorten the step so that no column reaches densification
        alpha = 1.0
        if np.any(rising):
            alpha = min(1.0, 0.9 * float(np.min((w_max - w[rising]) / dw[rising])))
        w = w + alpha * dw
        delta += alpha * float(step[-1])
        f, _ = internal(w)
        contact = np.where(active, f, 0.0)
        entering = ~active & (w < delta - cap - 1e-9 * max(delta, 1e-12))
        leaving = active & (contact < -tol)
        residual = max(float(np.max(np.abs(f[~active]), initial=0.0)),
                       abs(float(contact.sum()) - force_n))
        if not entering.any() and not leaving.any() and residual <= tol and alpha == 1.0:
            converged = True
            break
        if entering.any() or leaving.any():
            active = (active & ~leaving) | entering
            if not active.any():
                active[np.argmin(cap)] = True
            w = np.where(active, delta - cap, w)
    if not converged and max_steps == MAX_NEWTON_STEPS:
        log.warning("foundation press did not converge in %d Newton steps (residual %.2e N)",
                    iteration, residual)
    return NewtonResult(w=w, depth_m=float(delta), active=active,
                        contact_force_n=np.where(active, f, 0.0), residual_n=residual,
                        iterations=iteration, converged=converged)
