"""One table over the combinations of one or more ``deformap bench worlds`` runs (issue 16).

    PYTHONPATH=src python benchmarks/worlds_table.py RUN [RUN ...] [--worlds N]

Reads each run's ``runs.csv`` (a ``bench worlds`` or ``bench rescore`` folder) and prints, per
strategy/field/cut over the worlds below ``--worlds`` (default: all), what the README's "Many
worlds" tables show beyond ``summary.md``: the median pokes to region accuracy 0.9 (a world never
there counts ``max_pokes + 1``, as ``summary.json``), the share reaching it, the median final
accuracy, the mean accuracy after 5 / 10 / 20 pokes (a run that stopped early keeping its last
map), the median pokes until the map field's variance was under ``T_h`` (``max_pokes + 1`` when
never), how many runs ended mapped on another field than asked (a modulus run gone to β), the
share of worlds with fewer / more regions than true after the last poke, and the failed worlds
(each counted ``max_pokes + 1`` in the pokes, as ``summary.json``). Two runs of the same worlds
may be put side by side (say, the modulus field of one and the β-field of another); a combination
found in two runs is refused.
"""

from __future__ import annotations

import argparse
import csv
import json
import statistics
from collections import defaultdict
from pathlib import Path

GOOD = 0.9


def _read(run: Path, below: int | None) -> tuple[int, dict[tuple[str, str, str],
                                                           dict[int, list[dict[str, str]]]],
                                                  dict[tuple[str, str, str], int]]:
    """``run``'s ``max_pokes``, its finished rows by combination and world, and its failed worlds
    by combination."""
    try:
        max_pokes = int(json.loads((run / "bench.json").read_text(encoding="utf-8"))[
            "settings"]["max_pokes"])
        with (run / "runs.csv").open(encoding="utf-8", newline="") as handle:
            rows = list(csv.DictReader(handle))
        columns = {"world", "status", "strategy", "field", "cut", "poke", "accuracy", "found",
                   "true", "threshold", "map_field"}
        if rows and not columns <= set(rows[0]):
            raise KeyError(f"columns {sorted(columns - set(rows[0]))}")
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise SystemExit(f"RUN: expected a bench worlds folder with bench.json and runs.csv; got "
                         f"{run} ({exc})") from None
    found: dict[tuple[str, str, str], dict[int, list[dict[str, str]]]] = defaultdict(
        lambda: defaultdict(list))
    failed: dict[tuple[str, str, str], int] = defaultdict(int)
    for row in rows:
        world, key = int(row["world"]), (row["strategy"], row["field"], row["cut"])
        if below is not None and world >= below:
            continue
        if row["status"] != "ok":
            failed[key] += 1
        else:
            found[key][world].append(row)
    return max_pokes, found, failed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", type=Path, nargs="+", help="bench worlds folders")
    parser.add_argument("--worlds", type=int, help="only the worlds numbered below this")
    args = parser.parse_args()
    by: dict[tuple[str, str, str], tuple[int, dict[int, list[dict[str, str]]], int]] = {}
    for run in args.runs:
        max_pokes, found, failed = _read(run, args.worlds)
        for key in {*found, *failed}:
            if key in by:
                raise SystemExit(f"RUN: {'/'.join(key)} is in more than one run")
            by[key] = (max_pokes, found.get(key, {}), failed.get(key, 0))
    print(f"| combination | worlds | median pokes to {GOOD} | reach {GOOD} | final accuracy | "
          f"mean accuracy after 5 / 10 / 20 | median pokes to T_h | ended on another field | "
          f"fewer / more regions than true at the end | failed |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for key in sorted(by):
        max_pokes, worlds, n_failed = by[key]
        never = max_pokes + 1  # as summary.json: a world never there, or failed
        pokes, final, to_th = [never] * n_failed, [], []
        acc: dict[int, list[float]] = {5: [], 10: [], 20: []}
        other = under = over = 0
        for rows in worlds.values():
            rows.sort(key=lambda r: int(r["poke"]))
            pokes.append(next((int(r["poke"]) for r in rows if float(r["accuracy"]) >= GOOD),
                              never))
            to_th.append(next((int(r["poke"]) for r in rows if r["threshold"] == "True"), never))
            final.append(float(rows[-1]["accuracy"]))
            for k in acc:  # a run that stopped early keeps its last map
                upto = [r for r in rows if int(r["poke"]) <= k]
                if upto and k <= max_pokes:
                    acc[k].append(float(upto[-1]["accuracy"]))
            other += rows[-1]["map_field"] != key[1]
            under += int(rows[-1]["found"]) < int(rows[-1]["true"])
            over += int(rows[-1]["found"]) > int(rows[-1]["true"])
        n = len(worlds) + n_failed
        if not n:
            continue
        reach = sum(p <= max_pokes for p in pokes)
        means = " / ".join(f"{statistics.mean(v):.3f}" if v else "–" for v in acc.values())
        fin = f"{statistics.median(final):.3f}" if final else "–"
        th = f"{statistics.median(to_th):g}" if to_th else "–"
        print(f"| {'/'.join(key)} | {n} | {statistics.median(pokes):g} | {reach / n:.0%} | "
              f"{fin} | {means} | {th} | {other} | {under / n:.0%} / {over / n:.0%} | "
              f"{n_failed} |")


if __name__ == "__main__":
    main()
