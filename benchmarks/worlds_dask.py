"""Throughput of ``deformap bench worlds`` on Dask: one worker (the baseline) against two, in the
same run, on the same small set of worlds.

    PYTHONPATH=src python benchmarks/worlds_dask.py [--worlds 4] [--max-pokes 3] [--seed 0]
        [--strategies paper] [--fields beta] [--default-world] [--out /tmp/worlds-dask]

Each configuration starts its own ``LocalCluster`` on the loopback interface (processes, one
thread each, no dashboard), runs the same worlds into a fresh folder and times the whole call
(cluster start excluded). The worlds are coarse (``WorldConfig.coarse()``: the engines' scaling,
not the maps, is measured) unless ``--default-world``. Prints worlds per hour for each and the
speed-up against one worker, and checks that both runs give the same numbers (``runs.csv``
without its time columns). On a machine shared with other work the speed-up is bounded by the
cores left free, and two processes also take a larger share of a loaded machine than one: say
the load average beside the result (printed too).
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import shutil
import time
from pathlib import Path

from deformap.eval import TIME_COLUMNS
from deformap.run import WorldsBenchConfig, bench_worlds


def _values(folder: Path) -> list[dict[str, str]]:
    rows = csv.DictReader(io.StringIO((folder / "runs.csv").read_text()))
    return [{k: v for k, v in r.items() if k not in TIME_COLUMNS} for r in rows]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", type=int, default=4)
    parser.add_argument("--max-pokes", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--strategies", default="paper")
    parser.add_argument("--fields", default="beta")
    parser.add_argument("--default-world", action="store_true")
    parser.add_argument("--out", type=Path, default=Path("/tmp/worlds-dask"))
    args = parser.parse_args()
    from distributed import LocalCluster

    rows = []
    for n_workers in (1, 2):
        folder = args.out / f"workers-{n_workers}"
        shutil.rmtree(folder, ignore_errors=True)
        with LocalCluster(processes=True, n_workers=n_workers, threads_per_worker=1,
                          host="127.0.0.1", dashboard_address=None) as cluster:
            config = WorldsBenchConfig(
                worlds=args.worlds, seed=args.seed, max_pokes=args.max_pokes,
                strategies=tuple(args.strategies.split(",")), fields=tuple(args.fields.split(",")),
                coarse=not args.default_world, scheduler=cluster.scheduler_address)
            t0 = time.perf_counter()
            bench_worlds(config, folder)
            seconds = time.perf_counter() - t0
        rows.append((n_workers, seconds, args.worlds / seconds * 3600.0))
    same = _values(args.out / "workers-1") == _values(args.out / "workers-2")
    base = rows[0][1]
    print(f"{args.worlds} worlds, {args.max_pokes} pokes, {args.strategies} × {args.fields}, "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{'Dask workers':>12} {'wall [s]':>9} {'worlds/h':>9} {'speed-up':>9}")
    for n, seconds, per_hour in rows:
        label = "(baseline)" if n == 1 else f"{base / seconds:.2f}×"
        print(f"{n:>12} {seconds:>9.1f} {per_hour:>9.1f} {label:>9}")
    print(f"same numbers with 1 and 2 workers: {same}")


if __name__ == "__main__":
    main()
