"""What every figure of stiffness shares: one colour direction, soft dark and stiff light.

The modulus E and a world's hardness are drawn with :data:`STIFFNESS_CMAP` on a log scale
(:func:`modulus_norm`), the deformability β (which grows with softness) with its reverse, so that
in every figure the same colour means the same end of the scale: dark is soft, light is stiff. A
rigid surface, which has no modulus to draw, is :data:`RIGID_COLOUR`.
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import LogNorm
from numpy.typing import ArrayLike

__all__ = ["BETA_CMAP", "RIGID_COLOUR", "STIFFNESS_CMAP", "modulus_norm"]

STIFFNESS_CMAP = "viridis"
"""E and hardness: soft (low) dark, stiff (high) light; viridis reads in grey and to most
colour-blind readers."""

BETA_CMAP = "viridis_r"
"""β, which is high where the surface is soft: the reverse of :data:`STIFFNESS_CMAP`."""

RIGID_COLOUR = "0.55"
"""A rigid surface (no modulus to draw): a mid grey, apart from both ends of the colour map."""


def modulus_norm(*moduli_kpa: ArrayLike) -> LogNorm:
    """A log colour scale over the finite, positive values of every array given (kPa), widened
    about its geometric middle to span at least a factor of ten, so that one scale serves the
    maps drawn side by side and a near-uniform map does not paint noise as structure."""
    values = [np.asarray(m, dtype=float).ravel() for m in moduli_kpa]
    finite = np.concatenate(values) if values else np.array([])
    finite = finite[np.isfinite(finite) & (finite > 0)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (1.0, 10.0)
    if high / low < 10.0:
        mid = np.sqrt(low * high)
        low, high = mid / np.sqrt(10.0), mid * np.sqrt(10.0)
    return LogNorm(vmin=low, vmax=high)
