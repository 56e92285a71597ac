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
    for another physics), ``poke_compute_s`` and ``poke_compute_camera_only_s`` (its baseline).
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
    with_record, camera_only = _poke_compute(sc.workspace, cloud, presses, rng)
    return {
        "scenario": sc.name, "element_size_m": cfg.element_size_m, "construction_s": construction,
        "press_s": float(np.median(press_times)), "press_load_by_load_s": load_by_load,
        "observe_s": float(np.median(observe_times)), "n_dofs": world.n_dofs,
        "n_points": len(cloud),
        "n_points_on_area": int(np.count_nonzero(sc.workspace.contains(cloud.xy))),
        "poke_compute_s": with_record, "poke_compute_camera_only_s": camera_only,
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


def _poke_compute(workspace: Any, cloud: Any, presses: list[Any], rng: np.random.Generator
                  ) -> tuple[float, float]:
    """Median compute of one poke (dent, β, the force–travel reading, the map field updated) on
    the presses, with their records and, the baseline, without them (mapped on the β-field)."""
    medians = []
    for keep_record in (True, False):
        # without records the map is on β (no fallback warning in a benchmark's output)
        mapper = Mapper(workspace, ExplorationConfig(field="modulus" if keep_record else "beta"))
        mapper.initialise(cloud, np.random.default_rng(rng.integers(2**32)))
        times = []
        for index, obs in enumerate(presses):
            press = obs if keep_record else dataclasses.replace(obs, force_travel=None)
            t0 = time.perf_counter()
            mapper.add(mapper.process_press(press, index))
            times.append(time.perf_counter() - t0)
        medians.append(float(np.median(times)))
    return medians[0], medians[1]
