"""The material law of the stiffening-FEM physics: a continuum foam that stiffens as it is
compressed toward densification (``WorldConfig(physics="stiffening-fem")``; the solve is
:mod:`deformap.world._stiffening_fem`).

A small-strain elastic solid whose volumetric response stiffens toward densification. Each hex
``e`` of the FEM's mesh (:mod:`deformap.world._fem`) has the strain energy

    W_e(u) = ½ uₑᵀ Kₑ(E₀) uₑ + V_e Φ(ε_e),     Φ'(ε) = M₀ ε [(1 − ε/ε_d)^(−m) − 1]  (ε > 0),

``Kₑ(E₀)`` the linear FEM's element stiffness at the block's small-strain modulus ``E₀``
(``modulus_pa``, the world's ground truth), ``ε_e = −(1/V_e) ∫ div u dV`` the element's mean
compressive volumetric strain (linear in its 24 displacements: ``ε_e = cₑ · uₑ``),
``M₀ = E₀ (1 − ν) / ((1 + ν)(1 − 2ν))`` the constrained modulus, ``ε_d`` the world's
``densification_strain`` and ``m`` its ``stiffening_exponent``; ``Φ = 0`` in dilatation
(``ε ≤ 0``). Under confined (uniaxial-strain) compression ``ε`` is the axial strain and the
stress is the column law ``σ = M₀ ε / (1 − ε/ε_d)^m`` of the ``stiffening-foam`` layer, whose
tangent is ``M₀ / (1 − ε/ε_d)²`` for ``m = 1``: the stress rises without bound as the cells close
(Gibson & Ashby 1997, ch. 5: densification at ``ε_d ≈ 1 − 1.4 ρ*/ρ_s``; their ``m = 1`` fit).
``m = 0`` is the linear FEM exactly.

The volumetric strain stiffens because densification is the foam's volume falling to its
solid's (``ε_d`` is a volume fraction); in a foam's uniaxial test (lateral expansion about nil
past the linear range) the axial strain is the volumetric one, and a volumetric term is how
hyperelastic foam laws stiffen (Storåkers 1986). The law is frame-free (no press direction),
shear stays at ``G₀ = E₀ / (2 (1 + ν))``, and at small strain the material is the linear FEM's
(``Φ'' → 0`` as ``ε → 0``). The energy's Hessian, the tangent, is
``K₀ + Σ_e V_e Φ''(ε_e) cₑ cₑᵀ``: the linear stiffness plus one rank-one term per compressed
element, symmetric positive definite and never softer than ``K₀``.

Range: the law holds while every element's ``ε < ε_d`` (the stress is unbounded at ``ε_d``);
small strain (no geometric nonlinearity), like the linear FEM. A strain is an element's mean, so
the stiffening a patch smaller than an element feels is averaged over it.

References
----------
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids: Structure and Properties, 2nd ed., ch. 5.
Cambridge University Press.
Storåkers, B. (1986). On material representation and constitutive branching in finite
compressible elasticity. Journal of the Mechanics and Physics of Solids 34(2), 125–145.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from deformap.world._fem import _CORNERS, FoamBody

__all__ = ["StrainOperator", "strain_operator", "volumetric_stress", "volumetric_tangent"]


def volumetric_stress(strain: NDArray[np.float64], constrained_pa: NDArray[np.float64], *,
                      densification: float, exponent: float) -> NDArray[np.float64]:
    """``Φ'(ε) = M₀ ε [(1 − ε/ε_d)^(−m) − 1]`` for ``ε > 0`` (0 otherwise), in Pa: the stress the
    stiffening adds to the linear solid's; ``inf`` at and past ``ε_d``."""
    eps = np.maximum(np.asarray(strain, dtype=float), 0.0)
    x = eps / densification
    with np.errstate(divide="ignore", invalid="ignore"):
        out = constrained_pa * eps * (np.power(1.0 - x, -exponent) - 1.0)
    return np.where(x < 1.0, out, np.inf)


def volumetric_tangent(strain: NDArray[np.float64], constrained_pa: NDArray[np.float64], *,
                       densification: float, exponent: float) -> NDArray[np.float64]:
    """``Φ''(ε) = M₀ [(1 − x)^(−m) + m x (1 − x)^(−m−1) − 1]``, ``x = ε/ε_d`` (0 for ``ε ≤ 0``):
    the derivative of :func:`volumetric_stress`, continuous at 0 (where it is 0)."""
    eps = np.maximum(np.asarray(strain, dtype=float), 0.0)
    x = eps / densification
    with np.errstate(divide="ignore", invalid="ignore"):
        out = constrained_pa * (np.power(1.0 - x, -exponent)
                                + exponent * x * np.power(1.0 - x, -exponent - 1.0) - 1.0)
    return np.where(x < 1.0, out, np.inf)


@dataclass(frozen=True)
class StrainOperator:
    """One block's elements: ``matrix`` ``(n_free, n_el)`` with column ``e`` the ``cₑ`` of
    ``ε_e = cₑ · u`` (free unknowns only), volumes [m³] and constrained moduli [Pa]."""

    matrix: sp.csc_matrix
    volume: NDArray[np.float64]
    constrained_pa: NDArray[np.float64]


def strain_operator(body: FoamBody) -> StrainOperator:
    """The element-mean compressive volumetric strain of every hex of ``body``: for a corner
    ``(ci, cj, ck)`` of a ``dx × dy × dz`` hex, ``∫ ∂N/∂x dV / V = (2 ci − 1) / (4 dx)`` (the
    divergence theorem on the box), so ``ε = −Σ_c Σ_d (2 c_d − 1) u_{c,d} / (4 Δ_d)``."""
    g = body.grid
    nu = body.poisson_ratio
    rows, cols, vals, volume, modulus = [], [], [], [], []
    count = 0
    for k in range(g.nz):
        dz = float(g.levels[k + 1] - g.levels[k])
        dofs, jj, ii = body.element_dofs(k)
        row = -((2 * _CORNERS - 1) / (4 * np.array([g.dx, g.dy, dz]))).ravel()  # (24,)
        rows.append(dofs.ravel())
        cols.append(np.repeat(np.arange(count, count + len(ii)), 24))
        vals.append(np.tile(row, len(ii)))
        volume.append(np.full(len(ii), g.dx * g.dy * dz))
        modulus.append(body.modulus[k, jj, ii])
        count += len(ii)
    full = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(3 * g.n_nodes, count))
    e = np.concatenate(modulus)
    return StrainOperator(matrix=full[body.free].tocsc(), volume=np.concatenate(volume),
                           constrained_pa=e * (1 - nu) / ((1 + nu) * (1 - 2 * nu)))
