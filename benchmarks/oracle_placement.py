"""How few pokes a good map could take: pokes placed knowing the layout, cut by nearest poke (issue 16).

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/oracle_placement.py [--worlds 100]
        [--seed 0] [--max-pokes 20] [--run RUN]

For each world of a ``deformap bench worlds`` seed (drawn from ``(seed, index)`` alone, as the
benchmark draws it; nothing is pressed) this places pokes as an oracle would: the first at the
workspace's centre, as every strategy's, then each where it raises the share of cells labelled as
their material most (the region accuracy before its label matching, which can only raise it), each
poke given the class of the material under it and every cell the class of its nearest poke (the
default cut). Candidates are the planner's 2 cm lattice of the cells a poke may be centred on.
A greedy placement is not the best placement, so its count is one that *can* be reached, not
the least: it says how far the strategies (which know nothing of the layout) are from what the
nearest-poke cut allows, and where the cut itself is the limit (a family the oracle too needs
many pokes for).

With ``--run``, a bench worlds folder of the same seed and families, it prints beside the oracle
the run's own medians per combination (its ``nearest`` cut), as the baseline on the same worlds.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from deformap.eval import region_scores, summarise_worlds  # noqa: E402
from deformap.eval._worlds import _draw, _material_truth  # noqa: E402
from deformap.explore import MapGrid  # noqa: E402
from deformap.world import LAYOUT_FAMILIES  # noqa: E402

GOOD = 0.9


def greedy_curve(task: dict[str, Any]) -> tuple[str, list[float]]:
    """The world's family and the region accuracy after each of ``max_pokes`` oracle pokes."""
    draw, explore = _draw(task)
    grid = MapGrid.build(draw.scenario.workspace, explore)
    labels, hardness, _ = _material_truth(draw.scenario, grid.xs, grid.ys)
    truth = labels.reshape(-1)
    cells = grid.cells_xy
    candidates = grid.plan_candidates
    dist = np.hypot(*(cells[None, :, :] - candidates[:, None, :]).transpose(2, 0, 1))  # (c, n)
    cand_label = truth[np.argmin(dist, axis=1)]  # the material under each candidate

    def place(xy: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        d = np.hypot(*(cells - xy).T)
        return d, np.full(len(cells), truth[int(np.argmin(d))])

    near, label = place(np.asarray(draw.scenario.workspace.center, float))
    curve = []
    for _ in range(int(task["max_pokes"])):
        found = label.reshape(labels.shape)
        curve.append(region_scores(found, labels, found.astype(float), hardness).accuracy)
        closer = dist < near[None, :]
        trial = np.where(closer, cand_label[:, None], label[None, :])
        best = int(np.argmax((trial == truth[None, :]).mean(axis=1)))
        near = np.minimum(near, dist[best])
        label = trial[best]
    return draw.family, curve


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", type=int, default=100, help="worlds 0 .. N-1 (default 100)")
    parser.add_argument("--seed", type=int, default=0, help="the benchmark's seed (default 0)")
    parser.add_argument("--max-pokes", type=int, default=20, help="pokes per world (default 20)")
    parser.add_argument("--run", type=Path, help="a bench worlds folder of the same seed")
    args = parser.parse_args()
    if args.worlds < 1 or args.max_pokes < 1:
        raise SystemExit(f"--worlds, --max-pokes: expected integers >= 1; got {args.worlds}, "
                         f"{args.max_pokes}")
    families, physics, run_rows = list(LAYOUT_FAMILIES), ["linear-fem"], None
    if args.run is not None:
        try:
            settings = json.loads((args.run / "bench.json").read_text(encoding="utf-8"))[
                "settings"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise SystemExit(f"--run: expected a bench worlds folder with its bench.json; got "
                             f"{args.run} ({exc})") from None
        if settings["seed"] != args.seed or "nearest" not in settings["cuts"]:
            raise SystemExit(f"--run: expected a run of seed {args.seed} scored under the nearest "
                             f"cut; got seed {settings['seed']}, cuts {settings['cuts']}")
        families, physics = settings["families"], settings["physics"]
        run_rows = settings
    results = []
    for index in range(args.worlds):
        task = {"seed": args.seed, "index": index, "families": families, "physics": physics,
                "max_pokes": args.max_pokes}
        family, curve = greedy_curve(task)
        rows = [{"strategy": "oracle", "field": "layout", "cut": "nearest", "poke": k + 1,
                 "accuracy": a, "modulus_error": None} for k, a in enumerate(curve)]
        results.append({"world": {"index": index, "family": family}, "rows": rows,
                        "status": "ok"})
    combos = [("oracle", "layout", "nearest")]
    if run_rows is not None:
        stored = {}
        for path in sorted((args.run / "worlds").glob("world-*.json")):
            try:
                r = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise SystemExit(f"--run: {path} cannot be read ({exc})") from None
            if r.get("status") == "ok" and r["world"]["index"] < args.worlds:
                stored[r["world"]["index"]] = [x for x in r["rows"] if x["cut"] == "nearest"
                                               and x["poke"] <= args.max_pokes]
        if set(stored) != set(range(args.worlds)):
            raise SystemExit(f"--run: expected worlds 0..{args.worlds - 1} finished; got "
                             f"{len(stored)}")
        for r in results:
            r["rows"] += stored[r["world"]["index"]]
        combos += [(s, f, "nearest") for s in run_rows["strategies"] for f in run_rows["fields"]]
    summary = summarise_worlds(results, combos, args.max_pokes)["strategies"]
    names = sorted({f for s in summary.values() for f in s["by_family"]})
    print(f"{args.worlds} worlds of seed {args.seed}, {args.max_pokes} pokes; median pokes to "
          f"region accuracy {GOOD} (never: {args.max_pokes + 1}), the share reaching it, and the "
          f"mean accuracy after 5 / 10 / 20 pokes\n")
    print("| placement | median pokes | reach | mean accuracy 5 / 10 / 20 | " + " | ".join(names)
          + " |")
    print("|---|---|---|---|" + "---|" * len(names))
    for s, f, c in combos:
        entry = summary[f"{s}/{f}/{c}"]
        means = []
        for k in (5, 10, 20):
            acc = [x["accuracy"] for r in results for x in r["rows"]
                   if (x["strategy"], x["field"], x["cut"], x["poke"]) == (s, f, c, k)]
            means.append(f"{np.mean(acc):.3f}" if acc else "–")
        label = "oracle (knows the layout)" if s == "oracle" else f"{s}/{f}"
        print(f"| {label} | {entry['median_pokes_to_accuracy_0.9']:g} | "
              f"{entry['share_reaching_0.9']:.0%} | {' / '.join(means)} | "
              + " | ".join(f"{entry['by_family'][n]['median_pokes_to_accuracy_0.9']:g}"
                           for n in names) + " |")


if __name__ == "__main__":
    main()
