"""Shared fixtures and tolerance helpers for deformap's tests and for users' own tests."""

from __future__ import annotations

from typing import Any

import numpy as np

from deformap.mechanics import elastic_dent, hardness_to_youngs_modulus, hertz_surface_deflection

__all__ = ["assert_allclose_m", "coarse_world", "elastic_dent", "hardness_to_modulus",
           "hertz_surface_deflection", "synthetic_poke"]

# Elastic dents, an analytic reference for the β estimation that is not shape matching, from
# deformap.mechanics; hardness_to_modulus is its hardness_to_youngs_modulus.
hardness_to_modulus = hardness_to_youngs_modulus


def assert_allclose_m(actual: Any, desired: Any, *, atol_m: float, err_msg: str = "") -> None:
    """Assert two arrays of lengths agree within ``atol_m`` metres (absolute)."""
    np.testing.assert_allclose(np.asarray(actual, dtype=float), np.asarray(desired, dtype=float),
                               rtol=0, atol=atol_m, err_msg=err_msg)  # fmt: skip


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
