"""The exploration loop: drive any ``Environment`` with the mapper until the β-field is known.

The loop speaks only to the :class:`~deformap.environment.Environment` protocol; it never knows
whether a simulated world or a robot answers. One poke, live or replayed, is one
:func:`poke_step`: acquire the press, reconstruct and estimate, add to the β-field.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np

from deformap.environment import Environment, PressObservation
from deformap.explore._config import ExplorationConfig
from deformap.explore._journal import Journal
from deformap.explore._mapper import Mapper
from deformap.explore._records import PokeRecord, PokeResult, Target
from deformap.explore._result import ExplorationResult

__all__ = ["explore", "poke_step"]


def poke_step(mapper: Mapper, index: int, acquire: Callable[[], PressObservation], *,
              finish: Callable[[], None] | None = None, target: Target | None = None,
              target_s: float | None = None) -> PokeResult:
    """One poke: ``acquire()`` the press, reconstruct its dent and β, ``finish()`` (the live
    loop's release; called even when the estimate fails), add it to the β-field.

    ``environment_s`` of the record is the time spent in ``acquire`` and ``finish``.
    """
    t0 = time.perf_counter()
    obs = acquire()
    try:
        t1 = time.perf_counter()
        poke = mapper.process_press(obs, index)
    finally:
        t2 = time.perf_counter()
        if finish is not None:
            finish()
        t3 = time.perf_counter()
    timings = {"environment_s": (t1 - t0) + (t3 - t2)}
    if target_s is not None:
        timings = {"target_s": target_s, **timings}
    return mapper.add(poke, target=target, timings=timings)


def explore(
    env: Environment,
    config: ExplorationConfig,
    *,
    rng: np.random.Generator,
    journal: Journal | None = None,
    done: Sequence[dict[str, Any]] = (),
    on_poke: Callable[[PokeResult], None] | None = None,
) -> ExplorationResult:
    """Observe, then poke where the β-field is least known until its variance is below ``T_h``,
    then make the ``boundary_pokes`` (if any) where a region boundary is least certain.

    Parameters
    ----------
    env : Environment
        The world or robot to explore.
    config : ExplorationConfig
        Settings of the mapper and the loop.
    rng : numpy.random.Generator
        The run's randomness. It is split once into independent streams (one for the surface fit,
        one per poke), so a resumed run draws exactly what the uninterrupted run drew.
    journal : Journal, optional
        Each completed poke is appended (and fsynced) before the next one starts.
    done : sequence of dict
        Poke records of a killed run, as its journal holds them (:meth:`PokeRecord.to_dict`'s
        form): they enter the β-field without being pressed or estimated again.
    on_poke : callable, optional
        Called after each new poke (progress display).
    """
    t_start = time.perf_counter()
    streams = rng.spawn(config.max_pokes + 1)
    mapper = Mapper(env.workspace, config)
    cloud = env.observe()
    t_observed = time.perf_counter()
    mapper.initialise(cloud, streams[0])
    t_surface = time.perf_counter()
    for k, record in enumerate(done):
        mapper.add(PokeResult(PokeRecord.from_dict(record, where=f"journal poke {k + 1}")))
    stop = "max_pokes"
    env_s = 0.0
    while len(mapper.pokes) < config.max_pokes:
        index = len(mapper.pokes)
        t_target = time.perf_counter()
        if index == 0:
            first = config.first_target
            xy = env.workspace.center if first is None else first
            target: Target | None = Target(np.array(xy, dtype=float), "first")
        else:
            target = mapper.next_target(streams[index + 1])
        if target is None:
            stop = "threshold"
            break
        poke = poke_step(mapper, index, partial(env.press, target.xy, config.force_n),
                         finish=env.release, target=target,
                         target_s=time.perf_counter() - t_target)  # fmt: skip
        env_s += poke.record.timings.environment_s or 0.0
        if journal is not None:
            journal.append(poke.record.to_dict())
        if on_poke is not None:
            on_poke(poke)
    else:
        # the poke limit stopped it unless the map was done: variance under T_h and no boundary
        # poke owed
        if mapper.max_variance() <= config.threshold and mapper.boundary_owed() == 0:
            stop = "threshold"
    timings = {
        "total_s": time.perf_counter() - t_start,
        "observe_s": t_observed - t_start,
        "surface_gp_s": t_surface - t_observed,
        "environment_s": env_s,
    }
    return mapper.result(stop, timings)
