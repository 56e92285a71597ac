"""One table over the combinations of one or more ``deformap bench worlds`` runs (issue 16).

    PYTHONPATH=src python benchmarks/worlds_table.py RUN [RUN ...] [--worlds N]

Reads each run's ``runs.csv`` (a ``bench worlds`` or ``bench rescore`` folder) and prints, per
strategy/field/cut over the worlds below ``--worlds`` (default: all), what the README's "Many
worlds" tables show beyond ``summary.md``: the median pokes to region accuracy 0.9 (a world never
there counts ``max_pokes + 1``, as ``summary.json``), the share reaching it, the median final
accuracy, the mean accuracy after 5 / 10 / 20 pokes, the median pokes until the map field's
variance was under ``T_h`` (``max_pokes + 1`` when never), how many runs ended mapped on another
field than asked (a modulus run gone to β), and the share of worlds with fewer / more regions than
true after the last poke. Two runs of the same worlds may be put side by side (say, the modulus
field of one and the β-field of another); a combination found in two runs is refused.
"""

from __future__ import annotations

import argparse
import csv
import statistics
from collections import defaultdict
from pathlib import Path

GOOD = 0.9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", type=Path, nargs="+", help="bench worlds folders")
    parser.add_argument("--worlds", type=int, help="only the worlds numbered below this")
    args = parser.parse_args()
    by: dict[tuple[str, str, str], dict[int, list[dict[str, str]]]] = {}
    for run in args.runs:
        path = run / "runs.csv"
        if not path.is_file():
            raise SystemExit(f"RUN: expected a bench worlds folder with runs.csv; got {run}")
        found: dict[tuple[str, str, str], dict[int, list[dict[str, str]]]] = defaultdict(
            lambda: defaultdict(list))
        with path.open(encoding="utf-8", newline="") as handle:
            for row in csv.DictReader(handle):
                world = int(row["world"])
                if row["status"] != "ok" or (args.worlds is not None and world >= args.worlds):
                    continue
                found[(row["strategy"], row["field"], row["cut"])][world].append(row)
        for key, worlds in found.items():
            if key in by:
                raise SystemExit(f"RUN: {'/'.join(key)} is in more than one run")
            by[key] = worlds
    print(f"| combination | worlds | median pokes to {GOOD} | reach {GOOD} | final accuracy | "
          f"mean accuracy after 5 / 10 / 20 | median pokes to T_h | ended on another field | "
          f"fewer / more regions than true at the end |")
    print("|---|---|---|---|---|---|---|---|---|")
    for key in sorted(by):
        worlds = by[key]
        pokes, final, to_th = [], [], []
        acc: dict[int, list[float]] = {5: [], 10: [], 20: []}
        other = under = over = 0
        for rows in worlds.values():
            rows.sort(key=lambda r: int(r["poke"]))
            cap = int(rows[-1]["poke"]) + 1
            pokes.append(next((int(r["poke"]) for r in rows if float(r["accuracy"]) >= GOOD),
                              cap))
            to_th.append(next((int(r["poke"]) for r in rows if r["threshold"] == "True"), cap))
            final.append(float(rows[-1]["accuracy"]))
            for k in acc:
                if len(rows) >= k:
                    acc[k].append(float(rows[k - 1]["accuracy"]))
            other += rows[-1]["map_field"] != key[1]
            under += int(rows[-1]["found"]) < int(rows[-1]["true"])
            over += int(rows[-1]["found"]) > int(rows[-1]["true"])
        n = len(worlds)
        reach = sum(p < c for p, c in zip(pokes, [int(r[-1]["poke"]) + 1
                                                   for r in worlds.values()], strict=True))
        means = " / ".join(f"{statistics.mean(v):.3f}" if v else "–" for v in acc.values())
        print(f"| {'/'.join(key)} | {n} | {statistics.median(pokes):g} | {reach / n:.0%} | "
              f"{statistics.median(final):.3f} | {means} | {statistics.median(to_th):g} | "
              f"{other} | {under / n:.0%} / {over / n:.0%} |")


if __name__ == "__main__":
    main()
