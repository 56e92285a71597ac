"""A second contact physics: a foam layer as a stiffening two-parameter foundation.

The world's first physics (:mod:`deformap.world._foam`) is 3-D linear elasticity. This one is of
another kind, so that the estimator (derived from a Hertz half-space with a bonded-layer
correction) is checked on a physics it was not derived on.

Layer theory (Vlasov & Leontiev 1966)
-------------------------------------
Each foam block of thickness ``H`` bonded to the rigid table deforms as
``u(x, y, z) = (0, 0, −w(x, y) · z / H)``: vertical displacement only, growing linearly from 0 at
the table to the surface deflection ``w`` (positive down). Integrating the strain energy of that
field through the thickness gives a two-parameter (Pasternak) foundation,

    Π[w] = ∫ Φ(w) dA + ½ G_p ∫ |∇w|² dA,

whose compression is carried by the column strain ``ε = w / H`` at the constrained (oedometric)
modulus ``M = E (1 − ν) / ((1 + ν)(1 − 2ν))`` (lateral strain suppressed by the kinematics), so
``Φ'(w) = σ(w / H)`` with the small-strain spring modulus ``k = M / H`` [Pa/m], and whose shear
layer (``γ = ∇w · z / H``, shear modulus ``G = E / (2 (1 + ν))``) gives ``G_p = G H / 3`` [N/m].
The influence length ``ℓ = sqrt(G_p / k) = H sqrt(G / (3 M))`` (0.31 H at ν = 0.3) is how far a
dent spreads beyond the tip. ``E`` is the block's ``modulus_pa``: the small-strain Young's modulus
stays the world's ground truth.

Stiffening (Gibson & Ashby 1997, ch. 5)
---------------------------------------
Compressing a foam toward densification brings its cell walls into contact and the stress rises
without bound as the strain nears the densification strain ``ε_d``. The column law is

    σ(ε) = M ε / (1 − ε / ε_d)^m      (ε ≥ 0; linear ``M ε`` in extension),

with ``ε_d`` the world's ``densification_strain`` (Gibson & Ashby: ``ε_D ≈ 1 − 1.4 ρ*/ρ_s``;
0.95 for a flexible polyurethane foam of relative density 0.035) and ``m`` its
``stiffening_exponent`` (their densification fit has ``m ≈ 1``; ``m = 0`` is a linear Winkler
spring). The plateau of elastomeric foams (elastic buckling of the cell walls) is left out: this
physics lies on the stiff side of linear elasticity.

Contact, force control, Newton
------------------------------
The rigid sphere of radius ``R`` sinks ``δ`` below the rest surface; a surface point at distance
``r`` from the target may not pass the tip's lower cap: ``w ≥ δ − c(r)``, ``c = R − sqrt(R² − r²)``
(Signorini conditions, with a non-negative contact force where equality holds). The press
commands the force ``F``, so ``δ`` is an unknown and ``Π[w] − F δ`` is minimised. Discretised on a
tensor grid of bilinear elements (lumped spring term, consistent shear term), the active set of
nodes in contact ties ``w = δ − c`` there and Newton's method solves for ``δ`` and the free
deflections; after each step, nodes that penetrate the tip join the active set and nodes whose
contact force pulls leave it (a primal–dual active-set method, Hintermüller, Ito & Kunisch 2002).
Steps are shortened so that no strain reaches ``ε_d``.

Grid: uniform spacing ``s = a / 6`` over a core of ±2 ``a`` around the target (``a`` the contact
radius expected; the press re-grids when the solved contact disc is off by half or more),
cells growing by 1.2 outside it out to 8 ``ℓ`` beyond the core, cut at the block's edge (a free
edge: neighbouring blocks are separate, not glued). Only the block under the target is loaded; a
tip overhanging a neighbour is not stopped by it.

Range: the tip sinks less than its radius and the column strain stays below ``ε_d``; the
kinematics neglect lateral displacement, so the model describes a layer (thin against the
block), not a half-space.

References
----------
Vlasov, V. Z., Leontiev, N. N. (1966). Beams, Plates and Shells on Elastic Foundations. Israel
Program for Scientific Translations (ch. 1: the two-parameter model from the layer's mode shape).
Kerr, A. D. (1964). Elastic and viscoelastic foundation models. J. Appl. Mech. 31(3), 491–498.
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids, 2nd ed., Cambridge University Press, ch. 5.
Hintermüller, M., Ito, K., Kunisch, K. (2002). The primal-dual active set strategy as a semismooth
Newton method. SIAM J. Optim. 13(3), 865–888.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.interpolate import RegularGridInterpolator
from scipy.sparse.linalg import splu
from scipy.special import k0, k1

from deformap.world._foam import Dent, FoamMesh
from deformap.world._scenario import Block, Scenario

__all__ = ["FoundationLayer", "NewtonResult", "StiffeningFoam", "graded_axis", "max_grid_nodes",
           "solve_press"]

log = logging.getLogger(__name__)

_CORE_CELLS_PER_RADIUS = 6  # grid spacing a / 6 over the contact disc
_CORE_RADII = 2.0  # the uniform core spans ±2 a
_GROWTH = 1.2  # cell growth outside the core
_REACH_LENGTHS = 8.0  # the grid reaches 8 ℓ beyond the core (the dent decays as exp(−r / ℓ))
_MAX_NEWTON = 80
_MAX_ROUNDS = 12  # solves a press may take to settle its grid and its mode shape
_DECAY_TOLERANCE = 0.01
_SETTLING_STEPS = 3


@dataclass(frozen=True, kw_only=True)
class FoundationLayer:
    """The foundation parameters of one foam block (see the module docstring).

    Parameters
    ----------
    modulus_pa, poisson_ratio, thickness_m : float
        The block's small-strain Young's modulus, Poisson ratio and thickness.
    densification_strain : float
        ``ε_d``: the strain at which the stress becomes unbounded.
    stiffening_exponent : float
        ``m``; 0 is a linear spring.
    decay : float
        ``γ`` of the mode shape ``φ(z) = sinh(γ z / H) / sinh γ`` (0: linear, ``z / H``).
    shear : bool
        False drops the shear layer (``G_p = 0``: a Winkler foundation).
    """

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
        """``∫ φ'² dz`` [1/m] and ``∫ φ² dz`` [m] over the thickness, in closed form."""
        h, g = self.thickness_m, self.decay
        if g < 1e-6:
            return 1.0 / h, h / 3.0
        s2 = math.sinh(g) ** 2
        half = math.sinh(2 * g) / (4 * g)
        return g * g / h * (half + 0.5) / s2, h * (half - 0.5) / s2

    @property
    def spring_pa_per_m(self) -> float:
        """Small-strain spring modulus ``k = M ∫ φ'² dz`` [Pa/m] (``M / H`` when linear)."""
        return self.constrained_modulus_pa * self._moments()[0]

    @property
    def shear_n_per_m(self) -> float:
        """Pasternak shear parameter ``G_p = G ∫ φ² dz`` [N/m] (``G H / 3`` when linear; 0
        without shear)."""
        return self.shear_modulus_pa * self._moments()[1] if self.shear else 0.0

    @property
    def influence_length_m(self) -> float:
        """``ℓ = sqrt(G_p / k)``; 0 without shear."""
        return math.sqrt(self.shear_n_per_m / self.spring_pa_per_m)

    @property
    def max_deflection_m(self) -> float:
        """The deflection at which the largest strain (at the top) reaches ``ε_d``, as the
        quadrature through the thickness sees it (its highest point): where its pressure is
        unbounded (inf when linear)."""
        if self.stiffening_exponent == 0.0:
            return math.inf
        slope = self.mode(_through_thickness(self.thickness_m)[0])[1]
        return self.densification_strain / float(np.max(slope))

    def decay_for(self, w: NDArray[np.float64], grid: FoundationGrid) -> float:
        """Vallabhan & Das's ``γ`` for the surface deflection ``w`` on ``grid``:
        ``(γ / H)² = (G / M) ∫ |∇w|² dA / ∫ w² dA``."""
        ratio = float(w @ (grid.laplacian @ w)) / float(np.sum(grid.area * w * w))
        return self.thickness_m * math.sqrt(self.shear_modulus_pa
                                            / self.constrained_modulus_pa * ratio)

    def pressure(self, w: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Spring pressure ``p(w) = ∫ σ(w φ') φ' dz`` [Pa] and ``dp/dw`` [Pa/m], elementwise
        (Gauss–Legendre through the thickness; closed form when linear)."""
        if self.stiffening_exponent == 0.0:
            return self.spring_pa_per_m * w, np.full_like(w, self.spring_pa_per_m)
        z, weight = _through_thickness(self.thickness_m)
        slope = self.mode(z)[1]  # (q,)
        eps = w[:, None] * slope  # (n, q) strains
        m, ed, big_m = self.stiffening_exponent, self.densification_strain, \
            self.constrained_modulus_pa
        squeeze = np.where(eps > 0.0, 1.0 - eps / ed, 1.0)
        sigma = big_m * eps * squeeze**-m
        dsigma = big_m * (squeeze**-m + np.where(eps > 0.0, eps * m / ed * squeeze**(-m - 1),
                                                 0.0))
        return (sigma * slope) @ weight, (dsigma * slope**2) @ weight


def _through_thickness(thickness_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """32 Gauss–Legendre heights and weights over ``[0, H]`` (exact for ``φ'²`` polynomials of
    degree 63; ``cosh²(γ z / H)`` to machine precision for the decays met here)."""
    x, wt = np.polynomial.legendre.leggauss(32)
    return 0.5 * thickness_m * (x + 1.0), 0.5 * thickness_m * wt


def graded_axis(center: float, lo: float, hi: float, *, step: float, core: float,
                reach: float) -> NDArray[np.float64]:
    """Node coordinates of one axis: spacing ``step`` within ``core`` of ``center``, then cells
    growing by 1.2 out to ``core + reach``, cut to ``[lo, hi]`` (whose ends become nodes when
    the grid reaches them). ``center`` (inside ``[lo, hi]``) is always a node."""
    offsets = list(np.arange(0.0, core + 0.5 * step, step))
    cell = step
    while offsets[-1] < core + reach:
        cell *= _GROWTH
        offsets.append(offsets[-1] + cell)
    half = np.asarray(offsets)
    axis = np.concatenate([center - half[:0:-1], center + half])
    body = axis[(axis > lo) & (axis < hi)]
    # a node closer to a cut end than a third of the cell before it would make a sliver
    if axis[0] <= lo and body.size > 1 and body[0] - lo < (body[1] - body[0]) / 3 \
            and body[0] != center:
        body = body[1:]
    if axis[-1] >= hi and body.size > 1 and hi - body[-1] < (body[-1] - body[-2]) / 3 \
            and body[-1] != center:
        body = body[:-1]
    return np.concatenate([[lo] if axis[0] <= lo else [], body, [hi] if axis[-1] >= hi else []])


def max_grid_nodes(extent_m: NDArray[np.float64], tip_radius_m: float) -> int:
    """Most nodes of a press grid over a block of ``(2,)`` in-plane ``extent_m``: per axis the
    core (``±2 a`` at spacing ``a / 6``, or coarser when clamped to ``R / 200``; ``a`` at most
    ``sqrt(2) R``, so at most 17 cells a side) and the graded cells out to the block's extent
    on either side, from the finest spacing ``R / 200``."""
    finest = tip_radius_m / 200
    core = math.ceil(_CORE_RADII * math.sqrt(2.0) * _CORE_CELLS_PER_RADIUS)
    count = 1
    for extent in np.asarray(extent_m, dtype=float):
        rings = math.ceil(math.log1p(extent * (_GROWTH - 1) / finest) / math.log(_GROWTH))
        count *= 2 * (core + rings) + 3
    return count


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
                max_steps: int = _MAX_NEWTON) -> NewtonResult:
    """Force-controlled sphere contact on the foundation by Newton's method with active sets.

    Unknowns: the deflections off the contact and the tip's sink ``δ`` (on the contact
    ``w = δ − c``). Their residual is the gradient of ``Π − F δ``: the nodal forces off the
    contact and the contact's total force minus ``F``; its Jacobian is the tangent stiffness
    reduced the same way (symmetric positive definite while ``ε < ε_d``). ``start`` is a first
    ``(w, active)`` (a coarser grid's solution); default: the nodes under the tip sunk
    ``depth_guess_m`` in contact. ``max_steps`` caps the Newton steps (an inexact solve, for
    a press still settling its grid and mode shape).
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
        step = -splu(jac, permc_spec="MMD_AT_PLUS_A",
                     options={"SymmetricMode": True}).solve(grad)
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
    if not converged and max_steps == _MAX_NEWTON:
        log.warning("foundation press did not converge in %d Newton steps (residual %.2e N)",
                    iteration, residual)
    return NewtonResult(w=w, depth_m=float(delta), active=active,
                        contact_force_n=np.where(active, f, 0.0), residual_n=residual,
                        iterations=iteration, converged=converged)


def _depth_guess(layer: FoundationLayer, force_n: float, tip_radius_m: float) -> float:
    """A first sink of the tip, to start Newton near the answer: the sphere as a flat punch of
    radius ``a = sqrt(2 R δ)`` carrying ``F = K(a) δ / 2`` (exact for the linear Winkler layer,
    ``F = π k R δ²``), with the linear Pasternak punch's stiffness
    ``K(a) = π a² k + 2π a sqrt(k G_p) K₁(a/ℓ) / K₀(a/ℓ)``."""
    k, gp, ell = layer.spring_pa_per_m, layer.shear_n_per_m, layer.influence_length_m
    depth = math.sqrt(force_n / (math.pi * k * tip_radius_m))
    for _ in range(30):  # a damped fixed point: K rises with δ
        a = math.sqrt(2 * tip_radius_m * min(depth, tip_radius_m))
        stiffness = math.pi * a * a * k
        if gp > 0.0:
            stiffness += 2 * math.pi * a * math.sqrt(k * gp) * float(k1(a / ell) / k0(a / ell))
        depth = math.sqrt(depth * 2 * force_n / stiffness)
    return depth


class StiffeningFoam(FoamMesh):
    """All foam blocks of a scenario as stiffening foundations (see the module docstring).

    The interface the world uses from :class:`~deformap.world._foam.FoamModel`: ``dent``,
    ``zero_displacement``, ``top_displacement``, ``n_dofs`` and the display mesh
    (``grids``, ``offsets``, ``rest_nodes``, ``n_nodes``).

    Parameters
    ----------
    scenario : Scenario
    element_size_m, top_layer_m, layer_growth : float
        The display mesh (the camera's view of the deformed blocks).
    poisson_ratio, densification_strain, stiffening_exponent : float
    shear : bool
        False drops the shear layer (a Winkler foundation, for checks).
    """

    def __init__(self, scenario: Scenario, *, element_size_m: float, top_layer_m: float,
                 layer_growth: float, poisson_ratio: float, densification_strain: float,
                 stiffening_exponent: float, shear: bool = True) -> None:
        super().__init__(scenario, element_size_m=element_size_m, top_layer_m=top_layer_m,
                         layer_growth=layer_growth)
        self.poisson_ratio = poisson_ratio
        self.layers = {index: FoundationLayer(
            modulus_pa=scenario.blocks[index].modulus_pa, poisson_ratio=poisson_ratio,
            thickness_m=scenario.blocks[index].thickness_m,
            densification_strain=densification_strain,
            stiffening_exponent=stiffening_exponent, shear=shear) for index in self.foam_blocks}
        self.shear = shear
        # the last press's Newton solve and its layer (mode shape), for checks
        self.last: NewtonResult | None = None
        self.last_layer: FoundationLayer | None = None
        self.last_grid: FoundationGrid | None = None

    @property
    def n_dofs(self) -> int:
        """Top nodes of the foam blocks' display meshes (one deflection each); each press
        solves on a grid of its own, graded around the tip."""
        return sum((self.grids[i].nx + 1) * (self.grids[i].ny + 1) for i in self.layers)

    def dent(self, target_xy: NDArray[np.float64], force_n: float, *, tip_radius_m: float,
             initial_radius_m: float | None = None) -> Dent:
        """Solve the press of ``force_n`` newtons at ``target_xy``. ``initial_radius_m`` is the
        contact radius expected, which sets the grid (default: a Winkler foundation's,
        ``a² = 2 R δ`` with ``F = π k R δ²``)."""
        target = np.asarray(target_xy, dtype=float).reshape(2)
        index = self.block_at(target)
        if index is None:
            return Dent(displacement=self.zero_displacement(), depth_m=0.0,
                        contact_radius_m=0.0, iterations=0)
        block = self.scenario.blocks[index]
        layer = replace(self.layers[index], decay=1.0) if self.shear else self.layers[index]
        depth = _depth_guess(layer, force_n, tip_radius_m)
        # the contact disc of a dragged surface is smaller than the cap's sqrt(2 R δ)
        radius = (initial_radius_m if initial_radius_m else
                  math.sqrt(tip_radius_m * min(depth, tip_radius_m)))
        if self.shear:
            # a first mode shape: the influence length of a thick layer, H sqrt(G / 2M) / γ, is
            # about the contact radius (as the solved presses find)
            decay = layer.thickness_m * math.sqrt(
                layer.shear_modulus_pa / (2 * layer.constrained_modulus_pa)) / radius
            layer = replace(layer, decay=max(decay, 0.1))
            depth = _depth_guess(layer, force_n, tip_radius_m)
        lo, hi = block.polygon.min(axis=0), block.polygon.max(axis=0)
        finest, coarsest = tip_radius_m / 200, tip_radius_m / _CORE_CELLS_PER_RADIUS
        iterations, field, grid, reach, grid_step = 0, None, None, 0.0, 0.0
        settled = False
        for _ in range(_MAX_ROUNDS):
            step = min(max(radius / _CORE_CELLS_PER_RADIUS, finest), coarsest)
            if grid is None or not math.isclose(step, grid_step) or \
                    layer.influence_length_m * _REACH_LENGTHS > reach:
                grid_step = step
                reach = 1.5 * _REACH_LENGTHS * layer.influence_length_m + 2 * step
                axes = [graded_axis(float(target[d]), float(lo[d]), float(hi[d]), step=step,
                                    core=_CORE_RADII * radius, reach=reach) for d in (0, 1)]
                grid = FoundationGrid.build(block, *axes)
            start = (np.zeros(len(grid.xy)) if field is None else field(grid.xy[:, ::-1]),
                     np.sum((grid.xy - target) ** 2, axis=1) <= radius**2)
            # while the grid and the mode shape settle, a few Newton steps a round; then in full
            result = solve_press(layer, grid, target, force_n, tip_radius_m, depth, start,
                                 max_steps=_MAX_NEWTON if settled else _SETTLING_STEPS)
            iterations += result.iterations
            depth = result.depth_m
            solved = math.sqrt(float(grid.area[result.active].sum()) / math.pi)
            field = self._field(grid, result.w)
            if settled:
                break
            fits = (4 * step <= solved <= 9 * step or (step == finest and solved < 4 * step)
                    or (step == coarsest and solved > 9 * step))
            decay = layer.decay_for(result.w, grid) if self.shear else 0.0
            settled = fits and abs(decay - layer.decay) <= _DECAY_TOLERANCE * max(layer.decay,
                                                                                  1.0)
            log.debug("foundation press: a=%.5f m, δ=%.5f m, γ=%.3f", solved, depth, decay)
            if settled and result.converged:
                break
            if not fits:
                radius = solved
            layer = replace(layer, decay=decay)
            settled = settled or _ == _MAX_ROUNDS - 2  # the last round solves in full
        assert grid is not None  # _MAX_ROUNDS ≥ 1
        self.last, self.last_layer, self.last_grid = result, layer, grid
        return Dent(displacement=self._displace(layer, index, result.w, grid),
                    depth_m=result.depth_m, contact_radius_m=min(solved, tip_radius_m),
                    iterations=iterations)

    @staticmethod
    def _field(grid: FoundationGrid, w: NDArray[np.float64]) -> RegularGridInterpolator:
        """The deflection as a function of ``(n, 2)`` points ``(y, x)`` (0 off the grid)."""
        full = np.zeros(grid.x.size * grid.y.size)
        full[grid.used] = w
        return RegularGridInterpolator((grid.y, grid.x), full.reshape(grid.y.size, grid.x.size),
                                       bounds_error=False, fill_value=0.0)

    def _displace(self, layer: FoundationLayer, index: int, w: NDArray[np.float64],
                  grid: FoundationGrid) -> NDArray[np.float64]:
        """The display mesh's displacement: ``u_z = −w φ(z)`` in the pressed block."""
        field = self._field(grid, w)
        u = self.zero_displacement()
        off, hex_grid = self.offsets[index], self.grids[index]
        xyz = self.rest_nodes[off:off + hex_grid.n_nodes]
        u[off:off + hex_grid.n_nodes, 2] = -field(xyz[:, [1, 0]]) * layer.mode(xyz[:, 2])[0]
        return u
