"""Run deformap's benchmarks and print their tables (what each measures: benchmarks/README.md).

    python benchmarks/run.py                                   # speed, world, io, memory
    python benchmarks/run.py --only speed,memory --json-dir benchmarks/results
    python benchmarks/run.py --quick                           # smaller sizes, a smoke run

Each benchmark is a ``deformap bench`` command (its code lives in ``deformap.eval._bench_*``) and runs
in its own Python process, so that no benchmark measures a heap another one grew. From a source
checkout the ``src/`` beside this folder is imported, installed or not.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

#: Benchmark → extra arguments of its quick (smoke) form.
BENCHMARKS: dict[str, list[str]] = {
    "speed": ["--quick"],
    "world": ["--coarse"],
    "io": [],
    "memory": ["--quick"],
}

_SRC = Path(__file__).resolve().parents[1] / "src"


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--only",
        default=",".join(BENCHMARKS),
        help=f"comma-separated subset of {','.join(BENCHMARKS)} (default: all)",
    )
    parser.add_argument(
        "--json-dir", type=Path, help="also write each table as JSON: DIR/<benchmark>.json"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic data")
    parser.add_argument("--quick", action="store_true", help="smaller sizes (a smoke run)")
    args = parser.parse_args(argv)
    args.only = [name.strip() for name in args.only.split(",") if name.strip()]
    unknown = sorted(set(args.only) - set(BENCHMARKS))
    if unknown or not args.only:
        parser.error(f"--only takes names from {','.join(BENCHMARKS)}; got {args.only!r}")
    return args


def _env() -> dict[str, str]:
    env = dict(os.environ)
    if (_SRC / "deformap").is_dir():  # benchmark this checkout, not another installed copy
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(_SRC), env.get("PYTHONPATH")) if p)
    env.setdefault("COLUMNS", "110")  # rich wraps its tables at 80 columns when piped
    return env


def main(argv: list[str] | None = None) -> int:
    """Run the chosen benchmarks one after another; return 1 if any failed."""
    args = _parse(argv)
    if args.json_dir is not None:
        args.json_dir.mkdir(parents=True, exist_ok=True)
    summary = []
    for name in args.only:
        command = [sys.executable, "-m", "deformap", "bench", name, "--seed", str(args.seed)]
        if args.quick:
            command += BENCHMARKS[name]
        if args.json_dir is not None:
            command += ["--json", str(args.json_dir / f"{name}.json")]
        print(f"\n$ deformap {' '.join(command[3:])}", flush=True)
        start = time.perf_counter()
        code = subprocess.run(command, env=_env(), check=False).returncode
        summary.append((name, time.perf_counter() - start, code))
    print("\nbenchmark   wall [s]  result")
    for name, seconds, code in summary:
        print(f"{name:<10} {seconds:>9.1f}  {'ok' if code == 0 else f'FAILED (exit {code})'}")
    return int(any(code != 0 for _, _, code in summary))


if __name__ == "__main__":
    sys.exit(main())
