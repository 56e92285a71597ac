"""One table over the combinations of one or more ``deformap bench worlds`` runs.

    PYTHONPATH=src python benchmarks/worlds_table.py RUN [RUN ...] [--worlds N]

Reads each run's worlds (a ``bench worlds`` or ``bench rescore`` folder) and prints, per
strategy/field/cut over the worlds below ``--worlds`` (default: all), what the results' tables
show beyond ``summary.md``: the median pokes to region accuracy 0.9 (with its
95 % bootstrap interval) and their mean, the share reaching it and the median final accuracy
(``summary.json``'s, :func:`deformap.eval.summarise_worlds`: a world never there, or failed,
counts ``max_pokes + 1``), the mean accuracy
after 5 / 10 / 20 pokes (:func:`deformap.eval.accuracy_curves`: a run that stopped early keeps
its last map), the median pokes until the map field's variance was under ``T_h``
(``max_pokes + 1`` when never), how many runs ended mapped on another field than asked (a modulus
run gone to β), the share of worlds with fewer / more regions than true after the last poke, and
the failed worlds. Two runs of the same worlds may be put side by side (say, the modulus field of
one and the β-field of another); a combination found in two runs is refused.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

import numpy as np

from deformap.errors import ConfigError
from deformap.eval import (
    GOOD_ACCURACY,
    WorldResult,
    accuracy_curves,
    combination_name,
    summarise_worlds,
)
from deformap.run import WorldsBenchConfig, load_worlds


def _read(run: Path, below: int | None) -> tuple[WorldsBenchConfig, list[WorldResult]]:
    """``run``'s settings and its worlds' results (those numbered below ``below``)."""
    try:
        config, results = load_worlds(run)
    except ConfigError as exc:
        raise SystemExit(f"RUN: {exc}") from None
    results = [r for r in results if below is None or r.index < below]
    if not results:
        raise SystemExit(f"RUN: expected finished worlds in {run}; got none")
    return config, results


def _ends(results: list[WorldResult], combination: tuple[str, str, str], max_pokes: int
          ) -> tuple[list[int], int, int, int]:
    """Per finished world, the pokes to ``T_h``; and how many ended on another field, with fewer
    regions than true, with more."""
    to_th, other, under, over = [], 0, 0, 0
    for result in results:
        if result.status != "ok":
            continue
        rows = sorted((r for r in result.rows
                       if (r["strategy"], r["field"], r["cut"]) == combination),
                      key=lambda r: r["poke"])
        to_th.append(next((r["poke"] for r in rows if r["threshold"]), max_pokes + 1))
        last = rows[-1]
        other += last["map_field"] != combination[1]
        under += last["found"] < last["true"]
        over += last["found"] > last["true"]
    return to_th, other, under, over


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", type=Path, nargs="+", help="bench worlds folders")
    parser.add_argument("--worlds", type=int, help="only the worlds numbered below this")
    args = parser.parse_args()
    seen: set[tuple[str, str, str]] = set()
    lines = []
    for run in args.runs:
        config, results = _read(run, args.worlds)
        k = config.max_pokes
        combos = config.combinations()
        if seen & set(combos):
            raise SystemExit(f"RUN: {'/'.join(sorted(seen & set(combos))[0])} is in more than "
                             f"one run")
        seen |= set(combos)
        summary = summarise_worlds(results, combos, k)["strategies"]
        curves = accuracy_curves(results, combos, k)["all"]
        for combo in combos:
            name = combination_name(*combo)
            s, acc = summary[name], curves[name]
            means = " / ".join(f"{np.mean(acc[:, p - 1]):.3f}" if p <= k and len(acc) else "–"
                               for p in (5, 10, 20))
            to_th, other, under, over = _ends(results, combo, k)
            n = s["worlds"]
            low, high = s["median_pokes_ci95"]
            lines.append((name, f"| {name} | {n} | {s['median_pokes_to_accuracy_0.9']:g} "
                                f"({low:g}–{high:g}) | {s['mean_pokes_to_accuracy_0.9']:.1f} | "
                                f"{s['share_reaching_0.9']:.0%} | "
                                f"{s['final_accuracy_median'] or float('nan'):.3f} | {means} | "
                                f"{statistics.median(to_th) if to_th else float('nan'):g} | "
                                f"{other} | {under / n:.0%} / {over / n:.0%} | {s['failed']} |"))
    print(f"| combination | worlds | median pokes to {GOOD_ACCURACY} (95 % interval) | mean "
          f"pokes to {GOOD_ACCURACY} | reach {GOOD_ACCURACY} | final accuracy | mean accuracy "
          f"after 5 / 10 / 20 | median pokes to T_h | ended on another field | fewer / more "
          f"regions than true at the end | failed |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for _, line in sorted(lines):
        print(line)


if __name__ == "__main__":
    main()
