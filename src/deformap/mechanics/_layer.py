"""A rigid sphere indenting an elastic layer bonded to a rigid base (Hertz with the finite-thickness
correction of Dimitriadis et al. 2002).

A rigid sphere of radius ``R`` sunk by ``δ`` into a half-space of Young's modulus ``E`` and
Poisson's ratio ``ν`` pushes back with Hertz's force (Johnson 1985, §4.2)

    F_H(δ) = (4/3) E* √R δ^(3/2),    E* = E / (1 − ν²).

On a layer of thickness ``h`` bonded to the table, Dimitriadis et al. (2002) correct it by a
series in ``χ = √(Rδ) / h``:

    F(δ) = F_H(δ) · P(χ),
    P(χ) = 1 − (2α₀/π) χ + (4α₀²/π²) χ² − (8/π³)(α₀³ + (4π²/15) β₀) χ³
             + (16α₀/π⁴)(α₀³ + (3π²/5) β₀) χ⁴,
    α₀(ν) = −(1.2876 − 1.4678 ν + 1.3442 ν²) / (1 − ν),
    β₀(ν) = (0.6387 − 1.0277 ν + 1.5164 ν²) / (1 − ν)    (bonded layer).

The series is evaluated as written (its χ⁴ coefficient at ``ν = 0.5`` is −0.0975; the paper's
printed incompressible form reads +0.0975). Valid for ``χ ≲ 1`` (the force stops rising at
:func:`layer_chi_limit`), small strain (``δ ≪ R``, ``δ ≪ h``) and a frictionless tip on a flat,
homogeneous, isotropic layer.

References
----------
Dimitriadis, E. K., et al. (2002). Elastic moduli of thin layers of soft material by AFM.
Biophysical Journal 82(5), 2798–2810 (Eq. 12, the bonded α₀, β₀).
Johnson, K. L. (1985). Contact Mechanics, §4.2. Cambridge University Press.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError
from deformap.mechanics._hertz import reduced_modulus

__all__ = ["layer_chi_limit", "layer_correction", "layer_correction_coefficients",
           "layer_indentation_force", "layer_indentation_stiffness"]


def layer_correction_coefficients(poisson_ratio: float) -> NDArray[np.float64]:
    """``(5,)`` coefficients ``c₀ = 1 … c₄`` of ``P(χ) = Σ cₖ χᵏ`` for a bonded layer (module
    docstring); ``ν`` in ``[0, 0.5]``, the range the bonded ``α₀``, ``β₀`` were fitted over."""
    nu = check_positive("poisson_ratio", poisson_ratio, allow_zero=True)
    if nu > 0.5:
        raise InvalidArgumentError(f"`poisson_ratio` must lie in [0, 0.5]; got {nu}")
    alpha = -(1.2876 - 1.4678 * nu + 1.3442 * nu**2) / (1.0 - nu)
    beta = (0.6387 - 1.0277 * nu + 1.5164 * nu**2) / (1.0 - nu)
    pi = np.pi
    return np.array([1.0, -2.0 * alpha / pi, 4.0 * alpha**2 / pi**2,
                     -8.0 / pi**3 * (alpha**3 + 4.0 * pi**2 / 15.0 * beta),
                     16.0 * alpha / pi**4 * (alpha**3 + 3.0 * pi**2 / 5.0 * beta)])


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
    """``P(χ)`` (the shape of ``chi``, 1 at ``χ = 0``), the bonded layer's force over Hertz's at
    the same depth, for ``χ = √(Rδ) / h ≥ 0``."""
    chi = np.asarray(chi, dtype=float)
    if not np.all(np.isfinite(chi)) or np.any(chi < 0):
        raise InvalidArgumentError("`chi` must hold finite values >= 0")
    coeffs = layer_correction_coefficients(poisson_ratio)
    return np.asarray(np.polynomial.polynomial.polyval(chi, coeffs))


def _terms(depth_m: Any, tip_radius_m: float, thickness_m: float, youngs_modulus_pa: float,
           poisson_ratio: float) -> tuple[NDArray[np.float64], NDArray[np.float64], float,
                                          NDArray[np.float64]]:
    """The checked depths ``δ``, ``χ = √(Rδ) / h``, ``(4/3) E* √R`` and ``P``'s coefficients."""
    check_array("depth_m", np.ravel(depth_m), (None,), what="depths in metres")
    depth = np.asarray(depth_m, dtype=float)
    if np.any(depth < 0):
        raise InvalidArgumentError(
            f"`depth_m` must hold depths >= 0 in metres; got {float(depth.min())}")
    r = check_positive("tip_radius_m", tip_radius_m)
    h = check_positive("thickness_m", thickness_m)
    scale = 4.0 / 3.0 * reduced_modulus(youngs_modulus_pa, poisson_ratio) * np.sqrt(r)
    coeffs = layer_correction_coefficients(poisson_ratio)
    return depth, np.sqrt(r * depth) / h, scale, coeffs


def layer_indentation_force(depth_m: Any, tip_radius_m: float, thickness_m: float,
                            youngs_modulus_pa: float, poisson_ratio: float) -> NDArray[np.float64]:
    """Force ``F = (4/3) E* √R δ^(3/2) · P(√(Rδ)/h)`` in newtons (the shape of ``depth_m``) of a
    rigid sphere of radius ``R`` sunk ``δ = depth_m ≥ 0`` into a layer of thickness ``h`` bonded
    to a rigid base; Hertz's half-space force as ``h → ∞``."""
    depth, chi, scale, coeffs = _terms(depth_m, tip_radius_m, thickness_m, youngs_modulus_pa,
                                       poisson_ratio)
    return np.asarray(scale * depth**1.5 * np.polynomial.polynomial.polyval(chi, coeffs))


def layer_indentation_stiffness(depth_m: Any, tip_radius_m: float, thickness_m: float,
                                youngs_modulus_pa: float, poisson_ratio: float,
                                ) -> NDArray[np.float64]:
    """Contact stiffness ``dF/dδ = (4/3) E* √R √δ · (1.5 P(χ) + 0.5 χ P'(χ))`` in N/m of
    :func:`layer_indentation_force` (same arguments); 0 at ``δ = 0``."""
    depth, chi, scale, coeffs = _terms(depth_m, tip_radius_m, thickness_m, youngs_modulus_pa,
                                       poisson_ratio)
    poly = np.polynomial.polynomial
    shape = 1.5 * poly.polyval(chi, coeffs) + 0.5 * chi * poly.polyval(chi, poly.polyder(coeffs))
    return np.asarray(scale * np.sqrt(depth) * shape)
