"""Hertz contact of the probe's spherical tip on foam: patch radius, indentation, pressure.

A sphere of radius ``R`` pressed with force ``F`` into an elastic half-space of modulus ``E`` and
Poisson's ratio ``ν`` touches it on a disc of radius ``a = (3 F R / (4 E*))^(1/3)``, with
``E* = E / (1 - ν²)`` (the tip is far stiffer than foam), sinks by ``δ = a² / R``, and presses with
``p(r) = p0 sqrt(1 - r² / a²)``, ``p0 = 3 F / (2 π a²)``, whose integral is ``F``.

References
----------
Johnson, K. L. (1985). Contact Mechanics, §4.2. Cambridge University Press.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["hertz_contact_radius", "hertz_indentation", "hertz_pressure_samples"]


def _reduced_modulus(youngs_modulus_pa: float, poisson_ratio: float) -> float:
    return youngs_modulus_pa / (1.0 - poisson_ratio**2)


def hertz_contact_radius(force_n: float, tip_radius_m: float, youngs_modulus_pa: float,
                         poisson_ratio: float) -> float:
    """Radius ``a`` in metres of the contact disc of a rigid sphere on an elastic half-space."""
    e_star = _reduced_modulus(youngs_modulus_pa, poisson_ratio)
    return float((3.0 * force_n * tip_radius_m / (4.0 * e_star)) ** (1.0 / 3.0))


def hertz_indentation(force_n: float, tip_radius_m: float, youngs_modulus_pa: float,
                      poisson_ratio: float) -> float:
    """Depth ``δ = a² / R`` in metres by which a rigid sphere sinks into an elastic half-space."""
    a = hertz_contact_radius(force_n, tip_radius_m, youngs_modulus_pa, poisson_ratio)
    return a * a / tip_radius_m


def hertz_pressure_samples(center_xy: NDArray[np.float64], radius_m: float, force_n: float,
                           n_across: int = 24) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Point forces that sample the Hertz pressure on a disc and sum to ``force_n`` exactly.

    Parameters
    ----------
    center_xy : (2,) float, metres
    radius_m : float
        Contact radius ``a``.
    force_n : float
        Total normal force.
    n_across : int
        Samples across the diameter (midpoint rule on a square lattice).

    Returns
    -------
    points : (s, 2) float, metres
    forces : (s,) float, newtons, summing to ``force_n``
    """
    step = 2.0 * radius_m / n_across
    offsets = (np.arange(n_across) + 0.5) * step - radius_m
    gx, gy = np.meshgrid(offsets, offsets)
    r2 = (gx**2 + gy**2).ravel()
    keep = r2 < radius_m**2
    weights = np.sqrt(1.0 - r2[keep] / radius_m**2)
    points = np.column_stack([gx.ravel()[keep], gy.ravel()[keep]]) + center_xy
    return points, force_n * weights / weights.sum()
