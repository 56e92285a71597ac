"""Compare the results of two sets of runs, timings aside: the same pokes, βs, regions, metrics.

Usage::

    python benchmarks/compare_reports.py OLD NEW

OLD and NEW are run folders (``report.json``) or folders of them (``deformap reproduce --out``);
every ``report.json`` and ``table.json`` under OLD is compared with the one at the same relative
path under NEW. Timings (any key ending in ``_s`` or named ``timings``), the version string and
absolute paths are left out, and so is every key ``--ignore`` names by its dotted path (a setting
added or retired on purpose, e.g. ``--ignore config.world.default_force_n``; ``[]`` stands for
any list index: ``--ignore pokes[].stiffness``); floats must agree to
``--rtol`` (default: exactly). Exit code 0 when everything agrees, 1 otherwise, with one line per
difference.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path
from typing import Any

IGNORED = {"timings", "deformap", "session", "time_s", "folder"}


def _differences(old: Any, new: Any, where: str, rtol: float,
                 ignore: frozenset[str] = frozenset()) -> list[str]:
    if isinstance(old, dict) and isinstance(new, dict):
        keys = {k for k in old.keys() | new.keys() if k not in IGNORED and not k.endswith("_s")
                and re.sub(r"\[\d+\]", "[]", f"{where}.{k}").lstrip(".") not in ignore}
        out = []
        for k in sorted(keys):
            if k not in old or k not in new:
                out.append(f"{where}.{k}: only in {'new' if k not in old else 'old'}")
            else:
                out += _differences(old[k], new[k], f"{where}.{k}", rtol, ignore)
        return out
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return [f"{where}: {len(old)} entries, now {len(new)}"]
        return [d for i, (a, b) in enumerate(zip(old, new, strict=True))
                for d in _differences(a, b, f"{where}[{i}]", rtol, ignore)]  # fmt: skip
    if isinstance(old, float) and isinstance(new, float):
        if old == new or (math.isnan(old) and math.isnan(new)):
            return []
        if rtol > 0 and math.isclose(old, new, rel_tol=rtol, abs_tol=rtol):
            return []
        return [f"{where}: {old!r}, now {new!r}"]
    return [] if old == new else [f"{where}: {old!r}, now {new!r}"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--rtol", type=float, default=0.0, help="relative tolerance of floats")
    parser.add_argument("--ignore", action="append", default=[], metavar="DOTTED.KEY",
                        help="leave out this key (repeat)")
    args = parser.parse_args(argv)
    names = ("report.json", "table.json")
    files = sorted(p.relative_to(args.old) for n in names for p in args.old.rglob(n))
    if not files:
        print(f"no report.json or table.json under {args.old}", file=sys.stderr)
        return 2
    problems = []
    for rel in files:
        if not (args.new / rel).is_file():
            problems.append(f"{rel}: missing in {args.new}")
            continue
        old = json.loads((args.old / rel).read_text())
        new = json.loads((args.new / rel).read_text())
        problems += [f"{rel}: {d}"
                     for d in _differences(old, new, "", args.rtol, frozenset(args.ignore))]
    for line in problems:
        print(line)
    print(f"{len(files)} files compared, {len(problems)} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
