"""Seeded mutants of every reader's input and every command-line option, counted by ending.

Each must load to a valid result or end in one clean error.

    python benchmarks/robustness.py --mutants 3000          # reader mutants
    python benchmarks/robustness.py --mutants 300 --seed 1  # a quick run
    python benchmarks/robustness.py --mutants 0 --cli-mutants 3000  # the command line's only

The reader mutants, their templates, the worker process with its per-case time limit and the
classification (``clean``, ``same``, ``changed``, ``silent``, ``traceback``, ``hang``) are
:mod:`deformap.testing.mutants`'s; their kinds include nested YAML alias bombs in every YAML a
user gives (``alias``: a session, a run configuration, a scenario, a raw bag's settings; one
accepted counts as ``silent``) and ascii clouds cut inside their last number
(``cut-number``); the command-line mutants (every option of every command given seeded hostile
values, an alias-bomb YAML among the paths, under a guard that stops a run before its work) and
their endings are
:mod:`deformap.testing.cli_mutants`'s. This script runs any number of them and prints a table per
reader and per value kind; it exits 1 when any traceback, hang, silent corruption or other ending
is counted. From a source checkout the ``src/`` beside this folder is imported, installed
or not. ``tests/robustness/`` runs the same machinery on a few hundred mutants each.
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
import time
from pathlib import Path

_SRC = Path(__file__).resolve().parents[1] / "src"
if _SRC.is_dir() and str(_SRC) not in sys.path:  # a source checkout's, installed or not
    sys.path.insert(0, str(_SRC))

from deformap.testing.mutants import run_mutants, table  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mutants", type=int, default=3000,
                        help="how many reader mutants (default 3000; 0: none)")
    parser.add_argument("--cli-mutants", type=int, default=0,
                        help="how many command-line mutants, at least (default 0: none; "
                             "deformap.testing.cli_mutants)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the mutants (default 0)")
    parser.add_argument("--limit", type=float, default=10.0,
                        help="seconds a case may take before it counts as a hang (default 10)")
    args = parser.parse_args(argv)
    if (args.mutants < 0 or args.cli_mutants < 0 or args.mutants + args.cli_mutants < 1
            or args.seed < 0 or not args.limit > 0):  # fmt: skip
        parser.error("--mutants and --cli-mutants must be >= 0 and not both 0, --seed >= 0 and "
                     "--limit > 0")
    logging.disable(logging.WARNING)  # refused pokes are counted, not logged
    bad: list[str] = []
    if args.mutants:
        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-robustness-") as tmp:
            cases = run_mutants(args.mutants, args.seed, args.limit, Path(tmp))
        print(table(cases))
        print(f"\n{len(cases)} mutants (seed {args.seed}) in {time.perf_counter() - start:.0f} s, "
              f"per-case limit {args.limit:g} s")
        bad += [f"{c.outcome}: {c.reader} {c.kind}: {c.detail}" for c in cases
                if c.outcome in ("traceback", "hang", "silent")]  # fmt: skip
    if args.cli_mutants:
        from deformap.testing.cli_mutants import HANG_LIMIT_S, cli_table, run_cli

        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-cli-mutants-") as tmp:
            cli_cases = run_cli(args.cli_mutants, args.seed, Path(tmp))
        print(("\n" if args.mutants else "") + cli_table(cli_cases))
        print(f"\n{len(cli_cases)} command-line mutants (seed {args.seed}) in "
              f"{time.perf_counter() - start:.0f} s, hang limit {HANG_LIMIT_S} s")
        bad += [f"{c.ending}: {c.option} ({c.kind}): {c.detail}" for c in cli_cases
                if c.ending in ("traceback", "hang", "other")]  # fmt: skip
    for line in bad[:20]:
        print(line)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
