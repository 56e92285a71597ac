"""Hertz contact of the probe's spherical tip on an elastic half-space, and the dent it leaves.

A rigid sphere of radius ``R`` pressed with force ``F`` into an elastic half-space of Young's
modulus ``E`` and Poisson's ratio ``ν`` (the tip is far stiffer than foam, so the reduced modulus
is ``E* = E / (1 − ν²)``) touches it on a disc of radius ``a = (3 F R / (4 E*))^(1/3)``, sinks by
``δ = a² / R``, and presses with ``p(r) = p0 √(1 − r² / a²)``, ``p0 = 3 F / (2 π a²)``, whose
integral is ``F``. The surface sinks by

- ``u(r) = π p0 (2a² − r²) / (4 a E*)`` for ``r ≤ a``,
- ``u(r) = p0 / (2 a E*) · [(2a² − r²) asin(a/r) + a √(r² − a²)]`` for ``r > a``,

continuous at ``r = a`` with ``u(0) = δ``.

References
----------
Johnson, K. L. (1985). Contact Mechanics, §3.4 and §4.2. Cambridge University Press.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_finite_scalar, check_int, check_positive
from deformap.errors import InvalidArgumentError
from deformap.mechanics._contact import TactileContact

__all__ = ["elastic_dent", "hertz_contact_radius", "hertz_indentation", "hertz_pressure_samples",
           "hertz_surface_at_depth", "hertz_surface_deflection", "reduced_modulus"]


def reduced_modulus(youngs_modulus_pa: float, poisson_ratio: float) -> float:
    """``E* = E / (1 − ν²)`` in pascals of a half-space (``E > 0``, ``ν`` in ``(−1, 0.5]``)
    against a rigid indenter."""
    e = check_positive("youngs_modulus_pa", youngs_modulus_pa)
    nu = check_finite_scalar("poisson_ratio", poisson_ratio)
    if not -1.0 < nu <= 0.5:
        raise InvalidArgumentError(f"`poisson_ratio` must lie in (-1, 0.5]; got {nu}")
    return e / (1.0 - nu**2)


def hertz_contact_radius(force_n: float, tip_radius_m: float, youngs_modulus_pa: float,
                         poisson_ratio: float) -> float:
    """Radius ``a = (3 F R / (4 E*))^(1/3)`` in metres of the contact disc of a rigid sphere
    pressed with ``force_n`` newtons into an elastic half-space (all arguments > 0, ``ν`` as in
    :func:`reduced_modulus`)."""
    f = check_positive("force_n", force_n)
    r = check_positive("tip_radius_m", tip_radius_m)
    e_star = reduced_modulus(youngs_modulus_pa, poisson_ratio)
    return float((3.0 * f * r / (4.0 * e_star)) ** (1.0 / 3.0))


def hertz_indentation(force_n: float, tip_radius_m: float, youngs_modulus_pa: float,
                      poisson_ratio: float) -> float:
    """Depth ``δ = a² / R`` in metres by which a rigid sphere sinks into an elastic half-space
    (``a`` from :func:`hertz_contact_radius`)."""
    a = hertz_contact_radius(force_n, tip_radius_m, youngs_modulus_pa, poisson_ratio)
    return a * a / float(tip_radius_m)


def hertz_surface_deflection(r: Any, force_n: float, tip_radius_m: float, modulus_pa: float,
                             poisson_ratio: float = 0.5) -> NDArray[np.float64]:
    """Downward surface deflection ``u(r)`` in metres (module docstring, ``u(0) = δ``) at
    horizontal distances ``r`` (any shape, metres) from the centre of a Hertz sphere's contact."""
    r = np.asarray(r, dtype=float)
    e_star = reduced_modulus(modulus_pa, poisson_ratio)
    a = hertz_contact_radius(force_n, tip_radius_m, modulus_pa, poisson_ratio)
    p0 = 3.0 * force_n / (2.0 * np.pi * a * a)
    inside = np.pi * p0 * (2 * a * a - r * r) / (4 * a * e_star)
    ro = np.maximum(r, a)
    outside = p0 / (2 * a * e_star) * ((2 * a * a - ro * ro) * np.arcsin(a / ro)
                                       + a * np.sqrt(ro * ro - a * a))
    return np.asarray(np.where(r <= a, inside, outside))


def hertz_surface_at_depth(r: Any, depth_m: float, tip_radius_m: float) -> NDArray[np.float64]:
    """Hertz's surface (:func:`hertz_surface_deflection`) about a sphere sunk ``depth_m``: its
    shape does not depend on the modulus, so the force that sinks the sphere that deep at
    ``E* = 1`` (``F = 4/3 √R δ^(3/2)``, ``E = 1``, ``ν = 0``) draws it."""
    force = 4.0 / 3.0 * np.sqrt(tip_radius_m) * depth_m**1.5
    return hertz_surface_deflection(r, force, tip_radius_m, 1.0, 0.0)


def hertz_pressure_samples(center_xy: NDArray[np.float64], radius_m: float, force_n: float,
                           n_across: int = 24) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(s, 2)`` points (metres) and ``(s,)`` forces (newtons, ``∝ √(1 − r² / a²)``, summing
    to ``force_n`` exactly) that sample the Hertz pressure on the disc of radius ``radius_m``
    about ``center_xy``: the midpoint rule on a square lattice of ``n_across`` cells across."""
    center = check_array("center_xy", center_xy, (2,), what="metres")
    radius_m = check_positive("radius_m", radius_m)
    n_across = check_int("n_across", n_across, minimum=1)
    step = 2.0 * radius_m / n_across
    offsets = (np.arange(n_across) + 0.5) * step - radius_m
    gx, gy = np.meshgrid(offsets, offsets)
    r2 = (gx**2 + gy**2).ravel()
    keep = r2 < radius_m**2
    weights = np.sqrt(1.0 - r2[keep] / radius_m**2)
    points = np.column_stack([gx.ravel()[keep], gy.ravel()[keep]]) + center
    return points, force_n * weights / weights.sum()


def elastic_dent(xs: Any, ys: Any, z_rest: Any, contact_xy: Any, *, force_n: float,
                 tip_radius_m: float, modulus_pa: float | None, poisson_ratio: float = 0.5,
                 ) -> tuple[NDArray[np.float64], TactileContact]:
    """Deformed ``(ny, nx)`` heightmap and tactile contact of a vertical Hertz poke on the rest
    heightmap ``z_rest`` over ``xs``, ``ys`` (metres): :func:`hertz_surface_deflection`
    subtracted, an analytic reference for the β estimation. ``modulus_pa`` None is a rigid
    surface. The tip rests in the dent below the grid node nearest ``contact_xy``, force
    ``(0, 0, −F)``."""
    xs, ys, z_rest = np.asarray(xs, float), np.asarray(ys, float), np.asarray(z_rest, float)
    gx, gy = np.meshgrid(xs, ys)
    cx, cy = float(contact_xy[0]), float(contact_xy[1])
    u, depth = np.zeros_like(z_rest), 0.0
    if modulus_pa is not None:
        u = hertz_surface_deflection(np.hypot(gx - cx, gy - cy), force_n, tip_radius_m,
                                     modulus_pa, poisson_ratio)
        depth = float(hertz_surface_deflection(0.0, force_n, tip_radius_m, modulus_pa,
                                               poisson_ratio))
    z_top = float(z_rest[np.argmin(np.abs(ys - cy)), np.argmin(np.abs(xs - cx))]) - depth
    contact = TactileContact(tip_center=np.array([cx, cy, z_top + tip_radius_m]),
                             force=np.array([0.0, 0.0, -force_n]), tip_radius_m=tip_radius_m)
    return z_rest - u, contact
