"""A rigid sphere pressed into a layer that acts as a two-parameter (Vlasov) foundation.

A layer of thickness ``h`` on a rigid base that deforms only vertically, ``u_z = −w(x, y) φ(z)``
with ``φ(0) = 0`` at the base and ``φ(h) = 1`` at the top, is a Pasternak foundation (Vlasov &
Leontiev 1966; Kerr 1964): the surface pressure is ``p = k w − G_p ∇²w`` with the spring
``k = M ∫ φ'² dz`` and the shear parameter ``G_p = G ∫ φ² dz``, ``M = E (1 − ν) / ((1 + ν)(1 − 2ν))``
the constrained modulus and ``G = E / (2 (1 + ν))``. The mode is ``φ = sinh(γ z / h) / sinh γ``
with Vallabhan & Das's (1988) ``γ² = h² (G / M) ∫ |∇w|² dA / ∫ w² dA`` of the deflected surface,
found by fixed-point iteration.

Under a frictionless sphere of radius ``R`` with contact radius ``a`` the surface follows the cap,
``w = δ − r² / (2R)`` for ``r ≤ a``, and outside it solves ``ℓ² ∇²w = w`` with
``ℓ = √(G_p / k)``: ``w = C K₀(r / ℓ)``. Continuity of ``w`` and of its slope at ``a`` (a smooth
tip carries no line load at its edge) gives, with ``x = a / ℓ``,

    δ = a² / (2R) + (a ℓ / R) K₀(x) / K₁(x),
    F = ∫ p dA = π k (δ a² − a⁴ / (4R)) + 2π G_p a² / R.

As ``G_p → 0`` this is the Winkler sphere, ``F = π k R δ²``. The layer's material is linear: a
foam that stiffens as it is compressed presses harder than this at depth.

References
----------
Vlasov, V. Z., Leontiev, N. N. (1966). Beams, Plates and Shells on Elastic Foundations. Israel
Program for Scientific Translations (ch. 1, the two-parameter foundation).
Kerr, A. D. (1964). Elastic and viscoelastic foundation models. J. Appl. Mech. 31(3), 491–498.
Vallabhan, C. V. G., Das, Y. C. (1988). Modified Vlasov model for beams on elastic foundations.
J. Geotech. Eng. 117(6) (the mode's decay γ from the surface's shape).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.special import k0e, k1e

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError

__all__ = ["foundation_indentation", "foundation_surface_deflection"]

_DECAY_ROUNDS = 60


def _moments(decay: NDArray[np.float64], thickness: float
             ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``∫ φ'² dz`` [1/m] and ``∫ φ² dz`` [m] of ``φ = sinh(γ z / h) / sinh γ`` over ``[0, h]``."""
    g = np.maximum(decay, 1e-4)
    # sinh(2γ) / (4γ sinh²γ) and 1 / (2 sinh²γ), written to stay finite for large γ
    e = np.exp(-2.0 * g)
    coth = (1.0 + e) / (1.0 - e)
    inv_s2 = 4.0 * e / (1.0 - e) ** 2
    half = coth / (2.0 * g)
    slope2 = g * g / thickness * (half + 0.5 * inv_s2)
    value2 = thickness * (half - 0.5 * inv_s2)
    # γ → 0: φ = z / h, the moments 1/h and h/3 (the series above loses its digits there)
    small = decay < 1e-2
    slope2 = np.where(small, (1.0 + g**4 / 45.0) / thickness, slope2)
    value2 = np.where(small, thickness * (1.0 / 3.0 - 2.0 * g * g / 45.0), value2)
    return slope2, value2


def _decay_map(decay: NDArray[np.float64], a: NDArray[np.float64], radius: float, h: float,
               shear_over_m: float) -> NDArray[np.float64]:
    """Vallabhan & Das's ``γ`` of the surface that the mode of decay ``decay`` gives."""
    slope2, value2 = _moments(decay, h)
    ell = np.sqrt(shear_over_m * value2 / slope2)
    x = a / ell
    c1 = a / radius * ell  # C K₁(x) = −ℓ w'(a)
    w_a = c1 * k0e(x) / k1e(x)
    depth = a * a / (2.0 * radius) + w_a
    # ∫ w² r dr and ∫ |w'|² r dr inside (the cap) and outside (C K₀, closed forms)
    in_sq = radius / 3.0 * (depth**3 - w_a**3)
    in_grad = a**4 / (4.0 * radius**2)
    out_sq = ell**2 * x * x / 2.0 * (c1 * c1 - w_a * w_a)
    out_grad = x * x / 2.0 * (w_a * w_a - c1 * c1) + x * w_a * c1
    return np.asarray(h * np.sqrt(shear_over_m * (in_grad + out_grad) / (in_sq + out_sq)))


def _solve(a: NDArray[np.float64], radius: float, h: float, nu: float
           ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``ℓ`` [m], ``k / E`` [1/m] and ``G_p / E`` [m] at contact radii ``a`` (module docstring).

    ``γ`` is the root of ``f(x) = log Γ(eˣ) − x``, ``Γ`` the map :func:`_decay_map`, from the
    larger of ``Γ(0)`` and the deep layer's ``γ`` (``ℓ ≈ a``): one fixed-point round, then
    secant steps in ``x``, each at most four fixed-point steps long (a safeguard where ``f`` is
    flat), until every entry's step is below ``10⁻¹²``."""
    shear_over_m = (1.0 - 2.0 * nu) / (2.0 * (1.0 - nu))  # G / M

    def f(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(np.log(_decay_map(np.exp(x), a, radius, h, shear_over_m)) - x)

    x0 = np.maximum(np.log(_decay_map(np.zeros_like(a), a, radius, h, shear_over_m)),
                    np.log(np.sqrt(shear_over_m) * h / a))
    f0 = f(x0)
    x1 = x0 + f0
    for _ in range(_DECAY_ROUNDS):
        f1 = f(x1)
        moved = x1 != x0
        slope = np.where(moved, (f1 - f0) / np.where(moved, x1 - x0, 1.0), -1.0)
        slope = np.where(slope < 0.0, slope, -1.0)  # no secant: a fixed-point step
        step = np.clip(-f1 / slope, -4.0 * np.abs(f1), 4.0 * np.abs(f1))
        x0, f0, x1 = x1, f1, x1 + step
        if np.max(np.abs(step)) < 1e-12:
            break
    slope2, value2 = _moments(np.exp(x1), h)
    spring = (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) * slope2
    shear = value2 / (2.0 * (1.0 + nu))
    return np.sqrt(shear / spring), spring, shear


def _check(contact_radius_m: Any, tip_radius_m: float, thickness_m: float, poisson_ratio: float,
           ) -> tuple[NDArray[np.float64], float, float, float]:
    a = check_array("contact_radius_m", np.ravel(contact_radius_m), (None,), what="metres")
    radius = check_positive("tip_radius_m", tip_radius_m)
    h = check_positive("thickness_m", thickness_m)
    nu = check_positive("poisson_ratio", poisson_ratio, allow_zero=True)
    if nu >= 0.5:
        raise InvalidArgumentError(f"`poisson_ratio` must lie in [0, 0.5); got {nu}")
    if np.any(a <= 0) or np.any(a > radius):
        raise InvalidArgumentError("`contact_radius_m` must lie in (0, tip_radius_m]")
    return a, radius, h, nu


def foundation_indentation(contact_radius_m: Any, tip_radius_m: float, thickness_m: float,
                           youngs_modulus_pa: float, poisson_ratio: float,
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Depth ``δ`` [m] and force ``F`` [N] (each the shape of ``contact_radius_m``) of a rigid
    sphere of radius ``R`` whose contact with a Vlasov foundation of thickness ``h`` has radius
    ``a = contact_radius_m`` in ``(0, R]`` (module docstring); ``ν`` in ``[0, 0.5)``, since an
    incompressible layer has no spring. ``F`` is proportional to ``E``; both rise with ``a``."""
    a, radius, h, nu = _check(contact_radius_m, tip_radius_m, thickness_m, poisson_ratio)
    modulus = check_positive("youngs_modulus_pa", youngs_modulus_pa)
    ell, spring, shear = _solve(a, radius, h, nu)
    depth = a * a / (2.0 * radius) + (a * ell / radius) * k0e(a / ell) / k1e(a / ell)
    force = modulus * np.pi * (spring * (depth * a * a - a**4 / (4.0 * radius))
                               + 2.0 * shear * a * a / radius)
    shape = np.shape(contact_radius_m)
    return depth.reshape(shape), force.reshape(shape)


def foundation_surface_deflection(r: Any, contact_radius_m: float, tip_radius_m: float,
                                  thickness_m: float, poisson_ratio: float,
                                  ) -> NDArray[np.float64]:
    """Downward deflection ``w(r)`` [m] (the shape of ``r``, metres from the contact's centre) of
    the foundation's surface under the sphere with contact radius ``a`` (module docstring): the
    cap inside, ``C K₀(r / ℓ)`` outside; ``w(0) = δ``. It does not depend on ``E``."""
    a, radius, h, nu = _check(np.array([contact_radius_m]), tip_radius_m, thickness_m,
                              poisson_ratio)
    ell = float(_solve(a, radius, h, nu)[0][0])
    a0 = float(a[0])
    r = np.asarray(r, dtype=float)
    ro = np.maximum(r, a0)
    outside = (a0 * ell / radius) * k0e(ro / ell) / k1e(a0 / ell) * np.exp(-(ro - a0) / ell)
    depth = a0 * a0 / (2.0 * radius) + (a0 * ell / radius) * k0e(a0 / ell) / k1e(a0 / ell)
    return np.asarray(np.where(r <= a0, depth - r * r / (2.0 * radius), outside))
