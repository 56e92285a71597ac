"""The exploration loop: drive any ``Environment`` with the mapper until the β-field is known.

The loop speaks only to the :class:`~deformap.environment.Environment` protocol; it never knows
whether a simulated world or a robot answers (DESIGN.md, rule 1).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from deformap.environment import Environment
from deformap.explore._config import ExplorationConfig
from deformap.explore._journal import Journal
from deformap.explore._mapper import Mapper, PokeResult

__all__ = ["ExplorationResult", "explore"]

logger = logging.getLogger(__name__)

StopReason = Literal["threshold", "max_pokes"]


@dataclass
class ExplorationResult:
    """What one exploration produced."""

    mapper: Mapper
    stop_reason: StopReason
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def pokes(self) -> list[PokeResult]:
        return self.mapper.pokes


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
        Poke records of a killed run, from its journal: they enter the β-field without being
        pressed or estimated again.
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
    for record in done:
        mapper.add(PokeResult(dict(record)))
    stop: StopReason = "max_pokes"
    env_s = 0.0
    while len(mapper.pokes) < config.max_pokes:
        index = len(mapper.pokes)
        first = config.first_target
        t_target = time.perf_counter()
        target = (
            np.array(env.workspace.center if first is None else first, dtype=float)
            if index == 0
            else mapper.next_target(streams[index + 1])
        )
        if target is None:
            stop = "threshold"
            break
        t0 = time.perf_counter()
        target_s = t0 - t_target
        obs = env.press(target, config.force_n)
        try:
            t1 = time.perf_counter()
            poke = mapper.process_press(obs, index)
        finally:
            t2 = time.perf_counter()
            env.release()
        t3 = time.perf_counter()
        # why this place: the first poke, the strategy's (until T_h), or a boundary poke
        poke.record["purpose"] = "first" if index == 0 else mapper.last_purpose
        plan = mapper.last_plan if index > 0 else None
        if plan is not None and plan.reaches:
            # the pokes the plan still foresees after this one (the progress display shows it)
            poke.record["planned_after"] = len(plan.targets) - 1
        mapper.add(poke)
        poke.record["timings"]["target_s"] = target_s
        poke.record["timings"]["environment_s"] = (t1 - t0) + (t3 - t2)
        env_s += poke.record["timings"]["environment_s"]
        if journal is not None:
            journal.append(poke.record)
        if on_poke is not None:
            on_poke(poke)
    else:
        # the poke limit stopped it unless the map was done: variance under T_h and no boundary
        # poke owed
        if mapper.max_variance() <= config.threshold and mapper.boundary_owed() == 0:
            stop = "threshold"
    total = time.perf_counter() - t_start
    timings = {
        "total_s": total,
        "observe_s": t_observed - t_start,
        "surface_gp_s": t_surface - t_observed,
        "environment_s": env_s,
    }
    return ExplorationResult(mapper=mapper, stop_reason=stop, timings=timings)
