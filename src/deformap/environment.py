"""The ``Environment`` protocol: all the exploration loop needs from a world or a robot.

The simulated world (:mod:`deformap.world`) and a real robot adapter both implement it, and the loop
in :mod:`deformap.explore` never knows which one it drives. :class:`TactileContact` is contact
mechanics, defined in :mod:`deformap.mechanics` (so that the estimator can take it without this
protocol) and re-exported here: ``deformap.environment.TactileContact`` is the same class.

Frames and units
----------------
Everything is SI and in the world frame: the table plane is ``z = 0``, ``z`` points up, and clouds
leave an environment already transformed by the camera's known extrinsics (``cam2world``).

References
----------
Caccamo, S., Güler, P., Kjellström, H., Kragic, D. (2016). Active Perception and Modeling of
Deformable Surfaces using Gaussian Processes and Position-based Dynamics. IEEE-RAS Humanoids.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from deformap._validation import (
    check_array,
    check_points,
    check_positive,
    check_vector,
)
from deformap.cloud import PointCloud
from deformap.errors import InvalidArgumentError
from deformap.mechanics import TactileContact

__all__ = [
    "Environment",
    "PressObservation",
    "TactileContact",
    "Workspace",
]


@dataclass(frozen=True, kw_only=True)
class Workspace:
    """The axis-aligned rectangle ``[lower, upper]`` of the table to map, in metres.

    Parameters
    ----------
    lower, upper : (2,) float
        Corners ``(x_min, y_min)`` and ``(x_max, y_max)``; ``upper`` must exceed ``lower``.
    """

    lower: tuple[float, float] = (0.0, 0.0)
    upper: tuple[float, float] = (0.60, 0.40)

    def __post_init__(self) -> None:
        lo = check_vector("lower", self.lower, 2, what="metres")
        hi = check_vector("upper", self.upper, 2, what="metres")
        if np.any(hi <= lo):
            raise InvalidArgumentError(
                f"`upper` must exceed `lower` on both axes; got lower={tuple(lo)}, upper={tuple(hi)}"
            )
        object.__setattr__(self, "lower", (float(lo[0]), float(lo[1])))
        object.__setattr__(self, "upper", (float(hi[0]), float(hi[1])))

    @property
    def size(self) -> tuple[float, float]:
        """Width and depth in metres."""
        return (self.upper[0] - self.lower[0], self.upper[1] - self.lower[1])

    @property
    def center(self) -> tuple[float, float]:
        """The rectangle's centre ``(x, y)`` in metres."""
        return (0.5 * (self.lower[0] + self.upper[0]), 0.5 * (self.lower[1] + self.upper[1]))

    def contains(self, xy: Any) -> NDArray[np.bool_]:
        """Mask of the ``(n, 2)`` points that lie inside the rectangle (edges included)."""
        pts = check_array("xy", np.atleast_2d(xy), (None, 2), what="xy coordinates in metres")
        lo, hi = np.asarray(self.lower), np.asarray(self.upper)
        return np.all((pts >= lo) & (pts <= hi), axis=1)

    def grid(self, spacing_m: float = 0.005) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Cell-centre coordinates ``(xs, ys)`` of a regular grid covering the rectangle.

        The grid has ``round(width / spacing)`` columns and ``round(depth / spacing)`` rows, so a
        60×40 cm workspace at the paper's 0.5 cm gives 120×80 cells.
        """
        step = check_positive("spacing_m", spacing_m)
        (x0, y0), (w, d) = self.lower, self.size
        nx, ny = max(1, round(w / step)), max(1, round(d / step))
        xs = np.asarray(x0 + (np.arange(nx) + 0.5) * (w / nx), dtype=np.float64)
        ys = np.asarray(y0 + (np.arange(ny) + 0.5) * (d / ny), dtype=np.float64)
        return xs, ys

    def to_dict(self) -> dict[str, list[float]]:
        return {"lower": list(self.lower), "upper": list(self.upper)}


@dataclass(frozen=True, kw_only=True)
class PressObservation:
    """Everything one press returns.

    Parameters
    ----------
    cloud : PointCloud
        The cloud seen while pressing, world frame. It contains the robot's stick and hand and
        misses what they occlude.
    contact : TactileContact
        Tip position, measured force and tip radius at the commanded force.
    robot_points : (m, 3) float, metres
        Points whose convex hull covers the stick and hand at that moment, from the robot model
        and proprioception (at least 4 points, not all on a plane).
    target_xy : (2,) float, metres
        The commanded target.
    force_n : float
        The commanded normal force.
    """

    cloud: PointCloud
    contact: TactileContact
    robot_points: NDArray[np.float64]
    target_xy: NDArray[np.float64]
    force_n: float

    def __post_init__(self) -> None:
        if not isinstance(self.cloud, PointCloud):
            raise InvalidArgumentError(f"`cloud` must be a PointCloud; got {type(self.cloud)}")
        if not isinstance(self.contact, TactileContact):
            raise InvalidArgumentError(
                f"`contact` must be a TactileContact; got {type(self.contact)}"
            )
        robot = check_points("robot_points", self.robot_points, min_rows=4)
        target = check_vector("target_xy", self.target_xy, 2, what="metres")
        robot.setflags(write=False)
        target.setflags(write=False)
        object.__setattr__(self, "robot_points", robot)
        object.__setattr__(self, "target_xy", target)
        object.__setattr__(self, "force_n", check_positive("force_n", self.force_n))


@runtime_checkable
class Environment(Protocol):
    """A surface that can be seen and pressed: a simulated world or a real robot.

    Implementations refuse a target outside ``workspace``, a non-positive force and a second
    ``press`` before ``release`` with a :class:`~deformap.errors.DeformapError`.
    """

    @property
    def workspace(self) -> Workspace:
        """The rectangle to map."""
        ...

    def observe(self) -> PointCloud:
        """One depth-camera cloud of the undisturbed surface, in the world frame."""
        ...

    def press(self, target_xy: Any, force_n: float) -> PressObservation:
        """Press at ``target_xy`` along the surface normal with ``force_n`` newtons and hold."""
        ...

    def release(self) -> None:
        """Lift the probe off the surface; the next ``press`` is allowed again."""
        ...
