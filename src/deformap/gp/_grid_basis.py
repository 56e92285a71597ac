"""One-dimensional feature maps of the grid GP: whitening, compression and Chebyshev interpolation.

With nodes ``u`` (m,) and k₁(u, u) = L Lᵀ, the whitened features g(t) = L⁻¹ k₁(u, t) have prior
N(0, I), and so do h(t) = Qᵀ g(t) for any orthonormal Q (m, r); DTC with h is exact up to
‖g(tᵢ)‖² − ‖h(tᵢ)‖². Q holds the fewest leading eigenvectors of Σᵢ g(tᵢ) g(tᵢ)ᵀ that leave every
point a residual below ``FEATURE_TOLERANCE``. Along the longer axis the features are interpolated
within short cells from R Chebyshev nodes (:func:`chebyshev_degree`).

References
----------
Titsias 2009 (SGPR; whitened inducing values); Lázaro-Gredilla & Figueiras-Vidal 2009
(inter-domain inducing features); Trefethen 2013, *Approximation Theory and Approximation
Practice*, Ch. 7 (Chebyshev interpolation error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from deformap.gp._exact import cholesky_with_jitter
from deformap.gp._kernels import _se_1d

__all__: list[str] = []

Array = NDArray[np.float64]

#: Largest prior variance (fraction of σₑ²) the features may miss at a point, and twice their
#: interpolation error: the order of the grid's own Nyström residual at its edge.
FEATURE_TOLERANCE = 1e-8
_SAMPLES_PER_LENGTH = 24


@dataclass(frozen=True, kw_only=True)
class AxisBasis:
    """Inducing nodes ``(m,)`` of one axis, the lower Cholesky factor ``(m, m)`` of their kernel
    matrix and the projection Q ``(m, r)`` with orthonormal columns."""

    nodes: Array
    chol: Array
    proj: Array
    length_scale: float

    @property
    def rank(self) -> int:
        return int(self.proj.shape[1])

    def whitened(self, coords: Array) -> Array:
        """``(n, m)`` rows g(t) = L⁻¹ k₁(u, t) for coordinates ``(n,)``."""
        k_1d = _se_1d(coords, self.nodes, self.length_scale)
        return sla.solve_triangular(self.chol, k_1d.T, lower=True, check_finite=False).T

    def features(self, coords: Array) -> Array:
        """``(n, r)`` rows h(t) = Qᵀ g(t)."""
        return self.whitened(coords) @ self.proj


def axis_basis(lo: float, hi: float, nodes: Array, *, length_scale: float, jitter: float,
               max_jitter: float, what: str) -> tuple[AxisBasis, float]:  # fmt: skip
    """The basis of ``nodes`` compressed to the modes of the data range [lo, hi], and the relative
    jitter its Cholesky needed; residuals checked at ``_SAMPLES_PER_LENGTH`` samples per σ_w."""
    chol, jit = cholesky_with_jitter(
        _se_1d(nodes, nodes, length_scale), jitter=jitter, max_jitter=max_jitter, what=what)
    count = max(2, math.ceil((hi - lo) / length_scale * _SAMPLES_PER_LENGTH) + 1)
    samples = np.linspace(lo, hi, count)
    white = sla.solve_triangular(chol[0], _se_1d(samples, nodes, length_scale).T, lower=True,
                                 check_finite=False).T
    _, vecs = np.linalg.eigh(white.T @ white)
    vecs = vecs[:, ::-1]
    coeff = white @ vecs  # in a complete orthonormal basis the residuals are sums of squares
    tail = np.cumsum((coeff**2)[:, ::-1], axis=1)[:, ::-1]  # tail[i, j] = Σ_{k≥j} coeff[i, k]²
    worst = np.append(tail.max(axis=0), 0.0)  # worst residual when keeping j modes
    rank = max(1, int(np.argmax(worst <= FEATURE_TOLERANCE)))
    proj = np.ascontiguousarray(vecs[:, :rank])
    return AxisBasis(nodes=nodes, chol=chol[0], proj=proj, length_scale=length_scale), jit


def chebyshev_degree(half_width: float, length_scale: float, tolerance: float) -> int:
    """Fewest Chebyshev nodes R that interpolate h on a cell of half-width δ within ``tolerance``:
    ‖h − p‖ ≤ 2 (δ/2)^R / R! · max ‖h⁽ᴿ⁾‖ (Hermite–Genocchi), ‖h⁽ᴿ⁾‖² ≤ (2R)! / (R! σ_w^{2R})."""
    if half_width <= 0.0:
        return 1
    for nodes in range(1, 64):
        log_bound = (math.log(2.0) + nodes * math.log(half_width / (2.0 * length_scale))
                     - math.lgamma(nodes + 1)
                     + 0.5 * (math.lgamma(2 * nodes + 1) - math.lgamma(nodes + 1)))
        if log_bound <= math.log(tolerance):
            return nodes
    raise AssertionError("unreachable: the bound falls below any tolerance for δ < σ_w")


def chebyshev_points(count: int) -> Array:
    """The ``count`` roots of T_count on [−1, 1]."""
    return np.cos((2.0 * np.arange(count) + 1.0) * np.pi / (2.0 * count))


def lagrange_weights(t: Array, points: Array) -> Array:
    """``(n, R)`` Lagrange basis polynomials of ``points`` (R,) at ``t`` (n,), both in [−1, 1], in
    product form (not barycentric), so that ``t`` may coincide with a node."""
    count = points.size
    diff = t[:, None] - points[None, :]
    left = np.ones((t.size, count))
    right = np.ones((t.size, count))
    if count > 1:
        left[:, 1:] = np.cumprod(diff[:, :-1], axis=1)
        right[:, :-1] = np.cumprod(diff[:, :0:-1], axis=1)[:, ::-1]
    gaps = points[:, None] - points[None, :]
    np.fill_diagonal(gaps, 1.0)
    return left * right / np.prod(gaps, axis=1)
