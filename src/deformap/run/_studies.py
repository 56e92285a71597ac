"""The studies on homogeneous simulated foams (the paper's Fig. 5), each into its own folder:
``hardness.json`` and ``hardness.png`` (β against hardness per contact protocol), or
``cluster-size.json`` and ``cluster-size.png`` (fit error against cluster size).

The numbers come from :mod:`deformap.eval`; this module builds the worlds, writes the files and
reports progress.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from deformap.eval import (
    DEFAULT_HARDNESSES,
    FoamPresses,
    cluster_size_study,
    collect_presses,
    hardness_study,
)
from deformap.explore import ExplorationConfig
from deformap.run._folder import create_run_folder, default_run_folder, write_json
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.world import Physics, WorldConfig, camera_preset

__all__ = ["CLUSTER_SIZE_FOAMS", "StudyOutput", "run_cluster_size_study", "run_hardness_study"]

CLUSTER_SIZE_FOAMS: tuple[float, ...] = (60.0, 110.0, 150.0)
"""Foams of the cluster-size study in newtons (the rigid board is added)."""


@dataclass(frozen=True, kw_only=True)
class StudyOutput:
    """What a study wrote: ``study`` (the content of its JSON file), ``folder`` and ``files``."""

    study: dict[str, Any]
    folder: Path
    files: list[Path]


def _foams(
    name: str, foams: Sequence[float | None], folder: Path, *, seed: int, coarse: bool,
    hooks: RunHooks, camera: str | None = None, thickness_m: float = 0.05,
    force_n: float | None = None, physics: Physics = "linear-fem",
) -> list[FoamPresses]:  # fmt: skip
    hooks.start(RunStart(kind="study", title=f"{name}, seed {seed}", folder=folder,
                         total=len(foams)))  # fmt: skip
    hooks.stage("pressing the foams")
    world = WorldConfig.coarse(physics=physics) if coarse else WorldConfig(physics=physics)
    if camera is not None:
        world = dataclasses.replace(world, camera=camera_preset(camera))
    explore = ExplorationConfig() if force_n is None else ExplorationConfig(force_n=force_n)
    return collect_presses(foams, world_config=world, config=explore, thickness_m=thickness_m,
                           rng=np.random.default_rng(seed), progress=hooks.step)  # fmt: skip


def _write(folder: Path, stem: str, study: dict[str, Any], plot: Any) -> list[Path]:
    json_file = write_json(folder / f"{stem}.json", study)
    plot(study, path=folder / f"{stem}.png")  # written atomically by viz
    return [json_file, folder / f"{stem}.png"]


def run_hardness_study(
    out: Path | None = None,
    *,
    seed: int = 0,
    hardness: Sequence[float] | None = None,
    coarse: bool = False,
    camera: str | None = None,
    thickness_m: float = 0.05,
    force_n: float | None = None,
    physics: str = "linear-fem",
    hooks: RunHooks = NO_HOOKS,
) -> StudyOutput:
    """β (each contact protocol) and the force–travel reading (stiffness, Young's modulus)
    against hardness (:func:`deformap.eval.hardness_study`).

    Parameters
    ----------
    out : Path, optional
        A new or empty folder (default: :func:`~deformap.run.default_run_folder`, stem
        ``hardness``, kind ``study``).
    seed : int
        Seed of the worlds' noise.
    hardness : sequence of float, optional
        Foams in newtons (the rigid board is added); default
        :data:`~deformap.eval.DEFAULT_HARDNESSES`.
    coarse : bool
        The coarse FEM mesh (a quick look).
    camera : str, optional
        A :data:`deformap.world.CAMERA_PRESETS` name (default: the world's own camera).
    thickness_m : float
        The foam blocks' thickness.
    force_n : float, optional
        The press force (default: the exploration's).
    physics : str
        The world's contact physics, a :data:`deformap.world.PHYSICS` name (``WorldConfig.physics``).
    hooks : RunHooks
    """
    from deformap.viz import plot_hardness_study  # matplotlib: only when a study is drawn

    folder = create_run_folder(out or default_run_folder("hardness", "study", seed), what="study")
    foams = DEFAULT_HARDNESSES if not hardness else (*hardness, None)
    if camera is not None:
        camera_preset(camera)  # an unknown name fails here, before any world is built
    # so does an unknown physics (one line naming `physics`)
    checked = WorldConfig(physics=physics).physics  # type: ignore[arg-type]
    presses = _foams("hardness study", foams, folder, seed=seed, coarse=coarse, hooks=hooks,
                     camera=camera, thickness_m=thickness_m, force_n=force_n, physics=checked)
    hooks.stage("estimating β per protocol")
    conditions = {"camera": camera or "primesense", "thickness_m": thickness_m,
                  "force_n": presses[0].presses[0].force_n if presses else force_n,
                  "physics": physics}
    study = {**conditions, **hardness_study(presses)}
    study["rows"] = [{**row, **conditions} for row in study["rows"]]
    return StudyOutput(study=study, folder=folder,
                       files=_write(folder, "hardness", study, plot_hardness_study))  # fmt: skip


def run_cluster_size_study(
    out: Path | None = None,
    *,
    seed: int = 0,
    coarse: bool = False,
    hooks: RunHooks = NO_HOOKS,
) -> StudyOutput:
    """Fit error and β against cluster size 2×2 … 6×6 (:func:`deformap.eval.cluster_size_study`)
    on the foams :data:`CLUSTER_SIZE_FOAMS` and the rigid board.

    Parameters are those of :func:`run_hardness_study` (default stem ``cluster-size``).
    """
    from deformap.viz import plot_cluster_size_study  # matplotlib: only when a study is drawn

    folder = create_run_folder(out or default_run_folder("cluster-size", "study", seed),
                               what="study")  # fmt: skip
    foams = (*CLUSTER_SIZE_FOAMS, None)
    presses = _foams("cluster-size study", foams, folder, seed=seed, coarse=coarse, hooks=hooks)
    hooks.stage("estimating β per cluster size")
    study = cluster_size_study(presses)
    return StudyOutput(study=study, folder=folder,
                       files=_write(folder, "cluster-size", study, plot_cluster_size_study))  # fmt: skip
