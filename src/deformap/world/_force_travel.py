"""The force–travel record of a simulated press, from the world's own physics.

A real arm records, from first contact to the commanded force, the tip's travel along the press
direction and the normal force (``docs/robot.md``). The world solves a press at each load level
(:func:`force_levels`, from the contact threshold to the commanded force): the true travel at level
``k`` is the dent depth ``δ(F_k)``. The encoders read the tip's position with an error of
``encoder_noise_m`` and the travel is counted from first contact (the first travel is exactly 0);
the force sensor reads ``F_k`` with an error of ``rel · F_k + abs`` (one standard deviation).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap.environment import ForceTravel
from deformap.world._config import RecordSpacing

__all__ = ["force_levels", "simulated_force_travel"]


def force_levels(contact_n: float, force_n: float, n_levels: int,
                 spacing: RecordSpacing = "force") -> NDArray[np.float64]:
    """``(n_levels + 1,)`` forces from ``contact_n`` to ``force_n`` (both kept), evenly spaced in
    force, or (``"travel"``) in travel for a Hertz contact: ``F_k^{2/3}`` evenly spaced, as an
    arm advancing at constant speed samples a press."""
    if spacing == "force":
        return np.linspace(contact_n, force_n, n_levels + 1)
    if spacing != "travel":
        raise ValueError(f"`spacing` must be 'force' or 'travel'; got {spacing!r}")
    levels = np.linspace(contact_n ** (2.0 / 3.0), force_n ** (2.0 / 3.0), n_levels + 1) ** 1.5
    levels[[0, -1]] = contact_n, force_n  # the ends exactly
    return levels


def simulated_force_travel(depths: NDArray[np.float64], levels: NDArray[np.float64],
                           rng: np.random.Generator, *, encoder_noise_m: float,
                           force_noise_rel: float, force_noise_n: float) -> ForceTravel:
    """The record of a press whose tip sinks ``depths[k]`` metres under ``levels[k]`` newtons
    (increasing), with ``n`` encoder draws then ``n`` force draws from ``rng`` (module
    docstring); zero noises give the exact record."""
    position = depths + rng.normal(0.0, 1.0, size=depths.size) * encoder_noise_m
    force = levels + rng.normal(0.0, 1.0, size=levels.size) * (
        force_noise_rel * levels + force_noise_n)
    return ForceTravel(travel_m=position - position[0], force_n=force)
