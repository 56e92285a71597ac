"""The force–travel record of a simulated press, from the world's own physics.

A real arm records, from first contact to the commanded force, the tip's travel along the press
direction and the normal force (``docs/robot.md``). The world solves a press at each load level
(:func:`force_levels`, from the contact threshold to the commanded force, evenly spaced in force):
the true indentation at level ``k`` is the dent depth ``δ(F_k)``. The encoders read the tip's
position with an error of ``encoder_noise_m`` and the travel is counted from first contact (the
first travel is exactly 0); the force sensor reads ``F`` with an error of ``rel · F + abs`` (one
standard deviation), each sample's draws independent.

The probe's protocol (:class:`~deformap.world._config.WorldConfig`) is load-controlled
(:func:`press_schedule`): the force rises at ``ramp_rate_n_per_s``, so level ``k`` is reached at
``(F_k − F_0) / rate``; an optional hold keeps the commanded force for ``hold_s`` (travel may
creep); an optional unloading branch lowers the force from the commanded one to the contact
threshold at the same rate. The world's physics solves the ramp at its levels, the hold at
``n_levels`` evenly spaced times and the unloading at the ramp's levels in reverse (the solved
schedule); the sensors read the ramp, the hold and the unloading at their own rate,
``sample_rate_hz`` (the sensor schedule: on the ramp and the unloading the force linear in time,
never fewer samples per stretch than the solved levels above contact), each sample's true
indentation read between the solved ones by the material's own law (:func:`sensor_depths`); no
sample costs a press solve of its own. The phases' noise is drawn from a stream of their own,
after the ramp's, so the ramp is the record without them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from deformap.environment import ForceTravel, PressPhase
from deformap.errors import InvalidArgumentError
from deformap.world._plastic import PlasticPress
from deformap.world._viscoelastic import PressHistory

__all__ = ["MAX_STRETCH_SAMPLES", "PressSchedule", "between_levels", "force_levels",
           "press_schedule", "sensor_depths", "simulated_force_travel", "with_phases"]


def force_levels(contact_n: float, force_n: float, n_levels: int) -> NDArray[np.float64]:
    """``(n_levels + 1,)`` forces from ``contact_n`` to ``force_n`` (both kept), evenly spaced in
    force: the levels a press is solved at."""
    return np.linspace(contact_n, force_n, n_levels + 1)


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


@dataclass(frozen=True, kw_only=True)
class PressSchedule:
    """When each sample of a press is taken: the ramp's ``times`` ``(n,)`` (seconds from first
    contact) at its forces ``levels`` ``(n,)`` (the solved levels, or the forces the sensors read
    the ramp at); the hold's times ``(m,)`` (empty: none) at the last level; the unloading's times
    and forces (empty: none)."""

    levels: NDArray[np.float64]
    times: NDArray[np.float64]
    hold_times: NDArray[np.float64]
    unload_times: NDArray[np.float64]
    unload_forces: NDArray[np.float64]

    @property
    def has_phases(self) -> bool:
        return bool(self.hold_times.size or self.unload_times.size)


#: Most samples one stretch of a record (ramp, hold or unloading) may hold: 100 s at 10 kHz, a
#: creep test's length at a fast sensor's rate; more is a protocol mistyped, not a press.
MAX_STRETCH_SAMPLES = 1_000_000


def _stretch(seconds: float, sample_rate_hz: float, n_levels: int, what: str) -> int:
    """Samples of a stretch ``seconds`` long at ``sample_rate_hz`` (never fewer than the solved
    levels), or a clear error naming the settings that made it too long."""
    n = max(n_levels, round(seconds * sample_rate_hz))
    if n > MAX_STRETCH_SAMPLES:
        raise InvalidArgumentError(
            f"the press's {what} would hold {n} samples ({seconds:.3g} s at `sample_rate_hz` "
            f"{sample_rate_hz:g}); at most {MAX_STRETCH_SAMPLES}: lower `sample_rate_hz`, or "
            f"raise `ramp_rate_n_per_s` / shorten `hold_s`")
    return n


def _falling(top: float, bottom: float, n: int) -> NDArray[np.float64]:
    """``n`` forces after ``top``, evenly spaced down to ``bottom`` (exactly, the last)."""
    forces = top - (top - bottom) * np.arange(1, n + 1) / n
    forces[-1] = bottom
    return forces


def press_schedule(levels: NDArray[np.float64], *, rate_n_per_s: float, hold_s: float,
                   unload: bool, sample_rate_hz: float | None = None) -> PressSchedule:
    """The protocol's sample times for a ramp through the solved ``levels`` (module docstring):
    the solved schedule, or with ``sample_rate_hz`` the sensors' (the ramp, the hold and the
    unloading sampled at that rate, each with never fewer samples than the levels above
    contact)."""
    n = levels.size - 1
    ramp_s = (levels[-1] - levels[0]) / rate_n_per_s
    if sample_rate_hz is None:
        forces = levels
    else:
        n_ramp = _stretch(ramp_s, sample_rate_hz, n, "loading ramp")
        forces = levels[0] + (levels[-1] - levels[0]) * np.arange(n_ramp + 1) / n_ramp
        forces[-1] = levels[-1]  # the commanded force exactly, as the solved ramp
    times = (forces - levels[0]) / rate_n_per_s
    n_hold = n if sample_rate_hz is None else _stretch(hold_s, sample_rate_hz, n, "hold")
    hold = times[-1] + hold_s * np.arange(1, n_hold + 1) / n_hold if hold_s > 0.0 else np.zeros(0)
    end = hold[-1] if hold.size else times[-1]
    if not unload:
        down = np.zeros(0)
    elif sample_rate_hz is None:
        down = levels[-2::-1].copy()
    else:
        down = _falling(levels[-1], levels[0], _stretch(ramp_s, sample_rate_hz, n, "unloading"))
    unload_times = end + (levels[-1] - down) / rate_n_per_s
    return PressSchedule(levels=forces, times=times, hold_times=hold,
                         unload_times=unload_times, unload_forces=down)


def between_levels(forces: NDArray[np.float64], level_forces: NDArray[np.float64],
                   level_depths: NDArray[np.float64]) -> NDArray[np.float64]:
    """The indentation at ``forces`` from the indentations solved at ``level_forces``, linear in
    ``F^(2/3)`` between neighbouring levels: the sphere's contact law ``δ = a + c F^(2/3)``
    (Hertz; ``a`` a dent already kept) over each interval."""
    x = np.maximum(level_forces, 0.0) ** (2.0 / 3.0)
    order = np.argsort(x, kind="stable")
    return np.interp(np.maximum(forces, 0.0) ** (2.0 / 3.0), x[order], level_depths[order])


def sensor_depths(solved: PressSchedule, sensor: PressSchedule, depths: NDArray[np.float64],
                  history: PressHistory | PlasticPress | None
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The true indentations at the ``sensor`` schedule's ramp, hold and unloading samples, from
    the ramp's ``depths`` at the solved levels and the press's ``history`` solved on the
    ``solved`` schedule (``None``: an elastic block).

    Elastic and plastic (rate-independent): the ramp reads between its solved levels, and the
    unloading between its own (an elastic block's retrace the ramp's), by :func:`between_levels`;
    the hold keeps the last level's indentation. Viscoelastic: the hold and the unloading are
    linear in time between the time steps of the solve, the strain's own form over a step in its
    recursive update (:mod:`deformap.world._viscoelastic`); the ramp, where the force rises with
    time, is linear in ``F^(2/3)`` between its steps (:func:`between_levels` on the steps' forces:
    over one step the body answers as an elastic one of the step's algorithmic compliance, whose
    indentation under a sphere goes as ``F^(2/3)``). A sample at a solved level's or step's time
    is that solve's indentation."""
    if isinstance(history, PressHistory):
        on_ramp = history.step_times <= solved.times[-1] * (1.0 + 1e-12)
        ramp = between_levels(sensor.levels, history.step_forces[on_ramp],
                              history.step_depths[on_ramp])
        return (ramp, np.interp(sensor.hold_times, history.step_times, history.step_depths),
                np.interp(sensor.unload_times, history.step_times, history.step_depths))
    ramp = between_levels(sensor.levels, solved.levels, depths)
    hold = np.full(sensor.hold_times.size, depths[-1])
    if history is None:
        return ramp, hold, between_levels(sensor.unload_forces, solved.levels, depths)
    forces = np.concatenate([solved.levels[-1:], solved.unload_forces])
    solved_depths = np.concatenate([depths[-1:], history.unloading])
    return ramp, hold, between_levels(sensor.unload_forces, forces, solved_depths)


def with_phases(record: ForceTravel, schedule: PressSchedule, zero_m: float,
                hold_depths: NDArray[np.float64], unload_depths: NDArray[np.float64],
                rng: np.random.Generator, *, encoder_noise_m: float, force_noise_rel: float,
                force_noise_n: float) -> ForceTravel:
    """``record`` with the schedule's times, hold and unloading, whose true indentations are
    ``hold_depths`` and ``unload_depths``; travel is counted from ``zero_m``, the encoder's reading
    at first contact. The unloading force is recorded as its running minimum: the controller
    retracts until the force has fallen to each level, so sensor noise never shows as a rise."""
    phases: dict[str, PressPhase] = {}
    for name, times, depths, forces in (
            ("hold", schedule.hold_times, hold_depths,
             np.full(schedule.hold_times.size, schedule.levels[-1])),
            ("unloading", schedule.unload_times, unload_depths, schedule.unload_forces)):
        if not times.size:
            continue
        travel = depths + rng.normal(0.0, 1.0, size=depths.size) * encoder_noise_m - zero_m
        force = forces + rng.normal(0.0, 1.0, size=forces.size) * (
            force_noise_rel * forces + force_noise_n)
        if name == "unloading":
            force = np.minimum.accumulate(np.maximum(force, 0.0))
        phases[name] = PressPhase(time_s=times, travel_m=travel, force_n=force)
    return replace(record, time_s=schedule.times, hold=phases.get("hold"),
                   unloading=phases.get("unloading"))
