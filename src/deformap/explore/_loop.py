"""The exploration loop: drive any ``Environment`` with the mapper until the map field is known.

The loop speaks only to the :class:`~deformap.environment.Environment` protocol; it never knows
whether a simulated world or a robot answers. One poke, live or replayed, is one
:func:`poke_step`: acquire the press, reconstruct and estimate, add to the fields.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from deformap._validation import describe
from deformap.cloud import PointCloud
from deformap.environment import Environment, PressObservation, Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore._config import ExplorationConfig
from deformap.explore._journal import Journal
from deformap.explore._mapper import Mapper
from deformap.explore._records import PokeRecord, PokeResult, Target
from deformap.explore._result import ExplorationResult

__all__ = ["MappingRun", "explore", "poke_step"]


def poke_step(mapper: Mapper, index: int, acquire: Callable[[], PressObservation], *,
              finish: Callable[[], None] | None = None, target: Target | None = None,
              target_s: float | None = None) -> PokeResult:
    """One poke: ``acquire()`` the press, reconstruct its dent and β, ``finish()`` (the live
    loop's release; called even when the estimate fails), add it to the fields.

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


class MappingRun:
    """What every exploration shares around its pokes, live or replayed: ``observe()`` the first
    cloud and fit the surface model with ``surface_rng`` (timed), one :func:`poke_step` per poke,
    and the result with the run's timings."""

    def __init__(self, workspace: Workspace, config: ExplorationConfig,
                 observe: Callable[[], PointCloud], surface_rng: np.random.Generator) -> None:
        self._t_start = time.perf_counter()
        self.mapper = Mapper(workspace, config)
        cloud = observe()
        t_observed = time.perf_counter()
        self.mapper.initialise(cloud, surface_rng)
        self._timings = {"observe_s": t_observed - self._t_start,
                         "surface_gp_s": time.perf_counter() - t_observed}  # fmt: skip
        self._environment_s = 0.0

    def step(self, index: int, acquire: Callable[[], PressObservation], *,
             finish: Callable[[], None] | None = None, target: Target | None = None,
             target_s: float | None = None) -> PokeResult:
        """:func:`poke_step` on this run's mapper."""
        poke = poke_step(self.mapper, index, acquire, finish=finish, target=target,
                         target_s=target_s)  # fmt: skip
        self._environment_s += poke.record.timings.environment_s or 0.0
        return poke

    def result(self, stop_reason: str) -> ExplorationResult:
        """The result, with ``total_s``, ``observe_s``, ``surface_gp_s`` and ``environment_s``."""
        timings = {"total_s": time.perf_counter() - self._t_start, **self._timings,
                   "environment_s": self._environment_s}  # fmt: skip
        return self.mapper.result(stop_reason, timings)


def _check_arguments(env: object, config: object, rng: object, journal: object, done: object,
                     on_poke: object) -> None:
    """Refuse, naming the argument, what :func:`explore` cannot take (before any work)."""
    expected = (
        ("env", env, Environment, "an Environment (workspace, observe, press, release)"),
        ("config", config, ExplorationConfig, "an ExplorationConfig"),
        ("rng", rng, np.random.Generator, "a numpy.random.Generator"),
    )
    for name, value, kind, what in expected:
        if not isinstance(value, kind):
            raise InvalidArgumentError(f"`{name}` must be {what}; got {describe(value)}")
    if journal is not None and not isinstance(journal, Journal):
        raise InvalidArgumentError(f"`journal` must be a Journal or None; got {describe(journal)}")
    if isinstance(done, (str, bytes)) or not isinstance(done, Sequence) or not all(
            isinstance(r, PokeRecord) for r in done):
        raise InvalidArgumentError(f"`done` must be a sequence of PokeRecord; got {describe(done)}")
    if on_poke is not None and not callable(on_poke):
        raise InvalidArgumentError(f"`on_poke` must be callable or None; got {describe(on_poke)}")


def explore(env: Environment, config: ExplorationConfig, *, rng: np.random.Generator,
            journal: Journal | None = None, done: Sequence[PokeRecord] = (),
            on_poke: Callable[[PokeResult], None] | None = None) -> ExplorationResult:
    """Observe ``env``, then poke where the map field is least known until its variance is below
    ``T_h``, then make the ``boundary_pokes`` (if any) where a region boundary is least certain.

    ``rng`` is split once into streams (the surface fit, one per poke), so a resumed run draws
    what the uninterrupted run drew; each poke is appended to ``journal`` before the next starts;
    ``done`` (a killed run's journalled pokes) enter the fields without being pressed again;
    ``on_poke`` is called after each new poke.
    """
    _check_arguments(env, config, rng, journal, done, on_poke)
    streams = rng.spawn(config.max_pokes + 1)
    run = MappingRun(env.workspace, config, env.observe, streams[0])
    mapper = run.mapper
    for record in done:
        mapper.add(PokeResult(record))
    stop = "max_pokes"
    while len(mapper.pokes) < config.max_pokes:
        index = len(mapper.pokes)
        t_target = time.perf_counter()
        if index == 0:
            target: Target | None = Target(np.array(mapper.first_target(), dtype=float),
                                           "first")  # fmt: skip
        else:
            target = mapper.next_target(streams[index + 1])
        if target is None:
            stop = "threshold"
            break
        poke = run.step(index, partial(env.press, target.xy, config.force_n), finish=env.release,
                        target=target, target_s=time.perf_counter() - t_target)  # fmt: skip
        if journal is not None:
            journal.append(poke.record.to_dict())
        if on_poke is not None:
            on_poke(poke)
    else:
        # the poke limit stopped it unless the map was done
        if mapper.max_variance() <= mapper.threshold and mapper.boundary_owed() == 0:
            stop = "threshold"
    return run.result(stop)
