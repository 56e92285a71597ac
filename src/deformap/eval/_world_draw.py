"""A benchmark world: drawn from ``(seed, index)`` alone, its ground truth, and the task that maps it.

A benchmark world (:func:`draw_world`) takes the ``index``-th of the layout families asked for, in
turn (so any run of ``n`` worlds spans them evenly), and draws the rest from
``numpy.random.SeedSequence([seed, index])``: the layout and its materials
(:func:`deformap.world.random_scenario`, hardness over :data:`HARDNESS_RANGE_N`, one material
rigid with probability :data:`P_RIGID`), the world's physics (any of
:data:`deformap.world.PHYSICS`), camera (every preset of :data:`deformap.world.CAMERA_PRESETS`),
block thickness (:data:`THICKNESSES_M`) and press force (:data:`FORCES_N`). The appearance family
(:data:`deformap.world.APPEARANCE_FAMILIES`) paints the layout from a generator of its own, so
every family paints the same layout, materials and axes of a world index.

A task maps each of its appearance families under one or two *arms* (:meth:`WorldTask.arms`): a
painted family twice, paired on the same world, presses and streams, with the appearance prior
off (the blind map) and on (``auto``); ``plain``, one look everywhere, once under ``auto``, so a
benchmark of plain worlds maps each world once per combination.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, cast, get_args, get_type_hints

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_settings, setting
from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig
from deformap.world import (
    APPEARANCE_FAMILIES,
    CAMERA_PRESETS,
    LAYOUT_FAMILIES,
    PHYSICS,
    Physics,
    Scenario,
    random_scenario,
)

__all__ = [
    "FORCES_N",
    "HARDNESS_RANGE_N",
    "PRIORS",
    "P_RIGID",
    "THICKNESSES_M",
    "WorldDraw",
    "WorldTask",
    "choices",
    "draw_world",
    "material_truth",
]

#: Hardness of the benchmark's foams [N]: super soft to firm, the hardness study's range.
HARDNESS_RANGE_N = (30.0, 250.0)
#: Block thicknesses [m]: the hardness study's matrix (``study hardness --full``).
THICKNESSES_M = (0.03, 0.05, 0.10)
#: Press forces [N]: the exploration's 0.6 N and a third below and above it, which still dent the
#: firmest foam beyond the camera's noise and never bottom out the softest.
FORCES_N = (0.4, 0.6, 0.8)
#: Probability that one material of a benchmark world is a rigid board (the generator's default).
P_RIGID = 0.25
#: ``ExplorationConfig.appearance`` of the two arms of a painted world: the blind map, the prior.
PRIORS = ("off", "auto")


def choices(name: str) -> tuple[str, ...]:
    """The values ``ExplorationConfig.<name>`` accepts (its ``Literal``): ``strategy``,
    ``field`` or ``region_labels``; new names added there are accepted here unchanged."""
    return tuple(get_args(get_type_hints(ExplorationConfig)[name]))


@dataclass(frozen=True, kw_only=True)
class WorldDraw:
    """One benchmark world: its layout and the axes it is measured under."""

    index: int
    family: str
    appearance: str
    physics: Physics
    camera: str
    thickness_m: float
    force_n: float
    scenario: Scenario

    def summary(self) -> dict[str, Any]:
        """Plain data naming the world (its blocks' hardness and whether any is rigid)."""
        return {"index": self.index, "family": self.family, "physics": self.physics,
                "camera": self.camera, "thickness_m": self.thickness_m, "force_n": self.force_n,
                "blocks": len(self.scenario.blocks),
                "hardness_n": sorted({b.hardness for b in self.scenario.blocks
                                      if not b.rigid}),
                "rigid": any(b.rigid for b in self.scenario.blocks)}  # fmt: skip


def draw_world(seed: int, index: int, families: Sequence[str] = LAYOUT_FAMILIES,
               physics: Sequence[str] = PHYSICS, appearance: str = "plain") -> WorldDraw:
    """The ``index``-th world of a benchmark seeded ``seed`` (module docstring); ``physics``
    the world physics to draw from (all by default), ``appearance`` the family that paints it.

    Raises
    ------
    InvalidArgumentError
        No family, an unknown physics or an unknown appearance family.
    """
    if not families:
        raise InvalidArgumentError("`families` must name at least one layout family; got none")
    if not physics or any(p not in PHYSICS for p in physics):
        raise InvalidArgumentError(f"`physics` must be names from {list(PHYSICS)}; got "
                                   f"{list(physics)}")
    rng = np.random.default_rng(np.random.SeedSequence([seed, index]))
    family = families[index % len(families)]
    drawn = cast(Physics, str(rng.choice(list(physics))))
    camera = str(rng.choice(sorted(CAMERA_PRESETS)))
    thickness = float(rng.choice(THICKNESSES_M))
    force = float(rng.choice(FORCES_N))
    scenario = random_scenario(rng, family=family, hardness_range_n=HARDNESS_RANGE_N,
                               p_rigid=P_RIGID, thickness_m=thickness,
                               appearance=appearance)  # fmt: skip
    return WorldDraw(index=index, family=family, appearance=appearance, physics=drawn,
                     camera=camera, thickness_m=thickness, force_n=force, scenario=scenario)


def material_truth(scenario: Scenario, xs: NDArray[np.float64], ys: NDArray[np.float64]
                   ) -> tuple[NDArray[np.int64], dict[int, float], NDArray[np.float64]]:
    """The world's ground truth on the grid ``xs`` × ``ys``, read from its layout (no FEM).

    Returns
    -------
    labels : (ny, nx) int
        One label per material (blocks of one hardness are one region).
    hardness : dict
        Each label's hardness [N].
    modulus : (ny, nx) float
        Young's modulus [Pa]; not finite on a rigid board.
    """
    hardness = scenario.per_block(xs, ys, [b.hardness for b in scenario.blocks])
    values, labels = np.unique(hardness, return_inverse=True)
    return (labels.reshape(hardness.shape).astype(np.int64),
            {k: float(v) for k, v in enumerate(values)},
            scenario.per_block(xs, ys, [b.modulus_pa for b in scenario.blocks]))


@dataclass(frozen=True, kw_only=True)
class WorldTask:
    """What one benchmark world is mapped with (:func:`deformap.eval.run_world`).

    Parameters
    ----------
    seed, index : int
        The world is the ``index``-th of the benchmark seeded ``seed`` (:func:`draw_world`).
    families, physics : tuple of str
        The layout families taken in turn and the world physics drawn from.
    appearances : tuple of str
        The appearance families the world is painted in, each mapped under its :meth:`arms`.
    strategies, fields : tuple of str
        ``ExplorationConfig.strategy`` and ``field`` values; every pair maps the world.
    cuts : tuple of str
        ``ExplorationConfig.region_labels`` values, each scored on the same pokes.
    max_pokes : int
        Pokes per combination.
    coarse : bool
        The test mesh and camera (:meth:`deformap.world.WorldConfig.coarse`) instead of the
        default world.
    exploration : ExplorationConfig
        Every other exploration setting; its strategy, field, cut, poke counts and force are the
        task's (:meth:`exploration_for`).
    """

    seed: int = setting(0, ge=0)
    index: int = setting(0, ge=0)
    families: tuple[str, ...] = LAYOUT_FAMILIES
    physics: tuple[str, ...] = PHYSICS
    # one look everywhere: a benchmark that names no appearance maps each world once
    appearances: tuple[str, ...] = ("plain",)
    strategies: tuple[str, ...] = choices("strategy")
    fields: tuple[str, ...] = choices("field")
    cuts: tuple[str, ...] = choices("region_labels")
    max_pokes: int = setting(12, ge=1, le=1000)
    coarse: bool = False
    exploration: ExplorationConfig = field(default_factory=ExplorationConfig)

    def __post_init__(self) -> None:
        check_settings(self)
        unknown = [a for a in self.appearances if a not in APPEARANCE_FAMILIES]
        if not self.appearances or unknown or len(set(self.appearances)) < len(self.appearances):
            raise InvalidArgumentError(f"`appearances` must be distinct names from "
                                       f"{list(APPEARANCE_FAMILIES)}; got "
                                       f"{list(self.appearances)}")

    def draw(self, appearance: str = "plain") -> WorldDraw:
        """The world this task maps, painted by ``appearance`` (:func:`draw_world`)."""
        return draw_world(self.seed, self.index, self.families, self.physics, appearance)

    def arms(self) -> tuple[tuple[str, str], ...]:
        """``(appearance family, ExplorationConfig.appearance)`` of every mapping of the world,
        in order: a painted family under each of :data:`PRIORS` (blind first), ``plain`` under
        ``auto`` only (module docstring)."""
        return tuple((a, p) for a in self.appearances
                     for p in (PRIORS if a != "plain" else PRIORS[1:]))

    def exploration_for(self, draw: WorldDraw) -> ExplorationConfig:
        """The exploration settings of ``draw``: every poke up to ``max_pokes`` made (the ones
        after the variance rule is met go to the least certain boundary, so every combination
        makes as many), pressed with the world's force."""
        k = self.max_pokes
        return replace(self.exploration, max_pokes=k, boundary_pokes=k, force_n=draw.force_n)
