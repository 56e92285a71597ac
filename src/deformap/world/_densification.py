"""The material law of the ``stiffening-fem`` physics (solved in
:mod:`deformap.world._stiffening_fem`): a small-strain elastic solid whose volumetric response
stiffens toward densification. Each hex ``e`` of the FEM's mesh has the strain energy

    W_e(u) = ½ uₑᵀ Kₑ(E₀) uₑ + V_e Φ(ε_e),     Φ'(ε) = M₀ ε [(1 − ε/ε_d)^(−m) − 1]  (ε > 0),

``Kₑ(E₀)`` the linear FEM's element stiffness at the block's ``modulus_pa``, ``ε_e = cₑ · uₑ`` the
element's mean compressive volumetric strain, ``M₀`` the constrained modulus; ``Φ = 0`` in
dilatation. Under confined compression it is the column law ``σ = M₀ ε / (1 − ε/ε_d)^m`` (Gibson &
Ashby 1997, ch. 5), stiffening in volume as hyperelastic foam laws do (Storåkers 1986); ``m = 0``
is the linear FEM. The tangent ``K₀ + Σ_e V_e Φ''(ε_e) cₑ cₑᵀ`` is never softer than ``K₀``.

References
----------
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids, 2nd ed., ch. 5. Cambridge University Press.
Storåkers, B. (1986). Finite compressible elasticity. J. Mech. Phys. Solids 34(2), 125–145.
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
    """``Φ'(ε)`` in Pa, the stress the stiffening adds to the linear solid's (``inf`` from
    ``ε_d``)."""
    eps = np.maximum(np.asarray(strain, dtype=float), 0.0)
    x = eps / densification
    with np.errstate(divide="ignore", invalid="ignore"):
        out = constrained_pa * eps * (np.power(1.0 - x, -exponent) - 1.0)
    return np.where(x < 1.0, out, np.inf)


def volumetric_tangent(strain: NDArray[np.float64], constrained_pa: NDArray[np.float64], *,
                       densification: float, exponent: float) -> NDArray[np.float64]:
    """``Φ''(ε)`` in Pa, the derivative of :func:`volumetric_stress` (0 for ``ε ≤ 0``)."""
    eps = np.maximum(np.asarray(strain, dtype=float), 0.0)
    x = eps / densification
    with np.errstate(divide="ignore", invalid="ignore"):
        out = constrained_pa * (np.power(1.0 - x, -exponent)
                                + exponent * x * np.power(1.0 - x, -exponent - 1.0) - 1.0)
    return np.where(x < 1.0, out, np.inf)


@dataclass(frozen=True)
class StrainOperator:
    """One block's elements: ``matrix`` ``(n_free, n_el)`` of columns ``cₑ``, volumes [m³] and
    constrained moduli [Pa]."""

    matrix: sp.csc_matrix
    volume: NDArray[np.float64]
    constrained_pa: NDArray[np.float64]


def strain_operator(body: FoamBody) -> StrainOperator:
    """The element-mean compressive volumetric strain of every hex of ``body``:
    ``ε = −Σ_c Σ_d (2 c_d − 1) u_{c,d} / (4 Δ_d)`` over corners ``c`` (divergence theorem)."""
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
