"""``deformap bench worlds``: many seeded random worlds, each mapped with every strategy × field,
on a local process pool or a Dask cluster, resumable; ``deformap bench rescore``: a benchmark's
stored pokes scored again under other cuts or region rules.

Run again on the same folder with the same settings, :func:`bench_worlds` reads the finished
worlds and computes only the others (a world that failed is tried again). The folder's files are
:mod:`deformap.run._worlds_folder`'s; the engines :mod:`deformap.run._worlds_engines`'s.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from deformap.errors import ConfigError, InvalidArgumentError
from deformap.eval import WorldResult, choices, rescore_world
from deformap.run._folder import claim_run_folder, default_run_folder, to_json, write_text
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.run._worlds_config import WorldsBenchConfig, exploration_changes, exploration_with
from deformap.run._worlds_engines import check_scheduler, world_results
from deformap.run._worlds_folder import (
    SETTINGS_NAME,
    finished_worlds,
    read_bench,
    read_world,
    start_folder,
    world_path,
    write_bench,
    write_summary,
)

__all__ = ["RESCORABLE", "WorldsOutput", "bench_worlds", "load_worlds", "rescore_worlds"]

#: The exploration settings a rescore may change: those that act after the pokes, on the
#: regions, so that scoring the stored pokes again is what a run under them would score.
RESCORABLE = ("merge_seams", "split_by_place")


@dataclass(frozen=True, kw_only=True)
class WorldsOutput:
    """What :func:`bench_worlds` wrote: ``summary`` (``summary.json``'s content), ``folder``,
    ``files`` and the worlds ``computed`` by this call (the others were read back)."""

    summary: dict[str, Any]
    folder: Path
    files: list[Path]
    computed: int
    seconds: float


def bench_worlds(config: WorldsBenchConfig, out: Path | None = None, *,
                 hooks: RunHooks = NO_HOOKS) -> WorldsOutput:
    """Run (or resume) the worlds benchmark ``config`` into ``out`` (module docstring).

    Parameters
    ----------
    config : WorldsBenchConfig
    out : Path, optional
        The folder: new, empty, or this benchmark's own to resume (default:
        ``runs/worlds-bench-s<seed>-<time>``).
    hooks : RunHooks
        ``on_start`` once; ``on_step`` per world with worlds done, worlds per hour and the
        estimate of time left.

    Raises
    ------
    ConfigError
        ``out`` holds something else, or a benchmark of another format or with other settings;
        the scheduler cannot be reached or dask is not installed.
    """
    if not isinstance(config, WorldsBenchConfig):
        raise ConfigError(f"`config` must be a WorldsBenchConfig; got {type(config).__name__}")
    if config.scheduler is not None:
        check_scheduler(config.scheduler)  # before the folder: nothing left by a wrong address
    folder = out or default_run_folder("worlds", "bench", config.seed)
    with claim_run_folder(folder, resume=(folder / SETTINGS_NAME).is_file(),
                          what="benchmark"):
        start_folder(config, folder)
        done = finished_worlds(folder, config.worlds)
        results = dict(done)
        engine = (f"Dask at {config.scheduler}" if config.scheduler
                  else f"{config.workers} local process{'es' if config.workers > 1 else ''}")
        hooks.start(RunStart(kind="bench worlds", folder=folder, total=config.worlds, done=len(done),
                             title=f"{config.worlds} worlds, seed {config.seed}, {engine}"))
        tasks = [config.task(i) for i in range(config.worlds) if i not in done]
        t0 = time.perf_counter()
        stream = world_results(tasks, workers=config.workers, scheduler=config.scheduler)
        computed = 0
        summary, files = write_summary(folder, config, list(results.values())) if done else ({}, [])
        for result in stream:
            write_text(world_path(folder, result.index), to_json(result.to_dict()))
            results[result.index] = result
            computed += 1
            summary, files = write_summary(folder, config, list(results.values()))
            elapsed = time.perf_counter() - t0
            rate = computed / elapsed * 3600.0
            left = (len(tasks) - computed) / rate * 3600.0 if rate > 0 else float("nan")
            what = (f"{result.seconds:.0f} s" if result.status == "ok"
                    else f"FAILED: {result.error}")
            hooks.step(f"world {result.index} ({result.world['family']}): {what} · "
                       f"{len(results)}/{config.worlds} done · {rate:.1f} worlds/h · "
                       f"{left / 60:.0f} min left")
        if not tasks and not files:
            summary, files = write_summary(folder, config, list(results.values()))
        return WorldsOutput(summary=summary, folder=folder, files=[folder / SETTINGS_NAME, *files],
                            computed=computed, seconds=time.perf_counter() - t0)


def load_worlds(folder: Path) -> tuple[WorldsBenchConfig, list[WorldResult]]:
    """The benchmark in ``folder`` and every world stored there (finished or failed), by index;
    ``worlds`` of the config counts up to the last one.

    Raises
    ------
    ConfigError
        ``folder`` holds no benchmark of this format, or a world file that cannot be read (the
        file and what is wrong are named).
    """
    config = read_bench(Path(folder))
    results = [read_world(p) for p in sorted(Path(folder, "worlds").glob("world-*.json"))]
    if results:
        config = replace(config, worlds=1 + max(r.index for r in results))
    return config, results


def _check_rows(path: Path, result: WorldResult, config: WorldsBenchConfig) -> None:
    """Refuse a finished world whose rows are not of the benchmark ``config`` (one line)."""
    arms = config.task(result.index).arms()
    for row in result.rows:
        combo = f"{row.get('strategy')}/{row.get('field')}"
        if row.get("strategy") not in config.strategies or \
                row.get("field") not in config.fields or not isinstance(row.get("poke"), int) \
                or (row.get("appearance"), row.get("prior")) not in arms:
            raise ConfigError(f"source: {path} is not a rescorable world: a row of {combo!r} "
                              f"({row.get('appearance')}/{row.get('prior')}) at poke "
                              f"{row.get('poke')!r} is not of this benchmark")
        mapped = row.get("map_field", row["field"])
        if mapped not in choices("field"):
            raise ConfigError(f"source: {path} is not a rescorable world: a row of {combo!r} at "
                              f"poke {row['poke']} has `map_field` {mapped!r}, expected one of "
                              f"{list(choices('field'))}")
        stored = result.pokes if mapped == row["field"] else result.fallback_pokes
        key = WorldResult.run_key(row["appearance"], row["prior"], row["strategy"], row["field"])
        if key not in stored:
            raise ConfigError(f"source: {path} is not a rescorable world: no stored "
                              f"{'pokes' if mapped == row['field'] else 'fallback pokes'} of "
                              f"{key!r}, whose map field was {mapped!r} at poke {row['poke']}")


def rescore_worlds(source: Path, out: Path, *, cuts: Sequence[str] | None = None,
                   changes: Mapping[str, Any] | None = None,
                   hooks: RunHooks = NO_HOOKS) -> WorldsOutput:
    """Score the finished worlds of the benchmark folder ``source`` again under ``cuts`` and the
    exploration ``changes`` (dotted keys among :data:`RESCORABLE`, on top of the source's; default:
    the source's), from the pokes each world stored, into the new folder ``out`` (``bench.json``
    naming the source, ``worlds/``, ``runs.csv``, the summary and curves, as
    :func:`bench_worlds` writes them). No press is made again: the pokes do not depend on the
    cut (:func:`deformap.eval.rescore_world`).

    Raises
    ------
    ConfigError
        ``source`` is not a worlds benchmark of this format, holds no finished world, or a world
        that cannot be rescored (the file and what is wrong are named); ``out`` is not new or
        empty; a cut is unknown; a change is not rescorable or refused. Every world is checked
        before ``out`` is created. A failed world is carried into ``out`` as it was.
    """
    changes = dict(changes or {})
    moved = sorted(set(changes) - set(RESCORABLE))
    if moved:
        raise ConfigError(f"--set {', '.join(moved)}: a rescore scores the stored pokes again, so "
                          f"it may change only {', '.join(RESCORABLE)} (the rules that act after "
                          f"the pokes); run `bench worlds` to measure the others")
    config, results = load_worlds(Path(source))
    exploration = exploration_with({**exploration_changes(config.exploration), **changes})
    try:
        config = replace(config, exploration=exploration,
                         cuts=config.cuts if cuts is None else tuple(cuts))
    except InvalidArgumentError as exc:
        raise ConfigError(str(exc)) from None
    paths = sorted(Path(source, "worlds").glob("world-*.json"))
    for path, result in zip(paths, results, strict=True):
        if result.status == "ok":
            _check_rows(path, result, config)
    if not any(r.status == "ok" for r in results):
        raise ConfigError(f"source: {source} must hold finished worlds with their pokes stored; "
                          f"got none")
    folder = Path(out)
    with claim_run_folder(folder, what="benchmark"):
        write_bench(folder, config, rescored_from=str(source))
        (folder / "worlds").mkdir(exist_ok=True)
        hooks.start(RunStart(kind="bench rescore", folder=folder, total=len(results), done=0,
                             title=f"{len(results)} worlds of {source} rescored"))
        t0 = time.perf_counter()
        rescored = []
        for result in results:
            again = result if result.status != "ok" else rescore_world(
                config.task(result.index), result)
            write_text(world_path(folder, result.index), to_json(again.to_dict()))
            rescored.append(again)
            hooks.step(f"world {result.index} ({result.world.get('family')}) · {len(rescored)}/"
                       f"{len(results)} done")
        summary, files = write_summary(folder, config, rescored)
        return WorldsOutput(summary=summary, folder=folder, files=[folder / SETTINGS_NAME, *files],
                            computed=len(rescored), seconds=time.perf_counter() - t0)
