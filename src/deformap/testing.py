"""Shared fixtures and tolerance helpers for deformap's tests and for users' own tests."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "FOAM_INDENTER_AREA_M2",
    "assert_allclose_m",
    "coarse_world",
    "elastic_dent",
    "flat_patch",
    "hardness_to_modulus",
    "hertz_surface_deflection",
    "synthetic_poke",
]


def assert_allclose_m(actual: Any, desired: Any, *, atol_m: float, err_msg: str = "") -> None:
    """Assert two arrays of lengths agree within ``atol_m`` metres (absolute)."""
    np.testing.assert_allclose(
        np.asarray(actual, dtype=float), np.asarray(desired, dtype=float), rtol=0, atol=atol_m,
        err_msg=err_msg,
    )


def flat_patch(n: int = 10, spacing_m: float = 0.005, height_m: float = 0.05) -> NDArray[np.float64]:
    """``(n*n, 3)`` points of a flat square patch at ``height_m``, row-major in (y, x)."""
    xs = (np.arange(n) - (n - 1) / 2) * spacing_m
    gx, gy = np.meshgrid(xs, xs)
    return np.column_stack([gx.ravel(), gy.ravel(), np.full(n * n, height_m)])


# ---- elastic dents (an analytic reference for the β estimation; not shape matching) ----------
#
# Hertz contact of a rigid sphere on a linear-elastic half-space (Johnson 1985, §3.4 and §4.2):
# contact radius a = (3 F R / 4 E*)^(1/3), depth δ = a² / R, pressure p0 = 3 F / (2π a²), and the
# surface deflection
#   r ≤ a: u(r) = π p0 (2a² − r²) / (4 a E*)
#   r > a: u(r) = p0 / (2 a E*) · [(2a² − r²) asin(a/r) + a √(r² − a²)]
# with E* = E / (1 − ν²). Foam hardness H (newtons to compress a 323 cm² indenter to 40 %, the
# manufacturer's figure) becomes a modulus through the 40 % strain: E = (H / 0.0323 m²) / 0.4.

FOAM_INDENTER_AREA_M2 = 0.0323
"""Area of the hardness test's indenter (ISO 2439, 323 cm²)."""


def hardness_to_modulus(hardness_n: float) -> float:
    """Young's modulus (Pa) of a foam of hardness ``hardness_n`` (N at 40 % compression)."""
    return float(hardness_n) / FOAM_INDENTER_AREA_M2 / 0.4


def hertz_surface_deflection(r: Any, force_n: float, tip_radius_m: float, modulus_pa: float,
                             poisson_ratio: float = 0.5) -> NDArray[np.float64]:
    """Downward surface deflection ``u(r)`` (metres) of a half-space under a Hertz sphere.

    Parameters
    ----------
    r : array of float, metres
        Horizontal distances from the contact centre.
    force_n, tip_radius_m, modulus_pa, poisson_ratio : float
        Normal force, sphere radius, Young's modulus and Poisson ratio of the half-space.
    """
    r = np.asarray(r, dtype=float)
    e_star = modulus_pa / (1.0 - poisson_ratio**2)
    a = (3.0 * force_n * tip_radius_m / (4.0 * e_star)) ** (1.0 / 3.0)
    p0 = 3.0 * force_n / (2.0 * np.pi * a * a)
    inside = np.pi * p0 * (2 * a * a - r * r) / (4 * a * e_star)
    ro = np.maximum(r, a)
    outside = p0 / (2 * a * e_star) * ((2 * a * a - ro * ro) * np.arcsin(a / ro)
                                       + a * np.sqrt(ro * ro - a * a))
    return np.asarray(np.where(r <= a, inside, outside))


def elastic_dent(xs: Any, ys: Any, z_rest: Any, contact_xy: Any, *, force_n: float,
                 tip_radius_m: float, modulus_pa: float | None, poisson_ratio: float = 0.5,
                 ) -> tuple[NDArray[np.float64], Any]:
    """Deformed heightmap and tactile contact of a vertical Hertz poke on a (locally flat) foam.

    Parameters
    ----------
    xs : (nx,) float, ys : (ny,) float, z_rest : (ny, nx) float, metres
        The rest heightmap.
    contact_xy : (2,) float, metres
    force_n, tip_radius_m : float
    modulus_pa : float or None
        ``None`` means a rigid surface (no dent).

    Returns
    -------
    z_deformed : (ny, nx) float, metres
    contact : deformap.environment.TactileContact
        Tip resting in the dent (its lowest point at the dent's bottom), force ``(0, 0, −F)``.
    """
    from deformap.environment import TactileContact  # the environment imports cloud, not testing

    xs, ys, z_rest = np.asarray(xs, float), np.asarray(ys, float), np.asarray(z_rest, float)
    gx, gy = np.meshgrid(xs, ys)
    cx, cy = float(contact_xy[0]), float(contact_xy[1])
    if modulus_pa is None:
        u = np.zeros_like(z_rest)
        depth = 0.0
    else:
        u = hertz_surface_deflection(np.hypot(gx - cx, gy - cy), force_n, tip_radius_m,
                                     modulus_pa, poisson_ratio)
        depth = float(hertz_surface_deflection(0.0, force_n, tip_radius_m, modulus_pa,
                                               poisson_ratio))
    j = int(np.argmin(np.abs(xs - cx)))
    i = int(np.argmin(np.abs(ys - cy)))
    z_top = float(z_rest[i, j]) - depth
    contact = TactileContact(tip_center=np.array([cx, cy, z_top + tip_radius_m]),
                             force=np.array([0.0, 0.0, -force_n]), tip_radius_m=tip_radius_m)
    return z_rest - u, contact
# ---- simulated world (deformap.world) ----


def coarse_world(scenario: str = "heterogeneous-60-110-rigid", seed: int = 0, **overrides: Any
                 ) -> Any:
    """A :class:`deformap.world.SimulatedWorld` on the coarse test mesh (builds in < 1 s).

    For tests of code that drives an ``Environment``; its dents are coarse-mesh numbers, not
    measurements. ``overrides`` go to :meth:`deformap.world.WorldConfig.coarse`.
    """
    from deformap.world import SimulatedWorld, WorldConfig, load_scenario

    return SimulatedWorld(load_scenario(scenario), config=WorldConfig.coarse(**overrides),
                          rng=np.random.default_rng(seed))


def synthetic_poke(xy: Any, beta: float, beta_std: float = 0.03, *, index: int = 0,
                   purpose: str | None = None) -> Any:
    """A :class:`deformap.explore.PokeResult` made up for tests of the β-field, target choice
    and regions: a poke at ``xy`` (metres) that read ``beta`` with uncertainty ``beta_std``
    (no dent, no estimate; its other fields are placeholders)."""
    from deformap.explore import ContactRecord, PokeRecord, PokeResult, PokeTimings

    x, y = (float(v) for v in np.asarray(xy, dtype=float).reshape(2))
    record = PokeRecord(
        index=index, target_xy=(x, y), contact_xy=(x, y),
        contact=ContactRecord(tip_center=(x, y, 0.06), force=(0.0, 0.0, -0.6),
                              tip_radius_m=0.01),
        force_n=0.6, beta=float(beta), beta_std=float(beta_std), betas=(), errors=(),
        iterations=0, residual=0.0, converged=True, n_roi_points=0, camera_noise_m=None,
        timings=PokeTimings(filter_s=0.0, touch_gp_s=0.0, beta_s=0.0),
        purpose=purpose,  # type: ignore[arg-type]
    )  # fmt: skip
    return PokeResult(record)
