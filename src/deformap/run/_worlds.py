"""``deformap bench worlds``: many seeded random worlds, each mapped with every strategy × field,
on a local process pool or a Dask cluster, resumable.

The folder holds ``bench.json`` (the settings, written first), ``worlds/world-NNNNN.json`` (one
result per world, written atomically as it arrives: a killed run loses at most the worlds in
flight) and, rewritten after every world, ``runs.csv``, ``summary.json``, ``summary.md`` and
``curves.png`` (:mod:`deformap.eval._worlds_summary`, :func:`deformap.viz.plot_world_curves`).
Run again on the same folder with the same settings, it reads the finished worlds and computes
only the others (a world that failed is tried again).

Engines. By default a local process pool (``concurrent.futures`` with the ``spawn`` start
method: no state of the parent leaks into a worker); with ``scheduler``, a ``dask.distributed``
cluster (``Client(address)``; results stream back with ``as_completed``). Either way a world
that raises is tried once more and then reported as failed (in ``runs.csv``, ``summary.json``
and its world file), never dropped. Tasks and results cross processes as plain data (numbers,
strings, lists, dicts). Each world runs with its BLAS pinned to one thread (threadpoolctl in the
task; for the local pool also the environment variables, set before a worker loads numpy): two
OpenBLAS threads per process doubled a run's wall time on a loaded 2-core machine (issue 16).
"""

from __future__ import annotations

import contextlib
import json
import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Literal

from deformap import __version__
from deformap._validation import SettingError, check_settings, setting
from deformap.errors import ConfigError
from deformap.eval import (
    POKES_FORMAT,
    accuracy_curves,
    choices,
    fell_back_cuts,
    markdown_summary,
    rescore_world,
    run_world,
    runs_csv,
    summarise_worlds,
)
from deformap.explore import ExplorationConfig
from deformap.run._folder import create_run_folder, default_run_folder, to_json, write_text
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.viz import plot_world_curves
from deformap.world import LAYOUT_FAMILIES, PHYSICS

__all__ = ["BLAS_THREAD_VARIABLES", "WorldsBenchConfig", "WorldsOutput", "bench_worlds",
           "rescore_worlds"]

logger = logging.getLogger(__name__)

#: The environment variables that size the BLAS and OpenMP thread pools a worker's numpy and
#: scipy start with; each is set to 1 for the local pool's workers.
BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                         "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")
SETTINGS_NAME = "bench.json"
# removed from ExplorationConfig (wt-explore); the bench's own options go with SETTINGS_BEFORE
UnreadPlace = Literal["beta", "avoid"]
BoundaryScore = Literal["straddle", "nearest-poke"]
#: What a run did before each of these settings was in ``bench.json``: scored without the split by
#: place, gave a run to β at an unread place, scored boundary pokes by straddle.
SETTINGS_BEFORE: dict[str, Any] = {"split_by_place": False, "unread_place": "beta",
                                   "boundary_score": "straddle"}


@dataclass(frozen=True, kw_only=True)
class WorldsBenchConfig:
    """What ``deformap bench worlds`` runs (``worlds``, ``workers`` and ``scheduler`` do not
    change a world's result, so a run may resume with more worlds or on another engine).

    Parameters
    ----------
    worlds : int
        How many worlds (indices 0 .. worlds − 1 of the seed).
    seed : int
    families : tuple of str
        Layout families, taken in turn (:data:`deformap.world.LAYOUT_FAMILIES`).
    physics : tuple of str
        The world physics each world's is drawn from (:data:`deformap.world.PHYSICS`).
    strategies, fields : tuple of str
        ``ExplorationConfig.strategy`` and ``field`` values, every pair mapped on every world.
    cuts : tuple of str
        ``ExplorationConfig.region_labels`` values, each scored on the same pokes (the pokes
        do not depend on the cut).
    max_pokes : int
        Pokes per world and combination.
    merge_seams : bool
        ``ExplorationConfig.merge_seams`` for every cut scored (it acts after the pokes, on the
        regions, like the cut; its default is the exploration's).
    split_by_place : bool
        ``ExplorationConfig.split_by_place`` likewise.
    unread_place : {"beta", "avoid"}
        ``ExplorationConfig.unread_place`` (it changes where the pokes go after a place could
        not be read, so a rescore keeps the source's; default the exploration's).
    boundary_score : {"straddle", "nearest-poke"}
        ``ExplorationConfig.boundary_score`` (where the boundary pokes go; likewise kept).
    coarse : bool
        The test mesh and camera (:meth:`deformap.world.WorldConfig.coarse`, about a third of a
        default world's cost) instead of the default world. A smoke run only: on one linear-FEM
        world, 6 pokes of ``planned`` on the modulus field read E 100 % off on the 2 cm mesh
        and 14 % off on the default 7.5 mm mesh (region accuracy 0.86 against 0.94).
    workers : int
        Processes of the local pool.
    scheduler : str or None
        A ``dask.distributed`` scheduler's address (``tcp://host:8786``) instead of the pool.
    """

    worlds: int = setting(100, ge=1, le=1_000_000)
    seed: int = setting(0, ge=0)
    families: tuple[str, ...] = LAYOUT_FAMILIES
    physics: tuple[str, ...] = PHYSICS
    # every choice ExplorationConfig has, so a strategy or field added there is benchmarked too
    strategies: tuple[str, ...] = choices("strategy")
    fields: tuple[str, ...] = choices("field")
    cuts: tuple[str, ...] = choices("region_labels")
    # every poke is a press and a β sweep per combination (issue 16 reads 20 and more)
    max_pokes: int = setting(12, ge=1, le=1000)
    merge_seams: bool = ExplorationConfig().merge_seams
    split_by_place: bool = ExplorationConfig().split_by_place
    unread_place: UnreadPlace = "avoid"
    boundary_score: BoundaryScore = "straddle"
    coarse: bool = False
    workers: int = setting(1, ge=1, le=1024)
    scheduler: str | None = None

    def __post_init__(self) -> None:
        check_settings(self)
        for name, given, allowed in (("families", self.families, LAYOUT_FAMILIES),
                                     ("physics", self.physics, PHYSICS),
                                     ("strategies", self.strategies, choices("strategy")),
                                     ("fields", self.fields, choices("field")),
                                     ("cuts", self.cuts, choices("region_labels"))):
            unknown = [g for g in given if g not in allowed]
            repeated = sorted({g for g in given if given.count(g) > 1})
            if not given or unknown or repeated:
                why = ("none" if not given else f"{unknown} (unknown)" if unknown
                       else f"{repeated} more than once")
                raise SettingError(name, f"must be distinct names from {list(allowed)}; got "
                                         f"{why}")

    def result_settings(self) -> dict[str, Any]:
        """The settings a world's result depends on (``bench.json``; resuming compares them)."""
        return {k: v for k, v in asdict(self).items()
                if k not in ("worlds", "workers", "scheduler")}

    def combinations(self) -> list[tuple[str, str, str]]:
        return [(s, f, c) for s in self.strategies for f in self.fields for c in self.cuts]

    def task(self, index: int) -> dict[str, Any]:
        """The plain-data task of world ``index``."""
        return {"seed": self.seed, "index": index, "families": list(self.families),
                "physics": list(self.physics),
                "strategies": list(self.strategies), "fields": list(self.fields),
                "cuts": list(self.cuts), "max_pokes": self.max_pokes, "coarse": self.coarse,
                "merge_seams": self.merge_seams, "split_by_place": self.split_by_place,
                "unread_place": self.unread_place, "boundary_score": self.boundary_score}


@dataclass(frozen=True, kw_only=True)
class WorldsOutput:
    """What :func:`bench_worlds` wrote: ``summary`` (``summary.json``'s content), ``folder``,
    ``files`` and the worlds ``computed`` by this call (the others were read back)."""

    summary: dict[str, Any]
    folder: Path
    files: list[Path]
    computed: int
    seconds: float


def run_world_pinned(task: dict[str, Any]) -> dict[str, Any]:
    """:func:`deformap.eval.run_world` with BLAS and OpenMP pinned to one thread."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return run_world(task)


def _pin_worker() -> None:
    """A pool worker's start: BLAS pinned to one thread, and a watch that ends the worker when
    the process that started it is gone (killed by a signal that left it no time to stop its
    pool: the worker would compute its world to the end for nobody)."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)
    parent = multiprocessing.parent_process()
    if parent is not None:
        threading.Thread(target=_exit_with_parent, args=(parent,), daemon=True,
                         name="deformap-parent-watch").start()


def _exit_with_parent(parent: Any) -> None:
    """Wait on the parent's sentinel (its end of the start pipe on POSIX, its process handle
    on Windows: ready the moment it is gone) and end this worker then."""
    parent.join()
    os._exit(1)


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """The local pool of ``bench worlds``: spawn-started processes with BLAS pinned to one thread
    that end with the process that started them. A worker starts at a ``submit`` that finds
    none idle (up to ``workers``): submit within :func:`_one_thread_environment` (their numpy
    reads the thread variables as it loads)."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_pin_worker)


@contextlib.contextmanager
def _one_thread_environment() -> Iterator[None]:
    """The BLAS variables at 1 while workers start (they read them when they load numpy)."""
    saved = {k: os.environ.get(k) for k in BLAS_THREAD_VARIABLES}
    os.environ.update(dict.fromkeys(BLAS_THREAD_VARIABLES, "1"))
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _failed(task: dict[str, Any], exc: BaseException) -> dict[str, Any]:
    from deformap.eval import draw_world

    try:
        world = draw_world(task["seed"], task["index"], tuple(task["families"]),
                           tuple(task.get("physics", PHYSICS))).summary()
    except Exception:  # the failure to report may be the draw itself
        world = {"index": task["index"],
                 "family": task["families"][task["index"] % len(task["families"])]}
    error = f"{type(exc).__name__}: {exc}".splitlines()[0]
    return {"world": world, "rows": [], "seconds": None, "status": "failed", "error": error}


def _local_results(tasks: Sequence[dict[str, Any]], workers: int) -> Iterator[dict[str, Any]]:
    """Results as they finish on a spawn-started process pool; each task retried once."""
    with _one_thread_environment():
        pool = worker_pool(workers)
        try:
            pending: dict[Future[dict[str, Any]], tuple[dict[str, Any], int]] = {
                pool.submit(run_world_pinned, t): (t, 0) for t in tasks}
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    task, tries = pending.pop(future)
                    try:
                        result = future.result()
                    except Exception as exc:  # reported, never dropped
                        if tries == 0:
                            logger.warning("world %d failed (%s); trying once more",
                                           task["index"], exc)
                            pending[pool.submit(run_world_pinned, task)] = (task, 1)
                            continue
                        result = _failed(task, exc)
                    yield result
        except BaseException:
            # interrupted (or the caller stopped reading): start no further world
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown()


def _dask_results(tasks: Sequence[dict[str, Any]], address: str) -> Iterator[dict[str, Any]]:
    """Results as they finish on a ``dask.distributed`` cluster; each task retried once."""
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--scheduler needs dask.distributed; install it with "
                          "pip install 'deformap[dask]'") from None
    try:
        client = Client(address, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError(f"--scheduler: cannot reach a Dask scheduler at {address!r}: "
                          f"{exc}".splitlines()[0]) from None
    with client:
        stamp = time.time_ns()
        futures = {}
        for task in tasks:
            future = client.submit(run_world_pinned, task, retries=1, pure=False,
                                   key=f"deformap-world-{task['seed']}-{task['index']}-{stamp}")
            futures[future.key] = (future, task)
        for future in as_completed([f for f, _ in futures.values()]):
            task = futures[future.key][1]
            try:
                yield future.result()
            except Exception as exc:  # reported, never dropped
                yield _failed(task, exc)
            future.release()


def _world_path(folder: Path, index: int) -> Path:
    return folder / "worlds" / f"world-{index:05d}.json"


def _open_folder(config: WorldsBenchConfig, out: Path | None) -> tuple[Path, dict[int, Any]]:
    """The folder (new, or the same run's to resume) and the finished worlds found there."""
    folder = out or default_run_folder("worlds", "bench", config.seed)
    header = {"deformap": __version__, "settings": config.result_settings()}
    settings_file = folder / SETTINGS_NAME
    if settings_file.is_file():
        try:
            stored = json.loads(settings_file.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ConfigError(f"--out: {settings_file} cannot be read: {exc}") from None
        ours = json.loads(to_json(config.result_settings()))
        theirs = stored.get("settings") if isinstance(stored, dict) else None
        if isinstance(theirs, dict):  # a run from before a setting did what it did then
            theirs = {**SETTINGS_BEFORE, **theirs}
        if theirs != ours:
            there = theirs if isinstance(theirs, dict) else {}
            differ = ", ".join(f"{k}: {there.get(k)!r} there, {ours.get(k)!r} here"
                               for k in sorted(set(ours) | set(there))
                               if there.get(k) != ours.get(k))
            raise ConfigError(
                f"--out {str(folder)!r} holds a worlds benchmark with other settings "
                f"({differ}); choose another --out or the same settings")
    else:
        create_run_folder(folder, what="benchmark")
        write_text(settings_file, to_json(header))
    (folder / "worlds").mkdir(exist_ok=True)
    done: dict[int, Any] = {}
    for index in range(config.worlds):
        path = _world_path(folder, index)
        if path.is_file():
            with contextlib.suppress(OSError, ValueError):
                result = json.loads(path.read_text(encoding="utf-8"))
                if result.get("status") == "ok":
                    done[index] = result
    return folder, done


def _write_outputs(folder: Path, config: WorldsBenchConfig, results: Sequence[dict[str, Any]]
                   ) -> tuple[dict[str, Any], list[Path]]:
    combos = config.combinations()
    summary = summarise_worlds(results, combos, config.max_pokes)
    summary["settings"] = {**config.result_settings(), "worlds": config.worlds}
    files = [write_text(folder / "runs.csv", runs_csv(results, combos)),
             write_text(folder / "summary.json", to_json(summary)),
             write_text(folder / "summary.md", markdown_summary(summary))]
    curves = accuracy_curves(results, combos, config.max_pokes)
    if curves:
        plot_world_curves(curves, good_accuracy=summary["good_accuracy"],
                          path=folder / "curves.png")
        files.append(folder / "curves.png")
    return summary, files


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
        ``out`` holds something else, or a benchmark with other settings; the scheduler cannot
        be reached or dask is not installed.
    """
    if not isinstance(config, WorldsBenchConfig):
        raise ConfigError(f"`config` must be a WorldsBenchConfig; got {type(config).__name__}")
    folder, done = _open_folder(config, out)
    results = dict(done)
    engine = (f"Dask at {config.scheduler}" if config.scheduler
              else f"{config.workers} local process{'es' if config.workers > 1 else ''}")
    hooks.start(RunStart(kind="bench worlds", folder=folder, total=config.worlds, done=len(done),
                         title=f"{config.worlds} worlds, seed {config.seed}, {engine}"))
    tasks = [config.task(i) for i in range(config.worlds) if i not in done]
    t0 = time.perf_counter()
    stream = (_dask_results(tasks, config.scheduler) if config.scheduler
              else _local_results(tasks, config.workers))
    computed = 0
    summary, files = _write_outputs(folder, config, list(results.values())) if done else ({}, [])
    for result in stream:
        index = int(result["world"]["index"])
        write_text(_world_path(folder, index), to_json(result))
        results[index] = result
        computed += 1
        summary, files = _write_outputs(folder, config, list(results.values()))
        elapsed = time.perf_counter() - t0
        rate = computed / elapsed * 3600.0
        left = (len(tasks) - computed) / rate * 3600.0 if rate > 0 else float("nan")
        what = (f"{result['seconds']:.0f} s" if result["status"] == "ok"
                else f"FAILED: {result['error']}")
        hooks.step(f"world {index} ({result['world']['family']}): {what} · "
                   f"{len(results)}/{config.worlds} done · {rate:.1f} worlds/h · "
                   f"{left / 60:.0f} min left")
    if not tasks and not files:
        summary, files = _write_outputs(folder, config, list(results.values()))
    return WorldsOutput(summary=summary, folder=folder, files=[folder / SETTINGS_NAME, *files],
                        computed=computed, seconds=time.perf_counter() - t0)


def _check_stored(path: Path, result: Any, config: WorldsBenchConfig) -> dict[str, Any]:
    """``result`` read from ``path`` if it is a world of the benchmark ``config`` that can be
    rescored (a failed one is carried as it is); else one :class:`ConfigError` line naming the
    file and what is wrong."""
    def bad(what: str) -> ConfigError:
        return ConfigError(f"source: {path} is not a rescorable world: {what}")

    if not isinstance(result, dict) or not isinstance(result.get("world"), dict):
        raise bad("expected an object with a `world` object")
    index = result["world"].get("index")
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise bad(f"`world.index` must be an integer >= 0; got {index!r}")
    if result.get("status") != "ok":
        return result
    rows, pokes = result.get("rows"), result.get("pokes")
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise bad("`rows` must be a list of objects")
    if not isinstance(pokes, dict):
        raise bad("no `pokes` (a world run before pokes were stored)")
    version = result.get("pokes_format", 1)  # stored before the key was: the first format
    whole = isinstance(version, int) and not isinstance(version, bool)
    if not (whole and 1 <= version <= POKES_FORMAT):
        raise bad(f"`pokes_format` must be an integer from 1 to {POKES_FORMAT} (the formats this "
                  f"deformap reads); got {version!r}"
                  + (" (written by a newer version?)" if whole and version > POKES_FORMAT else ""))
    fallback = result.get("fallback_pokes", {})
    if not isinstance(fallback, dict):
        raise bad(f"`fallback_pokes` must be an object; got {type(fallback).__name__}")

    def check_pokes(data: Any, what: str) -> None:
        if not isinstance(data, dict):
            raise bad(f"no stored {what}")
        columns = ("x", "y", "value", "noise", "index")
        if not all(isinstance(data.get(k), list) for k in columns):
            raise bad(f"the {what} must have lists {list(columns)}")
        if version >= 2 and "thickness" not in data:
            raise bad(f"the {what} have no `thickness` (pokes_format {version})")
        sizes = {len(data[k]) for k in (*columns, *(("thickness",) if "thickness" in data
                                                    else ()))}
        if len(sizes) != 1 or not isinstance(data.get("thickness", []), list):
            raise bad(f"the {what} have columns of different lengths")
        numbers = [v for k in columns for v in data[k]]
        numbers += [v for v in data.get("thickness", []) if v is not None]
        if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in numbers):
            raise bad(f"the {what} must be numbers")

    combos: dict[str, tuple[str, int] | None] = {}  # each one's first poke on another field
    for row in rows:
        combo = f"{row.get('strategy')}/{row.get('field')}"
        if row.get("strategy") not in config.strategies or \
                row.get("field") not in config.fields or not isinstance(row.get("poke"), int):
            raise bad(f"a row of {combo!r} at poke {row.get('poke')!r} is not of this benchmark")
        mapped = row.get("map_field", row["field"])
        if mapped not in choices("field"):
            raise bad(f"a row of {combo!r} at poke {row['poke']} has `map_field` {mapped!r}, "
                      f"expected one of {list(choices('field'))}")
        if combos.get(combo) is None:
            combos[combo] = (mapped, row["poke"]) if mapped != row["field"] else None
    for combo, fell in combos.items():  # each combination's stored pokes, once
        check_pokes(pokes.get(combo), f"pokes of {combo!r}")
        if combo in fallback:
            check_pokes(fallback[combo], f"fallback pokes of {combo!r}")
        elif fell is not None and version >= 3:  # the third format stores them
            raise bad(f"no stored fallback pokes of {combo!r}, whose map field was {fell[0]!r} "
                      f"at poke {fell[1]} (pokes_format {version})")
    for (strategy, field), ran in fell_back_cuts(result).items():
        if set(config.cuts) - ran:
            raise bad(f"the run of {strategy}/{field} fell back from the modulus field to β, so "
                      f"its rows are carried, under the cuts it was scored on only "
                      f"({sorted(ran)}); got --cuts {sorted(config.cuts)}")
    return result


def rescore_worlds(source: Path, out: Path, *, cuts: Sequence[str] | None = None,
                   merge_seams: bool | None = None, split_by_place: bool | None = None,
                   hooks: RunHooks = NO_HOOKS) -> WorldsOutput:
    """Score the finished worlds of the benchmark folder ``source`` again under ``cuts``,
    ``merge_seams`` and ``split_by_place`` (default: the source's; a source from before the split
    by place was scored without it), from the pokes each world stored, into the new
    folder ``out`` (``bench.json`` naming the source, ``worlds/``, ``runs.csv``, the summary and
    curves, as :func:`bench_worlds` writes them). No press is made again: the pokes do not depend
    on the cut, so a cut or seam rule added later is measured on the same pokes in seconds a
    world (:func:`deformap.eval.rescore_world`).

    Raises
    ------
    ConfigError
        ``source`` is not a worlds benchmark, holds no finished world, or a world that cannot be
        rescored (from before the pokes were stored, or damaged: the file and what is wrong are
        named); ``out`` is not new or empty; a cut is unknown. Every world is checked before
        ``out`` is created. A failed world is carried into ``out`` as it was.
    """
    settings_file = Path(source) / SETTINGS_NAME
    try:
        stored = json.loads(settings_file.read_text(encoding="utf-8"))["settings"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ConfigError(f"source: {settings_file} is not a worlds benchmark's settings: "
                          f"{exc}") from None
    known = {f for f in WorldsBenchConfig.__dataclass_fields__} - {"worlds", "workers",
                                                                     "scheduler"}
    if not isinstance(stored, dict) or not set(stored) <= known:
        raise ConfigError(f"source: {settings_file} holds settings this version does not know: "
                          f"{sorted(set(stored) - known) if isinstance(stored, dict) else stored}")
    given: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v
                             for k, v in stored.items()}
    if cuts is not None:
        given["cuts"] = tuple(cuts)
    if merge_seams is not None:
        given["merge_seams"] = merge_seams
    given = {**SETTINGS_BEFORE, **given}  # a source from before a setting did what it did then
    if split_by_place is not None:
        given["split_by_place"] = split_by_place
    config = WorldsBenchConfig(worlds=1, **given)  # the settings checked before any world
    results = []
    for path in sorted(Path(source, "worlds").glob("world-*.json")):
        try:
            result = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ConfigError(f"source: {path} cannot be read: {exc}") from None
        results.append(_check_stored(path, result, config))
    finished = [r for r in results if r.get("status") == "ok"]
    if not finished:
        raise ConfigError(f"source: {source} must hold finished worlds with their pokes stored; "
                          f"got none")
    config = replace(config, worlds=1 + max(r["world"]["index"] for r in results))
    folder = Path(out)
    create_run_folder(folder, what="benchmark")
    write_text(folder / SETTINGS_NAME, to_json({"deformap": __version__,
                                                "settings": config.result_settings(),
                                                "rescored_from": str(source)}))
    (folder / "worlds").mkdir(exist_ok=True)
    hooks.start(RunStart(kind="bench rescore", folder=folder, total=len(results), done=0,
                         title=f"{len(results)} worlds of {source} rescored"))
    t0 = time.perf_counter()
    rescored = []
    for result in results:
        index = int(result["world"]["index"])
        again = result if result.get("status") != "ok" else rescore_world(
            config.task(index), result, config.cuts, merge_seams=config.merge_seams,
            split_by_place=config.split_by_place)
        write_text(_world_path(folder, index), to_json(again))
        rescored.append(again)
        hooks.step(f"world {index} ({result['world'].get('family')}) · {len(rescored)}/"
                   f"{len(results)} done")
    summary, files = _write_outputs(folder, config, rescored)
    return WorldsOutput(summary=summary, folder=folder, files=[folder / SETTINGS_NAME, *files],
                        computed=len(rescored), seconds=time.perf_counter() - t0)
