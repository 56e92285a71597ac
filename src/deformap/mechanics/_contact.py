"""The tactile contact: where the probe's tip is and what force it exerts at a press."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_positive, check_vector
from deformap.errors import InvalidArgumentError

__all__ = ["TactileContact"]


@dataclass(frozen=True, kw_only=True)
class TactileContact:
    """What the force sensor and proprioception say at the moment of the press: the ``(3,)``
    ``tip_center`` (world frame, metres) of the spherical tip of radius ``tip_radius_m`` and the
    ``(3,)`` ``force`` in newtons it exerts on the surface (``(0, 0, -F)`` pressing down)."""

    tip_center: NDArray[np.float64]
    force: NDArray[np.float64]
    tip_radius_m: float

    def __post_init__(self) -> None:
        center = check_vector("tip_center", self.tip_center, 3, what="metres")
        force = check_vector("force", self.force, 3, what="newtons")
        if not np.any(force):
            raise InvalidArgumentError("`force` must be a non-zero force vector; got (0, 0, 0)")
        for name, value in (("tip_center", center), ("force", force)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "tip_radius_m", check_positive("tip_radius_m", self.tip_radius_m))

    @property
    def force_n(self) -> float:
        """Magnitude of the contact force in newtons."""
        return float(np.linalg.norm(self.force))

    @property
    def direction(self) -> NDArray[np.float64]:
        """Unit vector of the force the probe exerts on the surface."""
        return np.asarray(self.force / np.linalg.norm(self.force))

    @property
    def contact_point(self) -> NDArray[np.float64]:
        """The point of the tip farthest along the force: where it presses the surface."""
        return np.asarray(self.tip_center + self.tip_radius_m * self.direction)
