"""Where the worlds of ``deformap bench worlds`` are computed: a local process pool or a Dask
cluster, results streamed back as they finish.

By default a local process pool (``concurrent.futures`` with the ``spawn`` start method: no
state of the parent leaks into a worker); with a scheduler, a ``dask.distributed`` cluster
(``Client(address)``; results stream back with ``as_completed``). Either way a world that raises
is tried once more and then reported as failed, never dropped. A task and its result cross the
process boundary as plain data (:func:`task_data`, :meth:`deformap.eval.WorldResult.to_dict`),
converted in :func:`run_world_data` only. Each world runs with its BLAS pinned to one thread
(threadpoolctl in the task; for the local pool also the environment variables, set before a
worker loads numpy), because two BLAS threads per process oversubscribe a machine that runs one
world per core.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from typing import Any

from deformap.errors import ConfigError
from deformap.eval import WorldResult, WorldTask, draw_world, run_world
from deformap.run._worlds_config import exploration_changes, exploration_with

__all__ = ["BLAS_THREAD_VARIABLES", "SCHEDULER_TIMEOUT_S", "check_scheduler", "task_data",
           "worker_pool", "world_results"]

logger = logging.getLogger(__name__)

#: The environment variables that size the BLAS and OpenMP thread pools a worker's numpy and
#: scipy start with; each is set to 1 for the local pool's workers.
BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                         "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")

#: Seconds a scheduler has to accept the connection and say who it is (:func:`check_scheduler`);
#: a scheduler on a busy network answers within one.
SCHEDULER_TIMEOUT_S = 10.0


def task_data(task: WorldTask) -> dict[str, Any]:
    """``task`` as the plain data that crosses the process boundary (:func:`run_world_data`)."""
    return {"seed": task.seed, "index": task.index, "families": list(task.families),
            "physics": list(task.physics), "appearances": list(task.appearances),
            "strategies": list(task.strategies),
            "fields": list(task.fields), "cuts": list(task.cuts), "max_pokes": task.max_pokes,
            "coarse": task.coarse, "exploration": exploration_changes(task.exploration)}


def _task(data: dict[str, Any]) -> WorldTask:
    """The inverse of :func:`task_data`."""
    lists = ("families", "physics", "appearances", "strategies", "fields", "cuts")
    given: dict[str, Any] = {k: tuple(v) if k in lists else v for k, v in data.items()
                             if k != "exploration"}
    return WorldTask(**given,
                     exploration=exploration_with(data["exploration"]))


def run_world_data(data: dict[str, Any]) -> dict[str, Any]:
    """:func:`deformap.eval.run_world` on :func:`task_data`'s data, with BLAS and OpenMP pinned
    to one thread; the result as :meth:`~deformap.eval.WorldResult.to_dict`'s data."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return run_world(_task(data)).to_dict()


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


def _failed(data: dict[str, Any], exc: BaseException) -> WorldResult:
    """The result of a world that raised twice: its draw (as far as it goes) and the error."""
    families, index = data["families"], data["index"]
    try:
        world = draw_world(data["seed"], index, tuple(families), tuple(data["physics"])).summary()
    except Exception:  # the failure to report may be the draw itself
        world = {"index": index, "family": families[index % len(families)]}
    error = f"{type(exc).__name__}: {exc}".splitlines()[0]
    return WorldResult(world=world, status="failed", error=error)


def _local_results(tasks: Sequence[dict[str, Any]], workers: int) -> Iterator[WorldResult]:
    """Results as they finish on a spawn-started process pool; each task retried once."""
    with _one_thread_environment():
        pool = worker_pool(workers)
        try:
            pending: dict[Future[dict[str, Any]], tuple[dict[str, Any], int]] = {
                pool.submit(run_world_data, t): (t, 0) for t in tasks}
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    task, tries = pending.pop(future)
                    try:
                        result = WorldResult.from_dict(future.result())
                    except Exception as exc:  # reported, never dropped
                        if tries == 0:
                            logger.warning("world %d failed (%s); trying once more",
                                           task["index"], exc)
                            pending[pool.submit(run_world_data, task)] = (task, 1)
                            continue
                        result = _failed(task, exc)
                    yield result
        except BaseException:
            # interrupted (or the caller stopped reading): start no further world
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown()


async def _identify(address: str, timeout_s: float) -> tuple[Any, Any]:
    """What the server at ``address`` answers to Dask's ``identity`` and ``versions``."""
    from distributed.comm import connect

    comm = await connect(address, timeout=timeout_s)
    try:
        await comm.write({"op": "identity", "reply": True})
        identity = await comm.read()
        await comm.write({"op": "versions", "reply": True})
        return identity, await comm.read()
    finally:
        comm.abort()


def check_scheduler(address: str) -> str:
    """Connect to ``address`` and require a Dask scheduler there, all within
    :data:`SCHEDULER_TIMEOUT_S`: it must answer Dask's ``identity`` as a ``Scheduler`` and its
    ``versions``. Returns the ``distributed`` version it reports.

    The whole exchange runs under one time limit, on its own event loop in a helper thread, so a
    server that accepts and then says nothing, or sends bytes that are no Dask message, ends in
    one line rather than a hang or an allocation of whatever size its bytes spell.

    Raises
    ------
    ConfigError
        dask is not installed; nothing answers at ``address``; the answer is no Dask scheduler's.
    """
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ConfigError("--scheduler needs dask.distributed; install it with "
                          "pip install 'deformap[dask]'") from None
    where, limit = f"--scheduler {address!r}", SCHEDULER_TIMEOUT_S
    quiet = logging.getLogger("distributed")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)  # a refused handshake is ours to report, in one line
    try:
        with ThreadPoolExecutor(1) as pool:
            identity, versions = pool.submit(
                asyncio.run, asyncio.wait_for(_identify(address, limit), limit)).result()
    except TimeoutError:
        raise ConfigError(f"{where}: no Dask scheduler answered within {limit:g} s") from None
    except OSError as exc:  # refused, unreachable (distributed's CommClosedError too)
        detail = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
        raise ConfigError(f"{where}: cannot reach a Dask scheduler there: {detail}") from None
    except Exception as exc:  # bytes that are no Dask message: its reader's own errors
        raise ConfigError(f"{where} answered, but not as a Dask scheduler "
                          f"({type(exc).__name__}: {str(exc)[:100]})".replace("\n", " ")) from None
    finally:
        quiet.setLevel(level)
    kind = identity.get("type") if isinstance(identity, dict) else None
    packages = versions.get("packages") if isinstance(versions, dict) else None
    if kind != "Scheduler" or not isinstance(packages, dict) or "distributed" not in packages:
        raise ConfigError(f"{where} answered, but not as a Dask scheduler (identity "
                          f"{str(kind)[:40]!r}, no distributed version)")
    return str(packages["distributed"])


def _dask_results(tasks: Sequence[dict[str, Any]], address: str) -> Iterator[WorldResult]:
    """Results as they finish on a ``dask.distributed`` cluster; each task retried once."""
    version = check_scheduler(address)
    from dask.distributed import Client, as_completed

    logger.info("Dask scheduler at %s, distributed %s", address, version)
    try:
        client = Client(address, timeout=f"{SCHEDULER_TIMEOUT_S:g}s")
    except Exception as exc:  # it answered a moment ago: whatever its client raises, one line
        raise ConfigError(f"--scheduler {address!r}: cannot connect a Dask client: "
                          f"{type(exc).__name__}: {exc}".splitlines()[0]) from None
    with client:
        stamp = time.time_ns()
        futures = {}
        for task in tasks:
            future = client.submit(run_world_data, task, retries=1, pure=False,
                                   key=f"deformap-world-{task['seed']}-{task['index']}-{stamp}")
            futures[future.key] = (future, task)
        for future in as_completed([f for f, _ in futures.values()]):
            task = futures[future.key][1]
            try:
                result = WorldResult.from_dict(future.result())
            except Exception as exc:  # reported, never dropped
                result = _failed(task, exc)
            yield result
            future.release()


def world_results(tasks: Sequence[WorldTask], *, workers: int = 1,
                  scheduler: str | None = None) -> Iterator[WorldResult]:
    """Each task's result as it finishes, on ``workers`` local processes or, with
    ``scheduler``, a Dask cluster; a world that raises twice comes back failed.

    Raises
    ------
    ConfigError
        The scheduler cannot be reached, or dask is not installed.
    """
    data = [task_data(t) for t in tasks]
    return (_dask_results(data, scheduler) if scheduler is not None
            else _local_results(data, workers))
