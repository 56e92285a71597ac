"""Shared fixtures and tolerance helpers for deformap's tests and for users' own tests."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.mechanics import (
    INDENTER_AREA_M2,
    elastic_dent,
    hardness_to_youngs_modulus,
    hertz_surface_deflection,
)

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
# They live in deformap.mechanics; these names are kept for users' tests and the examples.

FOAM_INDENTER_AREA_M2 = INDENTER_AREA_M2
"""Area of the hardness test's indenter (ISO 2439, 323 cm²), as
:data:`deformap.mechanics.INDENTER_AREA_M2`."""

hardness_to_modulus = hardness_to_youngs_modulus
"""Young's modulus (Pa) of a foam of hardness ``hardness_n`` (N at 40 % compression):
:func:`deformap.mechanics.hardness_to_youngs_modulus`."""


# ---- simulated world (deformap.world) ----


def coarse_world(scenario: str = "heterogeneous-60-110-rigid", seed: int = 0, **overrides: Any
                 ) -> Any:
    """A :class:`deformap.world.SimulatedWorld` on the coarse test mesh (quick to build).

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
