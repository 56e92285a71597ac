"""A press on an elastoplastic block: J2 plasticity with linear isotropic hardening, solved by the
FEM under the press's load history, restricted to the elements near the tip.

Small strains; von Mises yield ``f = q − (σ_y + H α)`` with ``q = sqrt(3/2) |s|`` of the deviatoric
stress ``s = 2G (dev ε − ε_p)`` and the equivalent plastic strain ``α``. At each Gauss point
(2×2×2 per trilinear hex) the radial return mapping (Simo & Hughes 1998, §3.3) takes the trial
state back to the yield surface: ``Δα = f / (3G + H)``, ``ε_p += Δα · (3/2) s / q``.

Plastic strain is deviatoric, so its stress is ``2G ε_p`` and equilibrium reads
``K₀ u = f_ext + F_p(ε_p)`` with ``F_p = Σ_gp Bᵀ 2G ε_p w``: each load level iterates the initial
stress method (Zienkiewicz, Valliappan & King 1969), ``u ← K₀⁻¹ (f_ext + F_p(ε_p(u)))`` on the
block's elastic factorisation, until the plastic strains change by less than
:data:`TOLERANCE` of the yield strain, the Hertz patch of ``f_ext`` re-solved
(:meth:`~deformap.world._foam.FoamModel.dent`, with the plastic displacement as its offset) at
each outer pass. Only the hexes whose columns lie within :data:`REACH_TIPS` tip radii of the
press, in the layers above that depth, may yield; the rest of the block stays elastic.

The press is rate-independent: the force held keeps the travel; the unloading retraces the levels
down to contact, and the residual dent is ``K₀⁻¹ F_p`` of the plastic strains then (the last step to
no force taken as elastic: no reverse yielding).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap.world._fem import _CORNERS, FoamBody
from deformap.world._foam import Dent, FoamModel
from deformap.world._materials import Plastic

__all__ = ["MAX_ITERATIONS", "REACH_TIPS", "TOLERANCE", "PlasticPress", "plastic_press"]

log = logging.getLogger(__name__)

REACH_TIPS = 4.0  #: the plastic zone's half-width and depth, in tip radii
TOLERANCE = 1e-3  #: of the yield strain: change of the plastic strains that ends the iteration
MAX_ITERATIONS = 300  #: initial-stress iterations per load level
_OUTER = 4  #: patch re-solves per load level

_GAUSS = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)


def _shape_gradients(dx: float, dy: float, dz: float) -> NDArray[np.float64]:
    """``(8, 8, 3)``: at each Gauss point, each corner's shape-function gradient."""
    out = np.empty((8, 8, 3))
    points = [(a, b, c) for c in _GAUSS for b in _GAUSS for a in _GAUSS]
    size = np.array([dx, dy, dz])
    for g, xi in enumerate(points):
        for c, corner in enumerate(_CORNERS):
            factors = [x if k else 1.0 - x for x, k in zip(xi, corner, strict=True)]
            signs = [1.0 if k else -1.0 for k in corner]
            for d in range(3):
                others = np.prod([factors[e] for e in range(3) if e != d])
                out[g, c, d] = signs[d] * others / size[d]
    return out


class _Zone:
    """The hexes that may yield: their DOFs ``(m, 24)``, shape gradients per layer, volumes."""

    def __init__(self, body: FoamBody, target: NDArray[np.float64], reach_m: float) -> None:
        g = body.grid
        dofs, grads, weights, centres = [], [], [], []
        depth_top = g.levels[-1]
        for k in range(g.nz):
            if depth_top - g.levels[k + 1] >= reach_m:
                continue
            layer, jj, ii = body.element_dofs(k)
            cx = g.origin[0] + (ii + 0.5) * g.dx
            cy = g.origin[1] + (jj + 0.5) * g.dy
            near = (np.abs(cx - target[0]) < reach_m) & (np.abs(cy - target[1]) < reach_m)
            dz = float(g.levels[k + 1] - g.levels[k])
            dofs.append(layer[near])
            centres.append(np.column_stack([
                cx[near] - target[0], cy[near] - target[1],
                np.full(int(near.sum()), depth_top - 0.5 * (g.levels[k] + g.levels[k + 1]))]))
            grads.append(np.broadcast_to(_shape_gradients(g.dx, g.dy, dz),
                                         (int(near.sum()), 8, 8, 3)))
            weights.append(np.full(int(near.sum()), g.dx * g.dy * dz / 8.0))
        self.reach_m = reach_m
        self.centres = np.concatenate(centres)  # (m, 3) hex centres relative to the press
        self.dofs = np.concatenate(dofs)
        self.grads = np.concatenate(grads)  # (m, gauss, corner, 3)
        self.weights = np.concatenate(weights)

    def strains(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(m, 8, 3, 3)`` small strains at the Gauss points of the ``(n_nodes·3,)`` field."""
        ue = u[self.dofs].reshape(-1, 8, 3)
        grad = np.einsum("mci,mgcj->mgij", ue, self.grads)
        return 0.5 * (grad + np.swapaxes(grad, -1, -2))

    def forces(self, stress: NDArray[np.float64], n: int) -> NDArray[np.float64]:
        """``(n,)`` nodal forces ``Σ Bᵀ σ w`` of the ``(m, 8, 3, 3)`` Gauss-point stresses."""
        fe = np.einsum("mgij,mgcj,m->mci", stress, self.grads, self.weights)
        out = np.zeros(n)
        np.add.at(out, self.dofs.ravel(), fe.reshape(len(self.dofs), 24).ravel())
        return out


def return_map(strain: NDArray[np.float64], plastic: NDArray[np.float64],
               alpha: NDArray[np.float64], *, shear_pa: float, material: Plastic
               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The radial return (module docstring) from the committed ``plastic`` strains and ``alpha``
    at total ``strain`` (``(..., 3, 3)``): the new plastic strains and ``alpha``."""
    e = strain - np.trace(strain, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3.0
    s = 2.0 * shear_pa * (e - plastic)
    q = np.sqrt(1.5 * np.sum(s * s, axis=(-2, -1)))
    excess = q - (material.yield_stress_pa + material.hardening_pa * alpha)
    step = np.where(excess > 0.0, excess, 0.0) / (3.0 * shear_pa + material.hardening_pa)
    direction = 1.5 * s / np.where(q > 0.0, q, 1.0)[..., None, None]
    return plastic + step[..., None, None] * direction, alpha + step


@dataclass(frozen=True, kw_only=True)
class PlasticPress:
    """The true indentation at each load level of the ramp and the unloading (metres), the dent
    at the commanded force, and the residual ``(n_nodes, 3)`` displacement at no force."""

    ramp: NDArray[np.float64]
    unloading: NDArray[np.float64]
    held: Dent
    residual: NDArray[np.float64]


def plastic_press(foam: FoamModel, index: int, material: Plastic, target: NDArray[np.float64],
                  *, levels: NDArray[np.float64], unload_forces: NDArray[np.float64],
                  tip_radius_m: float) -> PlasticPress:
    """Load block ``index`` through the forces ``levels``, then unload through ``unload_forces``
    (module docstring)."""
    body = foam.bodies[index]
    off, n_nodes = foam.offsets[index], foam.grids[index].n_nodes
    modulus = foam.scenario.blocks[index].modulus_pa
    shear = modulus / (2.0 * (1.0 + body.poisson_ratio))
    zone = _Zone(body, target, REACH_TIPS * tip_radius_m)
    plastic = np.zeros((len(zone.dofs), 8, 3, 3))
    alpha = np.zeros((len(zone.dofs), 8))
    limit = TOLERANCE * material.yield_stress_pa / (2.0 * shear)
    offset = np.zeros((foam.n_nodes, 3))
    depths: list[float] = []
    dent: Dent | None = None
    held: Dent | None = None
    foam.forget()
    for force in [*levels, *unload_forces]:
        trial = plastic
        for _ in range(_OUTER):
            dent = foam.dent(target, float(force), tip_radius_m=tip_radius_m,
                             initial_radius_m=dent.contact_radius_m if dent else None,
                             offset=offset)
            assert dent.solved is not None
            elastic = (dent.solved - offset)[off:off + n_nodes].ravel()
            trial, change = _iterate(body, zone, elastic, plastic, alpha, shear, material, limit)
            offset[off:off + n_nodes] = _plastic_displacement(body, zone, trial, shear)
            if change <= limit:
                break
        plastic, alpha = trial, return_map(
            zone.strains(elastic + offset[off:off + n_nodes].ravel()), plastic, alpha,
            shear_pa=shear, material=material)[1]
        assert dent is not None
        depths.append(dent.depth_m)
        if held is None and force == levels[-1]:
            held = dent
    assert held is not None
    _check_zone(zone, alpha)
    residual = np.zeros((foam.n_nodes, 3))
    residual[off:off + n_nodes] = _plastic_displacement(body, zone, plastic, shear)
    return PlasticPress(ramp=np.array(depths[:levels.size]),
                        unloading=np.array(depths[levels.size:]), held=held, residual=residual)


def _check_zone(zone: _Zone, alpha: NDArray[np.float64]) -> None:
    """Warn when the yielded hexes reach the zone's outer quarter: the zone is too small."""
    edge = np.max(np.abs(zone.centres), axis=1) > 0.75 * zone.reach_m
    if np.any(alpha[edge] > 0.0):
        log.warning("plastic press: the material yields within a quarter of the plastic zone's "
                    "edge (%.3g m from the press); the elastic rest of the block bounds it",
                    zone.reach_m)


def _plastic_displacement(body: FoamBody, zone: _Zone, plastic: NDArray[np.float64],
                          shear: float) -> NDArray[np.float64]:
    """``(n_nodes, 3)`` ``K₀⁻¹ F_p`` of the plastic strains."""
    f = zone.forces(2.0 * shear * plastic, 3 * body.grid.n_nodes)
    u = np.zeros(3 * body.grid.n_nodes)
    u[body.free] = body.solve_free(f[body.free])
    return u.reshape(-1, 3)


def _iterate(body: FoamBody, zone: _Zone, elastic: NDArray[np.float64],
             plastic: NDArray[np.float64], alpha: NDArray[np.float64], shear: float,
             material: Plastic, limit: float) -> tuple[NDArray[np.float64], float]:
    """Initial-stress iterations at a fixed load: the plastic strains of the converged level and
    the last change (max over the Gauss points)."""
    trial, change = plastic, np.inf
    for _ in range(MAX_ITERATIONS):
        u = elastic + _plastic_displacement(body, zone, trial, shear).ravel()
        new = return_map(zone.strains(u), plastic, alpha, shear_pa=shear, material=material)[0]
        change = float(np.max(np.abs(new - trial))) if new.size else 0.0
        trial = new
        if change <= limit:
            break
    else:
        log.warning("plastic press: the initial-stress iterations stopped after %d with a "
                    "plastic strain change of %.3g (tolerance %.3g)", MAX_ITERATIONS, change, limit)
    return trial, change
