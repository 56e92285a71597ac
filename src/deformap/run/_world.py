"""A look at the simulated world: the built-in scenarios in one table, and the pictures of one
scenario (its layout, a camera cloud, a pressed dent).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from deformap.explore import ExplorationConfig
from deformap.run._folder import claim_run_folder
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.world import SimulatedWorld, WorldConfig, list_scenarios, load_scenario

__all__ = ["ScenarioSummary", "scenario_summaries", "show_scenario"]


@dataclass(frozen=True, kw_only=True)
class ScenarioSummary:
    """One built-in scenario: its ``name``, its ``regions`` (``"60 N"``, ``"rigid"``, ...) in
    block order, and its ``description``."""

    name: str
    regions: tuple[str, ...]
    description: str


def scenario_summaries() -> list[ScenarioSummary]:
    """Every built-in scenario, in :func:`deformap.world.list_scenarios` order."""
    out = []
    for name in list_scenarios():
        sc = load_scenario(name)
        regions = tuple("rigid" if b.rigid else f"{b.hardness:.0f} N" for b in sc.blocks)
        out.append(ScenarioSummary(name=name, regions=regions, description=sc.description))
    return out


def show_scenario(name: str, out: Path, *, seed: int = 0, coarse: bool = False,
                  force_n: float = ExplorationConfig().force_n, hooks: RunHooks = NO_HOOKS,
                  ) -> list[Path]:
    """Write ``layout.png``, ``rgb.png``, ``cloud.png`` and ``dent.png`` of scenario ``name`` (a
    built-in name or YAML file) into ``out``, a new or empty folder, and return their paths.

    ``seed`` seeds the camera and sensor noise, ``coarse`` takes the coarse test mesh, ``force_n``
    is the press of ``dent.png`` (default: the exploration's).
    """
    from deformap.viz import show_world  # matplotlib: only when pictures are drawn

    scenario = load_scenario(name)
    with claim_run_folder(out, what="picture"):
        hooks.start(RunStart(kind="world", title=f"{name} seed {seed}", folder=out))
        hooks.stage("building the world")
        config = WorldConfig.coarse() if coarse else WorldConfig()
        world = SimulatedWorld(scenario, config=config, rng=np.random.default_rng(seed))
        hooks.stage("drawing")
        return show_world(world, out, force_n=force_n)
