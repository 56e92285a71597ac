"""Speed of the simulated world: construction (mesh, assembly, factorisation), press, observe."""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from deformap.explore import ExplorationConfig, Mapper
from deformap.world import SimulatedWorld, WorldConfig, load_scenario

__all__ = ["bench_world"]


N_PRESSES = 3
"""Presses timed (the median reported)."""


def bench_world(*, scenario: str = "heterogeneous-60-110-rigid", rng: np.random.Generator,
                config: Any = None) -> dict[str, Any]:
    """Time one world of ``scenario`` (``config``, default ``WorldConfig()``) and one poke's
    compute on :data:`N_PRESSES` of its presses with the exploration's force: ``construction_s``,
    ``press_s``, ``observe_s`` (medians, seconds), ``n_dofs``, ``n_points`` and
    ``n_points_on_area`` of one observation, ``scenario``, ``element_size_m``,
    ``press_load_by_load_s`` (the linear FEM solving each load as it comes, the baseline; None
    for another physics), ``poke_compute_s`` (the blind map, ``appearance: off``) beside
    ``poke_compute_camera_only_s`` (no record), ``poke_compute_prior_s`` (the appearance prior
    on, None when the cloud has no colour) and ``poke_compute_phases_s`` (records with a 2 s hold
    and an unloading branch, from a second world of the same scenario);
    ``initialise_s`` (the surface model alone) beside ``initialise_appearance_s`` (with the
    appearance image, its segments and the prior read from the observation's colours).
    """
    cfg = config or WorldConfig()
    sc = load_scenario(scenario)
    t0 = time.perf_counter()
    world = SimulatedWorld(sc, config=cfg, rng=rng)
    construction = time.perf_counter() - t0
    observe_times = []
    for _ in range(3):
        t0 = time.perf_counter()
        cloud = world.observe()
        observe_times.append(time.perf_counter() - t0)
    presses, press_times = _timed_presses(world)
    load_by_load = _press_load_by_load(world)
    seed = int(rng.integers(2**32))
    blind = ExplorationConfig(appearance="off")
    timed = {"poke_compute_s": _poke_compute(sc.workspace, cloud, presses, blind, seed),
             "poke_compute_camera_only_s": _poke_compute(
                 sc.workspace, cloud, [dataclasses.replace(p, force_travel=None) for p in presses],
                 dataclasses.replace(blind, field="beta"), seed),
             "poke_compute_prior_s": None if cloud.colors is None else _poke_compute(
                 sc.workspace, cloud, presses, ExplorationConfig(appearance="auto"), seed)}
    phased = SimulatedWorld(sc, config=dataclasses.replace(cfg, hold_s=2.0, unload=True),
                            rng=np.random.default_rng(seed))  # fmt: skip
    timed["poke_compute_phases_s"] = _poke_compute(sc.workspace, cloud,
                                                   _timed_presses(phased)[0], blind, seed)
    return {
        "scenario": sc.name, "element_size_m": cfg.element_size_m, "construction_s": construction,
        "press_s": float(np.median(press_times)), "press_load_by_load_s": load_by_load,
        "observe_s": float(np.median(observe_times)), "n_dofs": world.n_dofs,
        "n_points": len(cloud),
        "n_points_on_area": int(np.count_nonzero(sc.workspace.contains(cloud.xy))),
        **timed,
        "initialise_s": _initialise(sc.workspace, cloud, blind, seed),
        "initialise_appearance_s": None if cloud.colors is None else _initialise(
            sc.workspace, cloud, ExplorationConfig(appearance="auto"), seed),
    }  # fmt: skip


def _timed_presses(world: Any) -> tuple[list[Any], list[float]]:
    """The presses (along the workspace's middle, each released) and their times."""
    (x0, y0), (x1, y1) = world.workspace.lower, world.workspace.upper
    force_n = ExplorationConfig().force_n
    presses, times = [], []
    for f in np.linspace(0.2, 0.8, N_PRESSES):
        t0 = time.perf_counter()
        presses.append(world.press((x0 + f * (x1 - x0), y0 + 0.5 * (y1 - y0)), force_n))
        times.append(time.perf_counter() - t0)
        world.release()
    return presses, times


def _press_load_by_load(world: Any) -> float | None:
    """Median press with the FEM's unit responses off; None for a physics without them."""
    foam = world.foam
    if world.config.physics != "linear-fem":
        return None
    kept, foam.max_unit_columns = foam.max_unit_columns, 0
    try:
        return float(np.median(_timed_presses(world)[1]))
    finally:
        foam.max_unit_columns = kept


def _initialise(workspace: Any, cloud: Any, config: ExplorationConfig, seed: int) -> float:
    """Median of three :meth:`Mapper.initialise` on the observation under ``config``."""
    times = []
    for _ in range(3):
        mapper = Mapper(workspace, config)
        t0 = time.perf_counter()
        mapper.initialise(cloud, np.random.default_rng(seed))
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _poke_compute(workspace: Any, cloud: Any, presses: list[Any], config: ExplorationConfig,
                  seed: int) -> float:
    """Median compute of one poke (dent, β, the force–travel reading and what the press reveals,
    the map field updated) on the presses, under ``config``."""
    mapper = Mapper(workspace, config)
    mapper.initialise(cloud, np.random.default_rng(seed))
    times = []
    for index, press in enumerate(presses):
        t0 = time.perf_counter()
        mapper.add(mapper.process_press(press, index))
        times.append(time.perf_counter() - t0)
    return float(np.median(times))
