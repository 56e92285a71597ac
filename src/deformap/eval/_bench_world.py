"""Speed of the simulated world: construction (mesh, assembly, factorisation), press, observe."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from deformap.explore import ExplorationConfig

__all__ = ["bench_world"]


def bench_world(*, scenario: str = "heterogeneous-60-110-rigid", rng: np.random.Generator,
                config: Any = None, n_presses: int = 3,
                force_n: float = ExplorationConfig().force_n) -> dict[str, Any]:
    """Time one world at its default mesh (goals: build ≤ 20 s, press ≤ 1 s, observe ≤ 0.5 s).

    Parameters
    ----------
    scenario : str
        Built-in name or YAML path.
    rng : numpy.random.Generator
    config : WorldConfig, optional
        Defaults to ``WorldConfig()`` (the default mesh).
    n_presses : int
        Presses timed (median reported) at points spread over the workspace.
    force_n : float
        Their force (default: the exploration's).

    Returns
    -------
    dict with ``construction_s``, ``press_s``, ``observe_s`` (medians, seconds), ``n_dofs``,
    ``n_points`` and ``n_points_on_area`` of one observation, ``scenario``, ``element_size_m``.
    """
    from deformap.world import SimulatedWorld, WorldConfig, load_scenario

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
    (x0, y0), (x1, y1) = sc.workspace.lower, sc.workspace.upper
    press_times = []
    for f in np.linspace(0.2, 0.8, n_presses):
        t0 = time.perf_counter()
        world.press((x0 + f * (x1 - x0), y0 + 0.5 * (y1 - y0)), force_n)
        press_times.append(time.perf_counter() - t0)
        world.release()
    return {
        "scenario": sc.name,
        "element_size_m": cfg.element_size_m,
        "construction_s": construction,
        "press_s": float(np.median(press_times)),
        "observe_s": float(np.median(observe_times)),
        "n_dofs": world.n_dofs,
        "n_points": len(cloud),
        "n_points_on_area": int(np.count_nonzero(sc.workspace.contains(cloud.xy))),
    }
