"""The ``Environment`` protocol: all the exploration loop needs from a world or a robot.

The simulated world (:mod:`deformap.world`) and a robot adapter implement it; the loop never knows
which one it drives. Everything is SI in the world frame (the table is ``z = 0``, ``z`` up), clouds
included. :class:`TactileContact` comes from :mod:`deformap.mechanics`.

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

from deformap._validation import check_array, check_points, check_positive, check_vector
from deformap.cloud import PointCloud, hull_parts, tip_in_view
from deformap.errors import InvalidArgumentError
from deformap.mechanics import TactileContact

__all__ = ["FORCE_MISMATCH_ABS_N", "FORCE_MISMATCH_REL", "MAX_GRID_CELLS", "MAX_TRAVEL_M",
           "MIN_FORCE_RISE_N", "TIP_IN_VIEW_RADII", "TRAVEL_BACKWARDS_TOLERANCE_M", "Environment",
           "ForceTravel", "PressObservation", "PressPhase", "TactileContact", "Workspace"]


#: Most cells of a :meth:`Workspace.grid` (200 MB per float map layer).
MAX_GRID_CELLS = 25_000_000


@dataclass(frozen=True, kw_only=True)
class Workspace:
    """The axis-aligned rectangle ``[lower, upper]`` of the table to map: corners ``(x_min, y_min)``
    and ``(x_max, y_max)`` in metres, ``upper`` above ``lower`` on both axes."""

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
        """Cell centres ``(xs, ys)`` of a grid of ``round(width / spacing)`` × ``round(depth / spacing)``
        cells over the rectangle; more than :data:`MAX_GRID_CELLS` are refused before any allocation."""
        step = check_positive("spacing_m", spacing_m)
        (x0, y0), (w, d) = self.lower, self.size
        nx, ny = max(1, round(w / step)), max(1, round(d / step))
        if nx * ny > MAX_GRID_CELLS:
            raise InvalidArgumentError(
                f"`spacing_m` must give at most {MAX_GRID_CELLS:,} cells over the "
                f"{w:g}×{d:g} m workspace; got {step:g} m ({nx:,}×{ny:,} cells)")
        xs = np.asarray(x0 + (np.arange(nx) + 0.5) * (w / nx), dtype=np.float64)
        ys = np.asarray(y0 + (np.arange(ny) + 0.5) * (d / ny), dtype=np.float64)
        return xs, ys

    def to_dict(self) -> dict[str, list[float]]:
        return {"lower": list(self.lower), "upper": list(self.upper)}


#: How far [m] travel may fall below its largest value before (encoder noise, not a retraction):
#: ten standard deviations of arm encoders.
TRAVEL_BACKWARDS_TOLERANCE_M = 5e-4

#: Largest travel accepted [m]: a 5 cm dent would put a 1 cm tip's stick into the foam.
MAX_TRAVEL_M = 0.05

#: The force must rise by more than this [N] over a record: four times a probe sensor's noise.
MIN_FORCE_RISE_N = 0.02

#: A point of the cloud after release within this many tip radii of the tip centre may be the tip
#: itself (the tip's radius and a margin for depth noise; :class:`PressObservation`).
TIP_IN_VIEW_RADII = 1.1

#: A measured force may differ from the commanded by at most ``FORCE_MISMATCH_REL · force_n +
#: FORCE_MISMATCH_ABS_N``: far beyond a controller's overshoot and a sensor's noise.
FORCE_MISMATCH_REL = 0.25
FORCE_MISMATCH_ABS_N = 0.05


def _allowed_mismatch(force_n: float) -> float:
    return FORCE_MISMATCH_REL * force_n + FORCE_MISMATCH_ABS_N


def _check_times(name: str, value: Any, size: int, after: float | None) -> NDArray[np.float64]:
    times = np.array(check_array(name, value, (size,), what="seconds"))
    step = np.diff(times)
    if step.size and float(step.min()) <= 0.0:
        at = int(np.argmax(step <= 0.0)) + 1
        raise InvalidArgumentError(
            f"`{name}` must increase sample by sample; sample {at} ({times[at]:.6g} s) does not "
            f"come after sample {at - 1} ({times[at - 1]:.6g} s)")
    if after is not None and float(times[0]) < after:
        raise InvalidArgumentError(
            f"`{name}` must start at or after the stretch before it ends ({after:.6g} s); got "
            f"{times[0]:.6g} s (time going backwards)")
    times.setflags(write=False)
    return times


@dataclass(frozen=True, kw_only=True)
class PressPhase:
    """A stretch of a press after its loading ramp, ``n >= 2`` samples in time order: the hold
    (the commanded force or position held) or the unloading branch (the tip retracting).

    ``time_s`` is seconds on the ramp's clock, strictly increasing; ``travel_m`` the travel since
    first contact [m] (as the ramp's, within :data:`MAX_TRAVEL_M`), ``force_n`` the normal force
    [N], >= 0 within :data:`MIN_FORCE_RISE_N`. Stored as read-only float64 copies.
    """

    time_s: NDArray[np.float64]
    travel_m: NDArray[np.float64]
    force_n: NDArray[np.float64]

    def __post_init__(self) -> None:
        travel = np.array(check_array("travel_m", self.travel_m, (None,), what="metres", min_rows=2))
        force = np.array(check_array("force_n", self.force_n, (travel.size,), what="newtons"))
        times = _check_times("time_s", self.time_s, travel.size, None)
        if (largest := float(np.max(np.abs(travel)))) > MAX_TRAVEL_M:
            raise InvalidArgumentError(f"`travel_m` must be metres, at most {MAX_TRAVEL_M} m in "
                                       f"magnitude; got {largest:.4g}")
        if float(force.min()) < -MIN_FORCE_RISE_N:
            raise InvalidArgumentError(
                f"`force_n` must be the force pressing the surface, >= 0 within {MIN_FORCE_RISE_N} "
                f"N; got {float(force.min()):.4g} N")
        for name, arr in (("travel_m", travel), ("force_n", force), ("time_s", times)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.travel_m.size)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PressPhase):
            return NotImplemented
        return all(np.array_equal(getattr(self, k), getattr(other, k))
                   for k in ("time_s", "travel_m", "force_n"))


def _same(a: PressPhase | NDArray[np.float64] | None,
          b: PressPhase | NDArray[np.float64] | None) -> bool:
    """Equality of two optional parts of a record (``None`` equals only ``None``)."""
    if a is None or b is None:
        return a is None and b is None
    return bool(a == b) if isinstance(a, PressPhase) or isinstance(b, PressPhase) else bool(
        np.array_equal(a, b))


@dataclass(frozen=True, kw_only=True)
class ForceTravel:
    """The press's force–travel record from first contact to the commanded force, ``n >= 3``
    samples in time order (from forward kinematics and a force sensor, ``docs/robot.md``).

    ``travel_m`` is the travel along the press since first contact [m]: about 0 at first, never more
    than :data:`TRAVEL_BACKWARDS_TOLERANCE_M` below its largest before, within :data:`MAX_TRAVEL_M`.
    ``force_n`` is the normal force on the surface [N], its last sample positive and more than
    :data:`MIN_FORCE_RISE_N` above the first. Both are stored as read-only float64 copies.

    Optional, for what the press did besides loading (``None``: the robot did not say): ``time_s``,
    the ramp's sample times [s], strictly increasing; ``hold``, the samples while the commanded
    force or position is held; ``unloading``, the samples as the tip retracts, whose force never
    rises by more than :data:`MIN_FORCE_RISE_N`. A hold or unloading needs ``time_s``; each stretch
    starts no earlier than the one before ends.
    """

    travel_m: NDArray[np.float64]
    force_n: NDArray[np.float64]
    time_s: NDArray[np.float64] | None = None
    hold: PressPhase | None = None
    unloading: PressPhase | None = None

    def __post_init__(self) -> None:
        travel = np.array(check_array("travel_m", self.travel_m, (None,), what="metres",
                                      min_rows=3))  # fmt: skip
        force = np.array(check_array("force_n", self.force_n, (None,), what="newtons",
                                     min_rows=3))  # fmt: skip
        if travel.shape != force.shape:
            raise InvalidArgumentError(
                f"`force_n` must have one sample per `travel_m` sample ({travel.size}); "
                f"got {force.size}")
        largest = float(np.max(np.abs(travel)))
        if largest > MAX_TRAVEL_M:
            raise InvalidArgumentError(
                f"`travel_m` must be metres, at most {MAX_TRAVEL_M} m in magnitude (a press does "
                f"not sink the tip that far; millimetres?); got {largest:.4g}")
        if abs(travel[0]) > TRAVEL_BACKWARDS_TOLERANCE_M:
            raise InvalidArgumentError(
                f"`travel_m` must be the travel since first contact, its first sample 0 within "
                f"{TRAVEL_BACKWARDS_TOLERANCE_M} m (encoder noise); got {travel[0]:.4g} m (an "
                "absolute position?)")
        if float(force.min()) < -MIN_FORCE_RISE_N:
            raise InvalidArgumentError(
                f"`force_n` must be the force pressing the surface, >= 0 within "
                f"{MIN_FORCE_RISE_N} N (sensor noise); got {float(force.min()):.4g} N (a sensor "
                "not zeroed, or its reaction force not negated?)")
        behind = np.maximum.accumulate(travel) - travel
        worst = int(np.argmax(behind))
        if behind[worst] > TRAVEL_BACKWARDS_TOLERANCE_M:
            raise InvalidArgumentError(
                f"`travel_m` must not go backwards by more than {TRAVEL_BACKWARDS_TOLERANCE_M} m "
                f"(encoder noise); sample {worst} lies {behind[worst]:.4g} m below the largest "
                "travel before it")
        rise = float(force[-1] - force[0])
        if force[-1] <= 0.0 or rise <= MIN_FORCE_RISE_N:
            raise InvalidArgumentError(
                f"`force_n` must rise from contact to the commanded force: the last sample "
                f"positive and more than {MIN_FORCE_RISE_N} N above the first; got first "
                f"{force[0]:.4g} N, last {force[-1]:.4g} N")
        travel.setflags(write=False)
        force.setflags(write=False)
        object.__setattr__(self, "travel_m", travel)
        object.__setattr__(self, "force_n", force)
        self._check_phases(travel.size)

    def _check_phases(self, n: int) -> None:
        if self.time_s is None:
            if self.hold is not None or self.unloading is not None:
                raise InvalidArgumentError(
                    "`time_s` must be given with a hold or an unloading branch (their times are "
                    "on the ramp's clock); got none")
            return
        times = _check_times("time_s", self.time_s, n, None)
        object.__setattr__(self, "time_s", times)
        end = float(times[-1])
        for name in ("hold", "unloading"):
            phase = getattr(self, name)
            if phase is None:
                continue
            if not isinstance(phase, PressPhase):
                raise InvalidArgumentError(f"`{name}` must be a PressPhase; got {type(phase)}")
            _check_times(f"{name}.time_s", phase.time_s, len(phase), end)
            end = float(phase.time_s[-1])
        unloading = self.unloading
        if unloading is not None:
            lowest = np.minimum.accumulate(unloading.force_n)
            rise = unloading.force_n - lowest
            worst = int(np.argmax(rise))
            if rise[worst] > MIN_FORCE_RISE_N:
                raise InvalidArgumentError(
                    f"`unloading.force_n` must fall as the tip retracts (no rise beyond "
                    f"{MIN_FORCE_RISE_N} N); sample {worst} lies {rise[worst]:.4g} N above the "
                    "lowest force before it")

    def __len__(self) -> int:
        return int(self.travel_m.size)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ForceTravel):
            return NotImplemented
        return bool(np.array_equal(self.travel_m, other.travel_m)
                    and np.array_equal(self.force_n, other.force_n)
                    and all(_same(getattr(self, k), getattr(other, k))
                            for k in ("time_s", "hold", "unloading")))


@dataclass(frozen=True, kw_only=True)
class PressObservation:
    """Everything one press returns (world frame, SI).

    ``cloud`` is seen while pressing, the robot in it; ``contact`` (tip, measured force, tip radius)
    pushes into the surface (negative z) within ``FORCE_MISMATCH_REL · force_n +
    FORCE_MISMATCH_ABS_N`` of the commanded ``force_n`` at ``target_xy``, as does the last force of
    ``force_travel`` (None where the environment has no record). ``robot_points`` ((m, 3), at least
    4 not coplanar) span the stick and hand, or a tuple holds one such array per part, each hull
    removed on its own (:attr:`robot_hulls` gives the tuple either way).

    ``released`` (optional) is the surface seen once the tip has left, for the dent the press
    kept. A cloud with the tip still in view is refused: its points within
    :data:`TIP_IN_VIEW_RADII` tip radii of ``contact.tip_center`` and more than half a radius
    above it (the tip's top, what a camera above sees of it) are the tip when their median height
    stands more than a quarter radius above the surface 2–3 radii away (its 90th percentile).
    """

    cloud: PointCloud
    contact: TactileContact
    robot_points: NDArray[np.float64] | tuple[NDArray[np.float64], ...]
    target_xy: NDArray[np.float64]
    force_n: float
    force_travel: ForceTravel | None = None
    released: PointCloud | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.cloud, PointCloud):
            raise InvalidArgumentError(f"`cloud` must be a PointCloud; got {type(self.cloud)}")
        if not isinstance(self.contact, TactileContact):
            raise InvalidArgumentError(
                f"`contact` must be a TactileContact; got {type(self.contact)}")
        parts = hull_parts(self.robot_points)
        hulls = ((check_points("robot_points", self.robot_points, min_rows=4),) if parts is None
                 else tuple(check_points(f"robot_points[{i}]", part, min_rows=4)
                            for i, part in enumerate(parts)))  # fmt: skip
        target = check_vector("target_xy", self.target_xy, 2, what="metres")
        for hull in hulls:
            hull.setflags(write=False)
        target.setflags(write=False)
        object.__setattr__(self, "robot_points", hulls[0] if parts is None else hulls)
        object.__setattr__(self, "target_xy", target)
        force_n = check_positive("force_n", self.force_n)
        object.__setattr__(self, "force_n", force_n)
        self._check_contact_force(force_n)
        self._check_released()
        record = self.force_travel
        if record is None:
            return
        if not isinstance(record, ForceTravel):
            raise InvalidArgumentError(
                f"`force_travel` must be a ForceTravel or None; got {type(record).__name__}")
        final, allowed = float(record.force_n[-1]), _allowed_mismatch(force_n)
        if abs(final - force_n) > allowed:
            raise InvalidArgumentError(
                f"`force_travel` must end at the commanded force {force_n:.4g} N (within "
                f"{allowed:.3g} N); its last force is {final:.4g} N")

    def _check_released(self) -> None:
        """The cloud after release must be a PointCloud with no point where the tip's top would be."""
        released = self.released
        if released is None:
            return
        if not isinstance(released, PointCloud):
            raise InvalidArgumentError(
                f"`released` must be a PointCloud or None; got {type(released).__name__}")
        shown = tip_in_view(released.points, self.contact.tip_center, self.contact.tip_radius_m,
                            within_radii=TIP_IN_VIEW_RADII)
        if shown:
            raise InvalidArgumentError(
                f"`released` must be seen once the tip has left; {shown} of its points lie within "
                f"{TIP_IN_VIEW_RADII} tip radii of the tip centre, on its top (the tip still in "
                "view)")

    @property
    def robot_hulls(self) -> tuple[NDArray[np.float64], ...]:
        """The robot's hulls' points, one ``(m_i, 3)`` array per part (one for a single hull)."""
        robot = self.robot_points
        return robot if isinstance(robot, tuple) else (robot,)

    def _check_contact_force(self, force_n: float) -> None:
        """The measured force must push into the surface (world z up) at about the commanded size."""
        force = self.contact.force
        if force[2] >= 0.0:
            raise InvalidArgumentError(
                "`contact.force` must push into the surface (negative z in the world frame, z up); "
                f"got {tuple(float(f) for f in force)} N")
        measured, allowed = self.contact.force_n, _allowed_mismatch(force_n)
        if abs(measured - force_n) > allowed:
            raise InvalidArgumentError(
                f"`contact.force` must be near the commanded force {force_n:.4g} N (within "
                f"{allowed:.3g} N); its magnitude is {measured:.4g} N")


@runtime_checkable
class Environment(Protocol):
    """A surface that can be seen and pressed: a simulated world or a real robot.

    A target outside ``workspace``, a non-positive force and a second ``press`` before ``release``
    are refused with a :class:`~deformap.errors.DeformapError`.
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
