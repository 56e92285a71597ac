"""One experiment on the simulated world: explore, score against ground truth, write the run folder.

``runs/<name>/`` receives ``config.yaml`` (the effective configuration), ``journal.jsonl`` (each poke
as it completes, for ``--resume``), ``report.json``, ``map.png`` and one ``poke-NN.png`` per poke.
"""

from __future__ import annotations

import json
import logging
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from deformap import __version__
from deformap._config import config_from_dict, config_to_dict, dump_yaml, load_yaml
from deformap._validation import check_int, check_settings, setting
from deformap.errors import ConfigError, DeformapError
from deformap.eval._metrics import region_scores
from deformap.explore import (
    ExplorationConfig,
    ExplorationResult,
    Journal,
    PokeResult,
    explore,
    read_journal,
)
from deformap.explore._journal import JOURNAL_NAME, replace_durably
from deformap.world import SimulatedWorld, WorldConfig, load_scenario

__all__ = [
    "RunConfig",
    "build_report",
    "load_run_config",
    "map_report",
    "run_experiment",
    "run_generators",
    "write_figures",
    "write_map_figures",
]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """The whole configuration of a run: which world, which seed, and every component's settings."""

    scenario: str = "heterogeneous-60-110-rigid"
    seed: int = setting(0, ge=0)
    world: WorldConfig = field(default_factory=WorldConfig)
    exploration: ExplorationConfig = field(default_factory=ExplorationConfig)

    def __post_init__(self) -> None:
        check_settings(self)


def load_run_config(path: str | Path | None) -> RunConfig:
    """Read a run configuration from YAML (missing keys keep their defaults)."""
    if path is None:
        return RunConfig()
    return config_from_dict(RunConfig, load_yaml(path), where=Path(path).name)


def _json_default(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value)}")


def _finite(value: float) -> float | None:
    return None if value is None or not math.isfinite(value) else float(value)


@dataclass
class RunOutput:
    """What :func:`run_experiment` returns: the report written and the live objects."""

    report: dict[str, Any]
    result: ExplorationResult
    world: SimulatedWorld
    folder: Path


def _write_whole(path: Path, text: str) -> None:
    """Write ``text`` through a temporary file: a kill leaves the old file or the new, not half."""
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    replace_durably(tmp, path)


def _stored_if_same(out: Path, config: RunConfig, header: dict[str, Any]) -> dict[str, Any]:
    """The journal's own header if it names this run in an older form, else ``header``.

    A configuration field added since the run began is missing from its journal header; read
    with that field at its default (new fields default to the behaviour before them), the stored
    configuration may equal this run's, which then resumes. Anything else is left for
    :meth:`Journal.resume` to compare (and refuse, naming what differs).
    """
    try:
        stored = read_journal(out / JOURNAL_NAME).header
        same = (
            {k: v for k, v in stored.items() if k not in ("kind", "config")}
            == json.loads(json.dumps({k: v for k, v in header.items() if k != "config"}))
            and config_from_dict(RunConfig, stored["config"], where="journal header") == config
        )
    except (DeformapError, KeyError, TypeError):
        return header
    return {k: v for k, v in stored.items() if k != "kind"} if same else header


def _prepare_folder(
    out: Path, config: RunConfig, header: dict[str, Any], resume: bool
) -> tuple[Journal, list]:
    """Check the run folder and open its journal; ``config.yaml`` is always written first.

    So a run killed at any moment leaves ``config.yaml`` beside any journal, and a folder with
    ``config.yaml`` but no journal (killed before its journal was created) resumes from poke 1.
    """
    config_file = out / "config.yaml"
    if resume:
        if not (out / JOURNAL_NAME).exists():
            if not config_file.exists():
                raise ConfigError(f"cannot resume {str(out)!r}: it holds no {JOURNAL_NAME}")
            if load_run_config(config_file) != config:
                raise ConfigError(
                    f"cannot resume {str(out)!r}: its config.yaml differs from this run's"
                )
            logger.warning("%s: killed before its journal was created; starting over", out)
            return Journal.create(out, header), []
        journal, contents = Journal.resume(out, _stored_if_same(out, config, header))
        if contents.broken_line is not None:
            logger.warning(
                "%s: the last journal line was cut mid-write and is dropped (%d complete pokes kept)",
                out / JOURNAL_NAME,
                len(contents.pokes),
            )
        return journal, contents.pokes
    if out.exists() and any(out.iterdir()):
        raise ConfigError(
            f"output folder {str(out)!r} already holds a run; choose another --out or pass --resume"
        )
    out.mkdir(parents=True, exist_ok=True)
    _write_whole(config_file, dump_yaml(config))
    return Journal.create(out, header), []


def run_generators(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """The world's and the exploration's generators of a run with ``seed``.

    ``deformap record-sim`` and ``deformap map`` derive theirs the same way, so that a recorded
    session mapped offline with its seed fits the surface exactly as the live run did.
    """
    world_seq, explore_seq = np.random.SeedSequence(check_int("seed", seed, minimum=0)).spawn(2)
    return np.random.default_rng(world_seq), np.random.default_rng(explore_seq)


def run_experiment(
    config: RunConfig,
    out: str | Path,
    *,
    resume: bool = False,
    figures: bool = True,
    rerun: bool = False,
    on_poke: Callable[[PokeResult], None] | None = None,
) -> RunOutput:
    """Explore the configured scenario, score the map against ground truth, write the folder."""
    folder = Path(out)
    scenario = load_scenario(config.scenario)
    plain = config_to_dict(config)
    header = {"deformap": __version__, "config": plain, "scenario": scenario.to_dict()}
    journal, done = _prepare_folder(folder, config, header, resume)
    if resume:  # matched the journal header; restores a copy a kill or a user removed
        _write_whole(folder / "config.yaml", dump_yaml(config))
    world_rng, explore_rng = run_generators(config.seed)
    t0 = time.perf_counter()
    world = SimulatedWorld(scenario, config=config.world, rng=world_rng)
    world_s = time.perf_counter() - t0
    result = explore(
        world,
        config.exploration,
        rng=explore_rng,
        journal=journal,
        done=done,
        on_poke=on_poke,
    )
    report = build_report(config, result, world, world_build_s=world_s)
    (folder / "report.json").write_text(json.dumps(report, indent=2, default=_json_default))
    if figures:
        write_figures(folder, result, world, config)
    if rerun:
        from deformap.viz import record_run

        assert result.surface is not None
        record_run(folder / "run.rrd", result, initial_points=result.surface.points)
    return RunOutput(report=report, result=result, world=world, folder=folder)


def map_report(result: ExplorationResult, *, truth: Any = None) -> dict[str, Any]:
    """The part of ``report.json`` that a live run and a replayed session share.

    Parameters
    ----------
    result : ExplorationResult
    truth : object with ``ground_truth_labels(xs, ys)`` and ``ground_truth_hardness(xs, ys)``
        A :class:`~deformap.world.SimulatedWorld` or a session's
        :class:`~deformap.replay.GroundTruth`; ``None`` leaves the ground-truth metrics out.
    """
    beta, var = result.field.mean, result.field.variance
    xs, ys = result.xs, result.ys
    pokes = [p.record.to_dict() for p in result.pokes]
    per_poke_compute = [p.record.timings.compute_s for p in result.pokes]
    regions: dict[str, Any] | None = None
    true_regions = None
    found = result.regions
    if found is not None:
        # under region_labels "nearest" the cells take their nearest poke's class, and the
        # levels only separate the classes' βs
        regions = {"levels": found.levels.tolist(), "class_betas": found.class_betas.tolist(),
                   "poke_labels": found.poke_labels.tolist(),
                   "labels_by": result.config.region_labels}
        if truth is not None:
            labels = truth.ground_truth_labels(xs, ys)
            hardness_grid = truth.ground_truth_hardness(xs, ys)
            hardness = {
                int(label): float(hardness_grid[labels == label][0]) for label in np.unique(labels)
            }
            scores = region_scores(found.labels, labels, beta, hardness)
            regions = {**scores.to_dict(), **regions}
            true_regions = [
                {"label": label, "hardness_n": _finite(h)} for label, h in sorted(hardness.items())
            ]
    report: dict[str, Any] = {
        "pokes": pokes,
        "n_pokes": len(pokes),
        "stop_reason": result.stop_reason,
        # what the stopping rule compared with T_h (over ``stop_region``), and over the whole map
        "max_variance": result.max_variance,
        "max_variance_map": float(var.max()),
        "regions": regions,
    }
    if truth is not None:
        report["true_regions"] = true_regions
    report["timings"] = {
        **result.timings,
        "per_poke_s": [
            p["timings"].get("environment_s", 0.0) + c
            for p, c in zip(pokes, per_poke_compute, strict=True)
        ],
        "per_poke_compute_s": per_poke_compute,
    }
    return report


def build_report(
    config: RunConfig, result: ExplorationResult, world: SimulatedWorld, *, world_build_s: float
) -> dict[str, Any]:
    """The ``report.json`` content (see DESIGN.md, "What done looks like")."""
    report = {
        "deformap": __version__,
        "scenario": config.scenario,
        "seed": config.seed,
        "config": config_to_dict(config),
        **map_report(result, truth=world),
    }
    report["timings"]["world_build_s"] = world_build_s
    return report


def write_figures(
    folder: Path, result: ExplorationResult, world: SimulatedWorld, config: RunConfig
) -> None:
    """``map.png`` and one ``poke-NN.png`` per poke processed in this session."""
    write_map_figures(
        folder,
        result,
        truth=world,
        threshold=config.exploration.threshold,
        title=f"{config.scenario} (seed {config.seed}): {len(result.pokes)} pokes",
    )


def write_map_figures(
    folder: Path,
    result: ExplorationResult,
    *,
    truth: Any = None,
    threshold: float | None = None,
    title: str = "",
) -> None:
    """``map.png`` (when there is a poke) and one ``poke-NN.png`` per poke processed here.

    ``truth`` is as in :func:`map_report`; without it the map has no ground-truth panel.
    """
    from deformap.viz import plot_map, plot_poke

    if result.regions is not None:
        regions = result.regions
        contacts = np.array([p.xy for p in result.pokes])
        plot_map(
            result.xs,
            result.ys,
            beta=result.field.mean,
            variance=result.field.variance,
            contacts=contacts,
            labels=regions.labels,
            levels=regions.levels if result.config.region_labels == "isopleth" else None,
            truth_hardness=None
            if truth is None
            else truth.ground_truth_hardness(result.xs, result.ys),
            threshold=threshold,
            title=title,
            path=folder / "map.png",
        )
    for poke in result.pokes:
        dent, r = poke.dent, poke.record
        if dent is None:  # resumed from the journal: no arrays to draw
            continue
        plot_poke(
            roi_xs=dent.roi_xs,
            roi_ys=dent.roi_ys,
            rest_z=dent.rest_z,
            deformed_z=dent.deformed_z,
            roi_points=dent.roi_points,
            tactile=dent.tactile,
            betas=np.asarray(r.betas),
            errors=np.asarray(r.errors),
            beta=r.beta,
            beta_std=r.beta_std,
            title=f"poke {r.index + 1} at ({r.contact_xy[0]:.3f}, {r.contact_xy[1]:.3f}) m",
            path=folder / f"poke-{r.index + 1:02d}.png",
        )
