"""Memory benchmark: the peak memory of the surface GP (grid against exact) and of a β estimation.

Each case runs in a fresh process (``python -m deformap.eval._bench_memory CASE SIZE SEED``) that
builds its inputs, then measures the case alone: the peak of live Python and numpy allocations
(:mod:`tracemalloc`, blind to C libraries' own) and of the resident set (Linux ``VmHWM``, reset
through ``/proc/self/clear_refs`` after ``malloc_trim``). The cases are the speed benchmarks'
problems: the surface GP, exact or grid, and one β estimation, batched or its per-β loop.
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
import json
import os
import subprocess
import sys
import time
import tracemalloc
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from deformap._validation import check_int
from deformap.errors import InvalidArgumentError

__all__ = ["CASES", "bench_memory", "measure_case"]

CASES = ("gp-exact", "gp-grid", "beta-batched", "beta-loop")
#: The case each measured case is compared with (the baselines have none).
BASELINE = {"gp-grid": "gp-exact", "beta-batched": "beta-loop"}

_MIB = 2.0**20
_STATUS = Path("/proc/self/status")
_CLEAR_REFS = Path("/proc/self/clear_refs")


def _prepare(case: str, size: int, seed: int) -> Callable[[], Any]:
    """Build the case's inputs (outside the measurement) and return the call to measure."""
    rng = np.random.default_rng(seed)
    if case.startswith("gp-"):
        from deformap.eval._bench_gp import surface_problem, timed_fit_predict

        xy, z, xs, ys = surface_problem(size, rng)
        return lambda: timed_fit_predict(case.removeprefix("gp-"), xy, z, xs, ys)
    from scipy.spatial import cKDTree

    from deformap.eval._bench_msm import dent_problem, per_beta_loop
    from deformap.msm import ParticleGrid, ShapeMatchingConfig, estimate_beta

    cfg = ShapeMatchingConfig(cluster_size=3)
    xs, ys, z, pts, contact = dent_problem(size, rng)
    if case == "beta-batched":
        return lambda: estimate_beta(xs, ys, z, pts, contact, cfg)
    est = estimate_beta(xs, ys, z, pts, contact, cfg)  # which β, to which tolerance
    grid = ParticleGrid.from_heightmap(xs, ys, z)
    tree = cKDTree(pts)
    return lambda: per_beta_loop(grid, tree, contact, est, cfg)


def _status_kib(key: str) -> float | None:
    with contextlib.suppress(OSError):
        for line in _STATUS.read_text().splitlines():
            if line.startswith(key + ":"):
                return float(line.split()[1])
    return None


def _trim_heap() -> None:
    """Hand freed heap pages back to the OS (glibc), so the set-up's garbage is not reused unseen."""
    gc.collect()
    with contextlib.suppress(OSError, AttributeError):  # not glibc: the RSS may then read low
        ctypes.CDLL("libc.so.6").malloc_trim(0)


def _reset_peak_rss() -> bool:
    """Reset the kernel's peak-RSS mark of this process (Linux >= 4.0); False where impossible."""
    try:
        _CLEAR_REFS.write_text("5")
    except OSError:
        return False
    return _status_kib("VmHWM") is not None


def _run_case(case: str, size: int, seed: int) -> dict[str, Any]:
    """Measure ``case`` in this process (the child's side)."""
    run = _prepare(case, size, seed)
    _trim_heap()
    rss_before = _status_kib("VmRSS")
    peak_reset = rss_before is not None and _reset_peak_rss()
    tracing = tracemalloc.is_tracing()  # someone else's tracing (isolate=False) is left running
    if not tracing:
        tracemalloc.start()
    tracemalloc.reset_peak()
    traced_before = tracemalloc.get_traced_memory()[0]
    start = time.perf_counter()
    run()
    seconds = time.perf_counter() - start
    traced_peak = tracemalloc.get_traced_memory()[1] - traced_before
    if not tracing:
        tracemalloc.stop()
    rss_peak = _status_kib("VmHWM") if peak_reset else None
    row: dict[str, Any] = {
        "case": case, "size": size, "traced_peak_mib": traced_peak / _MIB,
        "rss_before_mib": None if rss_before is None else rss_before / 1024,
        "rss_peak_mib": None, "rss_added_mib": None, "seconds": seconds,
        "baseline": BASELINE.get(case),
    }  # fmt: skip
    if rss_peak is not None and rss_before is not None:
        row["rss_peak_mib"] = rss_peak / 1024
        row["rss_added_mib"] = (rss_peak - rss_before) / 1024
    return row


def _child_env() -> dict[str, str]:
    """This process's environment, with this very deformap first on the path (a source tree)."""
    src = str(Path(__file__).resolve().parents[2])
    path = os.pathsep.join(p for p in (src, os.environ.get("PYTHONPATH")) if p)
    return {**os.environ, "PYTHONPATH": path}


def measure_case(case: str, size: int, *, seed: int = 0, isolate: bool = True) -> dict[str, Any]:
    """Peak memory of one ``case`` of :data:`CASES` on ``size`` points of the cloud (``gp-*``)
    or particles per ROI side (``beta-*``), with synthetic data of ``seed``: ``case``, ``size``,
    ``traced_peak_mib``, ``rss_before_mib``, ``rss_peak_mib``, ``rss_added_mib`` (MiB; ``None``
    unmeasured, as with ``isolate=False``, measured in this process), ``seconds`` (while traced)
    and ``baseline`` (the case it is compared with, ``None`` for a baseline)."""
    if case not in CASES:
        raise InvalidArgumentError(f"`case` must be one of {list(CASES)}; got {case!r}")
    size = check_int("size", size, minimum=5 if case.startswith("beta-") else 2)
    seed = check_int("seed", seed, minimum=0)
    if not isolate:
        row = _run_case(case, size, seed)
        return {**row, "rss_before_mib": None, "rss_peak_mib": None, "rss_added_mib": None}
    done = subprocess.run([sys.executable, "-m", __name__, case, str(size), str(seed)],
                          env=_child_env(), capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"memory case {case} {size} failed:\n{done.stderr[-2000:]}")
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def bench_memory(*, gp_sizes: Sequence[int] = (3000, 12000), exact_max_points: int = 3000,
                 beta_side: int = 40, seed: int = 0, isolate: bool = True,
                 ) -> dict[str, list[dict[str, Any]]]:
    """Peak memory of the surface GP and of one β estimation, each beside its baseline:
    ``{"surface_gp": [rows], "beta_estimation": [rows]}``, rows of :func:`measure_case`, baselines
    first. The grid GP runs at each of ``gp_sizes``, the exact one at those up to
    ``exact_max_points`` (its N × N covariance is N² × 8 bytes several times over); the β
    estimation and its per-β loop on ``beta_side`` particles per ROI side."""
    sizes = [check_int("gp_sizes[i]", n, minimum=2) for n in gp_sizes]
    exact_max = check_int("exact_max_points", exact_max_points, minimum=2)

    def measure(case: str, size: int) -> dict[str, Any]:
        return measure_case(case, size, seed=seed, isolate=isolate)

    gp_rows = [measure("gp-exact", n) for n in sizes if n <= exact_max]
    gp_rows += [measure("gp-grid", n) for n in sizes]
    beta_rows = [measure("beta-loop", beta_side), measure("beta-batched", beta_side)]
    return {"surface_gp": gp_rows, "beta_estimation": beta_rows}


if __name__ == "__main__":  # the child of measure_case: one case, one JSON line on stdout
    _case, _size, _seed = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    print(json.dumps(_run_case(_case, _size, _seed)))
