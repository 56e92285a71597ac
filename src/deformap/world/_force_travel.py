"""The force–travel record of a simulated press, from the world's own physics.

A real arm records, from first contact to the commanded force, the tip's travel along the press
direction (encoders through forward kinematics) and the normal force (``docs/robot.md``). The
simulated world gives the same record from its physics (``WorldConfig.physics``):

- Load levels: ``n_levels + 1`` forces from the contact threshold ``F_c`` (the first sample) to
  the commanded force ``F``, evenly spaced in force or in travel (:func:`force_levels`).
- Travel: each level is its own press solve (:meth:`~deformap.world._foam.FoamModel.dent`), on the
  stiffness factorised when the world was built, started from the patch of the level above; the
  true descent at level ``k`` is the dent depth ``δ(F_k)``, 0 on rigid ground.
- Noise: the encoders read the tip's position with an error of ``encoder_noise_m`` at every
  sample and the travel is the position minus the position at first contact (so the first travel
  is exactly 0); the force sensor reads ``F_k`` with an error of ``rel · F_k + abs`` (one standard
  deviation). A rigid board gives a travel of encoder noise around zero.

The noise comes from a generator of its own, so the record moves no draw the press made.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap.environment import ForceTravel
from deformap.world._config import RecordSpacing

__all__ = ["force_levels", "simulated_force_travel"]


def force_levels(contact_n: float, force_n: float, n_levels: int,
                 spacing: RecordSpacing = "force") -> NDArray[np.float64]:
    """``(n_levels + 1,)`` forces from ``contact_n`` to ``force_n`` (both kept).

    ``spacing`` ``"force"``: evenly spaced. ``"travel"``: evenly spaced in travel for a Hertz
    contact (``δ ∝ F^{2/3}``: ``F_k^{2/3}`` evenly spaced from ``F_c^{2/3}`` to ``F^{2/3}``), as an
    arm advancing at constant speed samples a press; on the world's layers, whose indentation
    departs from Hertz's, the steps in travel are uneven by as much as that departure.
    """
    if spacing == "force":
        return np.linspace(contact_n, force_n, n_levels + 1)
    if spacing != "travel":
        raise ValueError(f"`spacing` must be 'force' or 'travel'; got {spacing!r}")
    levels = np.linspace(contact_n ** (2.0 / 3.0), force_n ** (2.0 / 3.0), n_levels + 1) ** 1.5
    levels[[0, -1]] = contact_n, force_n  # the ends exactly
    return levels


def simulated_force_travel(
    depths: NDArray[np.float64],
    levels: NDArray[np.float64],
    rng: np.random.Generator,
    *,
    encoder_noise_m: float,
    force_noise_rel: float,
    force_noise_n: float,
) -> ForceTravel:
    """The record of a press whose tip sinks ``depths[k]`` metres under ``levels[k]`` newtons.

    Parameters
    ----------
    depths : (n,) float, metres
        The tip's true indentation at each level.
    levels : (n,) float, newtons
        The true forces of the samples, increasing (:func:`force_levels`).
    rng : numpy.random.Generator
        The record's own noise stream: ``n`` encoder draws, then ``n`` force draws.
    encoder_noise_m, force_noise_rel, force_noise_n : float
        Standard deviations of the position reading, and of the force reading as
        ``force_noise_rel · F + force_noise_n``. Zeros give the exact record.
    """
    position = depths + rng.normal(0.0, 1.0, size=depths.size) * encoder_noise_m
    force = levels + rng.normal(0.0, 1.0, size=levels.size) * (
        force_noise_rel * levels + force_noise_n)
    return ForceTravel(travel_m=position - position[0], force_n=force)
