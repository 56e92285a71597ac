"""The force–travel record of a simulated press, from the world's own physics.

A real arm records, from first contact to the commanded force, the tip's travel along the press
direction and the normal force (``docs/robot.md``). The world solves a press at each load level
(:func:`force_levels`, from the contact threshold to the commanded force): the true travel at level
``k`` is the dent depth ``δ(F_k)``. The encoders read the tip's position with an error of
``encoder_noise_m`` and the travel is counted from first contact (the first travel is exactly 0);
the force sensor reads ``F_k`` with an error of ``rel · F_k + abs`` (one standard deviation).

The probe's protocol (:class:`~deformap.world._config.WorldConfig`) may add sample times, a hold
and an unloading branch (:func:`press_schedule`). The ramp is load-controlled: the force rises at
``ramp_rate_n_per_s``, so level ``k`` is reached at ``(F_k − F_0) / rate``; the hold keeps the
commanded force for ``hold_s`` (travel may creep); the unloading branch lowers the force from the
commanded one to the contact threshold at the same rate. The world's physics solves the hold at
``n_levels`` evenly spaced times and the unloading at the ramp's levels in reverse (the solved
schedule); the sensors read the hold and the unloading at their own rate, ``sample_rate_hz``
(the sensor schedule, never fewer samples than the solved one), each sample's true indentation
read between the solved ones by the material's own law (:func:`phase_depths`). The phases' noise
is drawn from a stream of their own, after the ramp's, so the ramp is the record without them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from deformap.environment import ForceTravel, PressPhase
from deformap.world._config import RecordSpacing
from deformap.world._plastic import PlasticPress
from deformap.world._viscoelastic import PressHistory

__all__ = ["PressSchedule", "between_levels", "force_levels", "phase_depths", "press_schedule",
           "simulated_force_travel", "with_phases"]


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


@dataclass(frozen=True, kw_only=True)
class PressSchedule:
    """When each sample of a press is taken: the ramp's ``times`` ``(n,)`` (seconds from first
    contact) at its ``levels``; the hold's times ``(m,)`` (empty: none) at the last level; the
    unloading's times and forces (empty: none)."""

    levels: NDArray[np.float64]
    times: NDArray[np.float64]
    hold_times: NDArray[np.float64]
    unload_times: NDArray[np.float64]
    unload_forces: NDArray[np.float64]

    @property
    def has_phases(self) -> bool:
        return bool(self.hold_times.size or self.unload_times.size)


def press_schedule(levels: NDArray[np.float64], *, rate_n_per_s: float, hold_s: float,
                   unload: bool, sample_rate_hz: float | None = None) -> PressSchedule:
    """The protocol's sample times for a ramp through ``levels`` (module docstring): the solved
    schedule, or with ``sample_rate_hz`` the sensors' (the hold and the unloading sampled at that
    rate, never fewer samples than the ramp's levels above contact)."""
    times = (levels - levels[0]) / rate_n_per_s
    n = levels.size - 1
    n_hold = n if sample_rate_hz is None else max(n, round(hold_s * sample_rate_hz))
    hold = times[-1] + hold_s * np.arange(1, n_hold + 1) / n_hold if hold_s > 0.0 else np.zeros(0)
    end = hold[-1] if hold.size else times[-1]
    if not unload:
        forces = np.zeros(0)
    elif sample_rate_hz is None:
        forces = levels[-2::-1].copy()
    else:
        n_unload = max(n, round((levels[-1] - levels[0]) / rate_n_per_s * sample_rate_hz))
        forces = levels[-1] - (levels[-1] - levels[0]) * np.arange(1, n_unload + 1) / n_unload
        forces[-1] = levels[0]  # down to contact exactly, as the solved branch
    unload_times = end + (levels[-1] - forces) / rate_n_per_s
    return PressSchedule(levels=levels, times=times, hold_times=hold,
                         unload_times=unload_times, unload_forces=forces)


def between_levels(forces: NDArray[np.float64], level_forces: NDArray[np.float64],
                   level_depths: NDArray[np.float64]) -> NDArray[np.float64]:
    """The indentation at ``forces`` from the indentations solved at ``level_forces``, linear in
    ``F^(2/3)`` between neighbouring levels: the sphere's contact law ``δ = a + c F^(2/3)``
    (Hertz; ``a`` a dent already kept) over each interval."""
    x = np.maximum(level_forces, 0.0) ** (2.0 / 3.0)
    order = np.argsort(x, kind="stable")
    return np.interp(np.maximum(forces, 0.0) ** (2.0 / 3.0), x[order], level_depths[order])


def phase_depths(solved: PressSchedule, sensor: PressSchedule, depths: NDArray[np.float64],
                 history: PressHistory | PlasticPress | None
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """The true indentations at the ``sensor`` schedule's hold and unloading samples, from the
    ramp's ``depths`` and the press's ``history`` solved on the ``solved`` schedule (``None``:
    an elastic block). Elastic: the hold keeps the last level's indentation and the unloading
    retraces the ramp's levels. Plastic (rate-independent): the hold keeps it too and the
    unloading follows its own solved levels. Both read between levels by
    :func:`between_levels`. Viscoelastic: linear in time between the time steps of the solve,
    the strain's own form over a step in its recursive update
    (:mod:`deformap.world._viscoelastic`)."""
    if isinstance(history, PressHistory):
        return (np.interp(sensor.hold_times, history.step_times, history.step_depths),
                np.interp(sensor.unload_times, history.step_times, history.step_depths))
    hold = np.full(sensor.hold_times.size, depths[-1])
    if history is None:
        return hold, between_levels(sensor.unload_forces, solved.levels, depths)
    forces = np.concatenate([solved.levels[-1:], solved.unload_forces])
    solved_depths = np.concatenate([depths[-1:], history.unloading])
    return hold, between_levels(sensor.unload_forces, forces, solved_depths)


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
