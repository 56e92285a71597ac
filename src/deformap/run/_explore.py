"""Explore a simulated scenario: poke until the map field is known, score the map against the
world's ground truth, and write the run folder: ``config.yaml`` before anything else,
``journal.jsonl`` (each poke as it completes) and ``poke-NN.png`` as the pokes come, then
``report.json``, ``map.npz``, ``pokes.csv``, ``map.png`` and with ``rerun`` ``run.rrd``. A run
killed at any moment resumes from its folder to the uninterrupted run's result.
"""

from __future__ import annotations

import contextlib
import json
import logging
import time
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from deformap import __version__
from deformap._config import config_from_dict, config_to_dict
from deformap._files import writing
from deformap._validation import check_positive
from deformap.errors import ConfigError, DeformapError, FileFormatError, FileWriteError
from deformap.explore import (
    JOURNAL_NAME,
    ExplorationConfig,
    ExplorationResult,
    Journal,
    PokeRecord,
    check_exploration_budget,
    explore,
    measure_press,
    read_journal,
)
from deformap.run._config import (
    CONFIG_NAME,
    RunConfig,
    config_yaml,
    load_run_config,
    run_generators,
)
from deformap.run._export import poke_writer, write_run_results
from deformap.run._figures import poke_figure_path, write_poke_figure, write_rerun
from deformap.run._folder import claim_run_folder, default_run_folder, run_stem, write_text
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.run._report import live_report
from deformap.world import SimulatedWorld, check_world_budget, load_scenario

__all__ = ["RunOutput", "explore_scenario"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, kw_only=True)
class RunOutput:
    """What :func:`explore_scenario` wrote (``report``: the content of ``report.json``) and the
    objects it made."""

    report: dict[str, Any]
    result: ExplorationResult
    world: SimulatedWorld
    folder: Path


def _stored_if_same(out: Path, config: RunConfig, header: dict[str, Any]) -> dict[str, Any]:
    """The journal's own header if it names this run: its configuration read back (a field added
    since at its default) equals ``config`` but for the ``robot`` guard, which the pokes do not
    depend on; else ``header`` for :meth:`Journal.resume` to compare."""
    try:
        stored = read_journal(out / JOURNAL_NAME).header
        same = (
            {k: v for k, v in stored.items() if k not in ("kind", "config")}
            == json.loads(json.dumps({k: v for k, v in header.items() if k != "config"}))
            and replace(config_from_dict(RunConfig, stored["config"], where="journal header"),
                        robot=config.robot) == config
        )
    except (DeformapError, KeyError, TypeError):
        return header
    return {k: v for k, v in stored.items() if k != "kind"} if same else header


def _has_journal(folder: Path) -> bool:
    """Whether ``folder`` holds a journal with anything in it (an empty one is a run killed as
    it created the file, as good as none)."""
    path = folder / JOURNAL_NAME
    return path.is_file() and path.stat().st_size > 0


@contextlib.contextmanager
def resume_hint_on_failure(folder: Path, again: str = "") -> Iterator[None]:
    """Add to a :class:`FileWriteError` of the block how to go on: the pokes the journal of
    ``folder`` keeps and the command that resumes it (``again``: the options to repeat)."""
    try:
        yield
    except FileWriteError as exc:
        try:
            kept = len(read_journal(folder / JOURNAL_NAME).pokes) if _has_journal(folder) else None
        except DeformapError:
            kept = None
        if kept is None:
            raise
        out = FileWriteError(f"{exc}; {kept} poke(s) kept in the journal: once that is fixed, "
                             f"continue with `deformap explore --resume {folder}`{again}")
        out.errno = exc.errno
        raise out from exc


def resume_journal(
    out: Path, config: RunConfig, header: dict[str, Any]
) -> tuple[Journal, list[PokeRecord]]:
    """The journal of the run in ``out`` and its pokes as records (a broken line refused before
    any work); a folder killed before its journal was written (none, or an empty file) starts
    over if its ``config.yaml`` is this run's."""
    if not _has_journal(out):
        if not (out / CONFIG_NAME).exists():
            raise ConfigError(f"cannot resume {str(out)!r}: it holds no {JOURNAL_NAME}")
        if load_run_config(out / CONFIG_NAME) != config:
            raise ConfigError(f"cannot resume {str(out)!r}: its config.yaml differs from this run's")
        logger.warning("%s: killed before its journal was written; starting over", out)
        if (out / JOURNAL_NAME).is_file():  # empty: created, killed before its header
            with writing(out / JOURNAL_NAME):
                (out / JOURNAL_NAME).unlink()
        return Journal.create(out, header), []
    journal, contents = Journal.resume(out, _stored_if_same(out, config, header))
    where = out / JOURNAL_NAME
    done = [PokeRecord.from_dict(r, where=f"{where} poke {k + 1}")
            for k, r in enumerate(contents.pokes)]  # fmt: skip
    for k, record in enumerate(done):  # a line copied, lost or moved would be a poke counted wrong
        if record.index != k:
            raise FileFormatError(
                f"journal {str(where)!r}: poke line {k + 1} must hold poke index {k}; got "
                f"{record.index} (a line repeated, missing or out of order)")
    if contents.broken_line is not None:
        logger.warning("%s: the last journal line was cut mid-write and is dropped (%d complete "
                       "pokes kept)", where, len(contents.pokes))
    return journal, done


def _redraw_resumed_pokes(folder: Path, result: ExplorationResult, world: SimulatedWorld,
                          config: ExplorationConfig) -> None:
    """Draw ``poke-NN.png`` of the journalled pokes that have none, pressing each again (the
    world's noise is keyed by the press, so it is the same poke); one whose β differs from its
    journal's gets a warning and no figure."""
    for poke in result.pokes:
        index = poke.record.index
        if poke.dent is not None or poke_figure_path(folder, index).exists():
            continue
        assert result.surface is not None  # explore() fits it before any poke
        obs = world.press(poke.record.target_xy, poke.record.force_n)
        world.release()
        again = measure_press(obs, index, result.surface, config)
        if again.record.beta != poke.record.beta:
            logger.warning("poke %d pressed again reads β %.4f, its journal %.4f: no figure",
                           index + 1, again.record.beta, poke.record.beta)
            continue
        write_poke_figure(folder, again)


def explore_scenario(config: RunConfig, out: Path | None = None, *, resume: bool = False,
                     figures: bool = True, rerun: bool = False, hooks: RunHooks = NO_HOOKS,
                     variance_max: float | None = None) -> RunOutput:
    """Explore ``config.scenario``, score the map against ground truth, write the run folder.

    ``out`` is new or empty (default: :func:`~deformap.run.default_run_folder` of the scenario),
    or with ``resume`` the run killed there, whose journalled pokes are not made again;
    ``figures`` draws ``map.png`` and the ``poke-NN.png``, ``rerun`` writes ``run.rrd``, and
    ``variance_max`` fixes the top of the map's variance scale. An unknown scenario, a bad ``out``
    (before any work), or on resume no run there or another configuration raise
    :class:`ConfigError`.
    """
    if variance_max is not None:  # before any work
        check_positive("variance_max", variance_max)
    if resume and out is None:
        raise ConfigError("`out` must name the run folder to resume; got None")
    scenario = load_scenario(config.scenario)
    check_exploration_budget(config.exploration, scenario.workspace)  # before any folder or work
    check_world_budget(config.world, scenario)
    folder = out or default_run_folder(run_stem(config.scenario), "explore", config.seed)
    header = {"deformap": __version__, "config": config_to_dict(config),
              "scenario": scenario.to_dict()}  # fmt: skip
    with claim_run_folder(folder, resume=resume, what="run" if resume else "output",
                          resume_hint=True), \
            resume_hint_on_failure(folder):
        if resume:
            if _has_journal(folder) and (
                    spec := read_journal(folder / JOURNAL_NAME).header.get("environment")):
                raise ConfigError(f"cannot resume {str(folder)!r} as a simulated run: it explored "
                                  f"--environment {spec}; pass that and its --env-arg values again")
            journal, done = resume_journal(folder, config, header)
            # matched the journal header; restores a copy a kill or a user removed
            write_text(folder / CONFIG_NAME, config_yaml(config))
        else:
            write_text(folder / CONFIG_NAME, config_yaml(config))
            journal, done = Journal.create(folder, header), []
        hooks.start(RunStart(kind="explore", title=f"{config.scenario} seed {config.seed}",
                             folder=folder, total=config.exploration.max_pokes,
                             done=len(done)))  # fmt: skip
        hooks.stage("building the world")
        world_rng, explore_rng = run_generators(config.seed)
        t0 = time.perf_counter()
        world = SimulatedWorld(scenario, config=config.world, rng=world_rng)
        world_s = time.perf_counter() - t0
        hooks.stage("exploring")
        result = explore(world, config.exploration, rng=explore_rng, journal=journal, done=done,
                         on_poke=poke_writer(folder, figures=figures, hooks=hooks))
        report = live_report(config, result, world, world_build_s=world_s)
        write_run_results(folder, result, report, figures=figures, truth=world,
                          poke_figures=False, hooks=hooks, variance_max=variance_max,
                          title=f"{config.scenario} (seed {config.seed}): "
                                f"{len(result.pokes)} pokes")  # fmt: skip
        if figures:
            _redraw_resumed_pokes(folder, result, world, config.exploration)
        if rerun:
            hooks.stage("writing run.rrd")
            write_rerun(folder / "run.rrd", result, truth=world)
    return RunOutput(report=report, result=result, world=world, folder=folder)
