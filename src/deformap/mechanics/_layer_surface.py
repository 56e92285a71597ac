"""The surface of an elastic layer bonded to a rigid base about a sphere pressed into it.

A normal pressure ``p(r)`` on a layer of thickness ``h`` bonded to a rigid base (its top free of
shear) sinks the surface by (Lebedev & Ufliand 1958; Sneddon 1951, ch. 10 for the Hankel
transform)

    w(r) = (2 / E*) ∫₀^∞ p̂(ξ) L(ξh) J₀(ξr) dξ,    p̂(ξ) = ∫₀^∞ p(s) J₀(ξs) s ds,
    L(u) = (2κ sinh 2u − 4u) / (2κ cosh 2u + 1 + κ² + 4u²),    κ = 3 − 4ν,

``L → 1`` for a deep layer (Boussinesq's half-space) and ``L ≈ u (1 − 2ν) / (2 (1 − ν)²)`` for a
thin one (the constrained modulus). Under the sphere the pressure is taken as Hertz's,
``p ∝ √(1 − r² / a²)`` with ``a = √(Rδ)``, the first-order picture of Dimitriadis et al. (2002),
whose ``α₀`` is this kernel's ``−∫₀^∞ (1 − L(u)) du``. Then ``p̂(ξ) ∝ a³ j(ξa)``,
``j(k) = (sin k − k cos k) / k³``, and the layer's surface is Hertz's less the part of the
half-space's deflection the base takes away:

    w(r) = w_H(r) − (4 a³ / (π R)) ∫₀^∞ j(ξa) (1 − L(ξh)) J₀(ξr) dξ,

``w_H`` Hertz's surface for contact radius ``a`` (Johnson 1985, §3.4). The profile is scaled to
the depth ``δ`` at its centre: the shape is the layer's, the depth the caller's.

Hertz's pressure under the sphere is the first-order picture: it holds while the contact is small
against the layer, ``χ = a / h ≲ 1`` (where the bonded layer's force series holds); beyond, the
shape is approximate, and past :data:`MAX_CHI` (a contact many layers wide, where the sphere would
pass through the surface drawn) the function refuses. The layer's sink decays within a few ``h``
outside the contact (the kernel's deficit ``1 − L`` vanishes there), so it is taken as zero beyond
``a +`` :data:`_FAR_LAYERS` ``h``, which also bounds the quadrature.

References
----------
Lebedev, N. N., Ufliand, Ia. S. (1958). Axisymmetric contact problem for an elastic layer.
J. Appl. Math. Mech. (PMM) 22(3), 442–450.
Sneddon, I. N. (1951). Fourier Transforms. McGraw-Hill.
Dimitriadis, E. K., et al. (2002). Elastic moduli of thin layers of soft material by AFM.
Biophysical Journal 82(5), 2798–2810.
Johnson, K. L. (1985). Contact Mechanics, §3.4. Cambridge University Press.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.special import j0

from deformap._validation import check_positive
from deformap.errors import InvalidArgumentError
from deformap.mechanics._hertz import hertz_surface_at_depth

__all__ = ["MAX_CHI", "layer_surface_deflection"]

# ξh up to 30 (1 − L < 1e-22 beyond), in steps of at most 0.05 and at least 16 a period of
# J₀(ξr) at the farthest point (the trapezoid rule)
_U_MAX = 30.0
_U_STEP = 0.05
_STEPS_PER_PERIOD = 16
# the correction is evaluated on this many radii out to the farthest point and interpolated
_RADII = 64
#: Largest contact radius over thickness drawn: ten layers wide is far outside the first-order
#: picture, and the quadrature grows as ``χ``.
MAX_CHI = 10.0
# the sink is taken as zero beyond a + 20 h: a bonded layer's surface load spreads over a few h
# (1 − L(u) vanishes as e^(−2u) for u ≫ 1), and the quadrature's residual there is far below
# the camera's resolution
_FAR_LAYERS = 20.0


def _kernel_deficit(u: NDArray[np.float64], nu: float) -> NDArray[np.float64]:
    """``1 − L(u)`` (module docstring), written to stay finite for large ``u``."""
    kappa = 3.0 - 4.0 * nu
    e = np.exp(-2.0 * u)
    # multiply L's numerator and denominator by 2 e^(−2u)
    num = 2.0 * kappa * (1.0 - e * e) - 8.0 * u * e
    den = 2.0 * kappa * (1.0 + e * e) + 2.0 * (1.0 + kappa**2 + 4.0 * u * u) * e
    return np.asarray(1.0 - num / den)


def _j(k: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(sin k − k cos k) / k³``, ``1/3`` at ``k = 0``."""
    small = k < 1e-3
    ks = np.where(small, 1.0, k)
    return np.asarray(np.where(small, 1.0 / 3.0 - k * k / 30.0,
                               (np.sin(ks) - ks * np.cos(ks)) / ks**3))


def layer_surface_deflection(r: Any, depth_m: float, tip_radius_m: float, thickness_m: float,
                             poisson_ratio: float) -> NDArray[np.float64]:
    """Downward deflection ``w(r)`` [m] (the shape of ``r``, metres from the contact's centre)
    of a bonded layer's surface about a sphere of radius ``R`` sunk ``δ = depth_m`` into it
    (module docstring); ``w(0) = δ``; Hertz's surface as ``h → ∞``. ``ν`` in ``[0, 0.5]``."""
    depth = check_positive("depth_m", depth_m)
    radius = check_positive("tip_radius_m", tip_radius_m)
    h = check_positive("thickness_m", thickness_m)
    nu = check_positive("poisson_ratio", poisson_ratio, allow_zero=True)
    if nu > 0.5:
        raise InvalidArgumentError(f"`poisson_ratio` must lie in [0, 0.5]; got {nu}")
    r = np.abs(np.asarray(r, dtype=float))
    if not np.all(np.isfinite(r)):
        raise InvalidArgumentError("`r` must hold finite distances in metres")
    a = np.sqrt(radius * depth)
    if a / h > MAX_CHI:
        raise InvalidArgumentError(
            f"the contact radius √(R·depth) = {a * 1e3:.3g} mm is {a / h:.3g} times "
            f"`thickness_m` ({h:g} m); the layer's surface is drawn up to {MAX_CHI:g}")
    far = a + _FAR_LAYERS * h
    beyond = r > far
    r = np.where(beyond, far, r)
    hertz = hertz_surface_at_depth(r, depth, radius)
    radii = np.linspace(0.0, max(float(r.max(initial=0.0)), a), _RADII)
    step = min(_U_STEP, 2.0 * np.pi * h / (_STEPS_PER_PERIOD * max(float(radii[-1]), h)))
    u = np.linspace(0.0, _U_MAX, int(np.ceil(_U_MAX / step)) + 1)
    weight = _j(u * a / h) * _kernel_deficit(u, nu)
    integrand = weight[None, :] * j0(np.outer(radii, u) / h)
    correction = 4.0 * a**3 / (np.pi * radius * h) * np.trapezoid(integrand, u, axis=1)
    w = hertz - np.interp(r, radii, correction)
    return np.asarray(np.where(beyond, 0.0, w * depth / (depth - correction[0])))
