"""A rigid sphere indenting an elastic layer bonded to a rigid base (Hertz with the finite-thickness
correction of Dimitriadis et al. 2002).

A rigid sphere of radius ``R`` that sinks by ``δ`` into an elastic half-space of Young's modulus
``E`` and Poisson's ratio ``ν`` pushes back with Hertz's force (Johnson 1985, §4.2)

    F_H(δ) = (4/3) E* √R δ^(3/2),    E* = E / (1 − ν²).

On a layer of thickness ``h`` bonded to a rigid table the base stiffens the contact as the contact
radius ``a ≈ √(Rδ)`` grows against ``h``. Dimitriadis et al. (2002) solve the bonded (no slip at the
base) and the non-bonded layer as a series in ``χ = √(Rδ) / h``; their force for a spherical
(paraboloidal) indenter is

    F(δ) = F_H(δ) · P(χ),
    P(χ) = 1 − (2α₀/π) χ + (4α₀²/π²) χ² − (8/π³)(α₀³ + (4π²/15) β₀) χ³
             + (16α₀/π⁴)(α₀³ + (3π²/5) β₀) χ⁴,

with, for the bonded layer,

    α₀(ν) = −(1.2876 − 1.4678 ν + 1.3442 ν²) / (1 − ν),
    β₀(ν) = (0.6387 − 1.0277 ν + 1.5164 ν²) / (1 − ν).

At ``ν = 0.5`` the first three coefficients are their printed 1.133, 1.283 and 0.769 (their bonded
equation for incompressible samples); the non-bonded ``α₀ = −0.347 (3 − 2ν)/(1 − ν)``,
``β₀ = 0.056 (5 − 2ν)/(1 − ν)`` put into the same series give their non-bonded coefficients
(0.884, 0.781, 0.386, 0.0048) to the printed digits. For the bonded case the series gives the
χ⁴ coefficient −0.0975 where the printed incompressible form reads +0.0975 (the same magnitude,
the opposite sign); this module evaluates the series, which its own non-bonded case confirms (the
two bonded readings differ by less than 5 % of ``F`` for ``χ ≤ 1``).

Range of validity
-----------------
- ``χ ≲ 1``: the series is an expansion in the contact radius over the thickness, meant for
  contact radii up to about the layer's thickness. Beyond it the
  polynomial is an extrapolation, and its negative χ⁴ term makes the force stop rising at
  :func:`layer_chi_limit` (``χ ≈ 2.2`` at ``ν = 0.33``, 1.7 at ``ν = 0``): past that it means
  nothing. :func:`deformap.stiffness.estimate_stiffness` stays below it and reports the ``χ`` it
  reached.
- small strain: Hertz's paraboloidal sphere and linear elasticity need ``a ≪ R`` (``δ ≪ R``),
  ``δ ≪ h`` and strains in the material's linear range; a foam pressed to a sizeable fraction of
  its thickness is outside all three. With a tip smaller than the layer (``R < h``) the depth
  reaches ``h`` before ``χ`` reaches 1 (``χ = √(R/h)`` at ``δ = h``), so there the strain, not
  ``χ``, bounds the model.
- frictionless contact at the tip, a flat and homogeneous, isotropic layer.

References
----------
Dimitriadis, E. K., Horkay, F., Maresca, J., Kachar, B., Chadwick, R. S. (2002). Determination of
elastic moduli of thin layers of soft material using the atomic force microscope. Biophysical
Journal 82(5), 2798–2810 (the spherical indenter on bonded and non-bonded layers: the series in χ,
α₀ and β₀ of the bonded and non-bonded cases, and their incompressible numerical forms, the bonded
one being their Eq. 12).
Johnson, K. L. (1985). Contact Mechanics, §4.2. Cambridge University Press.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError
from deformap.mechanics._hertz import reduced_modulus

__all__ = [
    "layer_chi_limit",
    "layer_correction",
    "layer_correction_coefficients",
    "layer_indentation_force",
    "layer_indentation_stiffness",
]


def layer_correction_coefficients(poisson_ratio: float) -> NDArray[np.float64]:
    """Coefficients ``c₀ … c₄`` of ``P(χ) = Σ cₖ χᵏ`` for a bonded layer (module docstring).

    Parameters
    ----------
    poisson_ratio : float
        ``ν`` in ``[0, 0.5]`` (the bonded ``α₀``, ``β₀`` were fitted over that range).

    Returns
    -------
    (5,) float
        ``c₀ = 1``; at ``ν = 0.5`` about ``(1, 1.133, 1.283, 0.769, −0.095)``.
    """
    nu = check_positive("poisson_ratio", poisson_ratio, allow_zero=True)
    if nu > 0.5:
        raise InvalidArgumentError(f"`poisson_ratio` must lie in [0, 0.5]; got {nu}")
    alpha = -(1.2876 - 1.4678 * nu + 1.3442 * nu**2) / (1.0 - nu)
    beta = (0.6387 - 1.0277 * nu + 1.5164 * nu**2) / (1.0 - nu)
    pi = np.pi
    return np.array([
        1.0,
        -2.0 * alpha / pi,
        4.0 * alpha**2 / pi**2,
        -8.0 / pi**3 * (alpha**3 + 4.0 * pi**2 / 15.0 * beta),
        16.0 * alpha / pi**4 * (alpha**3 + 3.0 * pi**2 / 5.0 * beta),
    ])


def layer_chi_limit(poisson_ratio: float) -> float:
    """The ``χ`` at which the bonded layer's force stops rising with depth (module docstring).

    ``dF/dδ ∝ 3 P(χ) + χ P'(χ) = Σ (3 + k) cₖ χᵏ``; this is its smallest positive root (``inf`` if
    it has none). The series holds well below it (``χ ≲ 1``).
    """
    coeffs = layer_correction_coefficients(poisson_ratio)
    roots = np.polynomial.polynomial.polyroots((3.0 + np.arange(coeffs.size)) * coeffs)
    real = [float(r.real) for r in roots if abs(r.imag) < 1e-12 and r.real > 0]
    return min(real) if real else float("inf")


def layer_correction(chi: Any, poisson_ratio: float) -> NDArray[np.float64]:
    """``P(χ)``, the bonded layer's force over Hertz's at the same depth (module docstring).

    Parameters
    ----------
    chi : array of float
        ``χ = √(Rδ) / h ≥ 0`` (any shape).
    poisson_ratio : float
        As in :func:`layer_correction_coefficients`.

    Returns
    -------
    array of float
        The shape of ``chi``; 1 at ``χ = 0``.
    """
    chi = np.asarray(chi, dtype=float)
    if not np.all(np.isfinite(chi)) or np.any(chi < 0):
        raise InvalidArgumentError("`chi` must hold finite values >= 0")
    coeffs = layer_correction_coefficients(poisson_ratio)
    return np.asarray(np.polynomial.polynomial.polyval(chi, coeffs))


def _checked(depth_m: Any, tip_radius_m: float, thickness_m: float, youngs_modulus_pa: float,
             poisson_ratio: float) -> tuple[NDArray[np.float64], float, float, float,
                                            NDArray[np.float64]]:
    check_array("depth_m", np.ravel(depth_m), (None,), what="depths in metres")
    depth = np.asarray(depth_m, dtype=float)
    if np.any(depth < 0):
        raise InvalidArgumentError(
            f"`depth_m` must hold depths >= 0 in metres; got {float(depth.min())}")
    r = check_positive("tip_radius_m", tip_radius_m)
    h = check_positive("thickness_m", thickness_m)
    e_star = reduced_modulus(youngs_modulus_pa, poisson_ratio)
    coeffs = layer_correction_coefficients(poisson_ratio)
    return depth, r, h, e_star, coeffs


def layer_indentation_force(depth_m: Any, tip_radius_m: float, thickness_m: float,
                            youngs_modulus_pa: float, poisson_ratio: float) -> NDArray[np.float64]:
    """Force in newtons of a rigid sphere sunk ``depth_m`` into a bonded elastic layer.

    ``F = (4/3) E* √R δ^(3/2) · P(√(Rδ)/h)`` (module docstring), vectorised over ``δ``; it tends to
    Hertz's half-space force (:func:`deformap.mechanics.hertz_indentation`'s inverse) as
    ``h → ∞`` and grows faster than it on thinner layers.

    Parameters
    ----------
    depth_m : array of float, metres
        Indentation depths ``δ ≥ 0`` (any shape).
    tip_radius_m : float
        Sphere radius ``R > 0``.
    thickness_m : float
        Layer thickness ``h > 0`` above the rigid base.
    youngs_modulus_pa : float
        ``E > 0``.
    poisson_ratio : float
        ``ν`` in ``[0, 0.5]``.

    Returns
    -------
    array of float, newtons
        The shape of ``depth_m``.
    """
    depth, r, h, e_star, coeffs = _checked(depth_m, tip_radius_m, thickness_m,
                                           youngs_modulus_pa, poisson_ratio)
    chi = np.sqrt(r * depth) / h
    hertz = 4.0 / 3.0 * e_star * np.sqrt(r) * depth**1.5
    return np.asarray(hertz * np.polynomial.polynomial.polyval(chi, coeffs))


def layer_indentation_stiffness(depth_m: Any, tip_radius_m: float, thickness_m: float,
                                youngs_modulus_pa: float, poisson_ratio: float,
                                ) -> NDArray[np.float64]:
    """Contact stiffness ``dF/dδ`` in N/m of :func:`layer_indentation_force` at ``depth_m``.

    With ``dχ/dδ = χ / (2δ)``: ``dF/dδ = (4/3) E* √R √δ · (1.5 P(χ) + 0.5 χ P'(χ))``. Arguments as
    in :func:`layer_indentation_force`; 0 at ``δ = 0``.
    """
    depth, r, h, e_star, coeffs = _checked(depth_m, tip_radius_m, thickness_m,
                                           youngs_modulus_pa, poisson_ratio)
    chi = np.sqrt(r * depth) / h
    poly = np.polynomial.polynomial
    shape = 1.5 * poly.polyval(chi, coeffs) + 0.5 * chi * poly.polyval(chi, poly.polyder(coeffs))
    return np.asarray(4.0 / 3.0 * e_star * np.sqrt(r) * np.sqrt(depth) * shape)
