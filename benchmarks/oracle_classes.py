"""What limits a worlds benchmark's maps: the classes found, or where the pokes went (issue 16).

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/oracle_classes.py RUN [--cut nearest]

``RUN`` is a folder written by ``deformap bench worlds`` (or ``bench rescore``) whose worlds stored
their pokes. For every strategy × field it scores, after every poke, the map an *oracle* would cut
from the same pokes: each poke given the class of the material under it (the world's layout,
read from its seed: nothing is pressed), every cell the class of its nearest poke. Beside it, as
the baseline measured on the same pokes and worlds, the run's own cut (``--cut``, default
``nearest``), read from its rows. The oracle's accuracy is what a perfect class test would reach
with these pokes and this cut; the gap to the run's is what the class test loses (materials
merged, seam presses split off), and what the oracle itself misses is where the pokes went (a
boundary between pokes placed no closer than their spacing allows).

The stored pokes are the field's own: for a run that fell back from the modulus field to β on
the way (``runs.csv``'s ``map_field``), the oracle sees the pokes that gave a modulus, not every
poke its map used. The table gives, per combination and per layout family, the median pokes to
region accuracy 0.9 (a world that never gets there counts ``max_pokes + 1``, as in
``summary.json``) and the share of worlds reaching it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from deformap.eval import region_scores, summarise_worlds
from deformap.eval._worlds import _draw, _material_truth
from deformap.explore import MapGrid


def _oracle_rows(task: dict[str, Any], result: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of the oracle cut (``cut`` "oracle") after every poke of every stored combination."""
    draw, explore = _draw(task)
    grid = MapGrid.build(draw.scenario.workspace, explore)
    labels, hardness, _ = _material_truth(draw.scenario, grid.xs, grid.ys)
    cells = grid.cells_xy
    under = cKDTree(cells)
    rows = []
    for combo, data in result["pokes"].items():
        strategy, field = combo.split("/")
        xy = np.column_stack([data["x"], data["y"]])
        index = np.asarray(data["index"], dtype=np.int64)
        truth_at_poke = labels.reshape(-1)[under.query(xy)[1]] if len(xy) else index
        for poke in range(1, task["max_pokes"] + 1):
            keep = index < poke
            if not keep.any():
                continue
            nearest = cKDTree(xy[keep]).query(cells)[1]
            found = truth_at_poke[keep][nearest].reshape(labels.shape)
            # the map's "values" order the found classes as the materials are ordered
            scores = region_scores(found, labels, found.astype(float), hardness)
            rows.append({"strategy": strategy, "field": field, "cut": "oracle", "poke": poke,
                         "accuracy": scores.accuracy, "modulus_error": None})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="a bench worlds folder with stored pokes")
    parser.add_argument("--cut", default="nearest", help="the run's cut shown beside the oracle")
    args = parser.parse_args()
    settings = json.loads((args.run / "bench.json").read_text(encoding="utf-8"))["settings"]
    if args.cut not in settings["cuts"]:
        raise SystemExit(f"--cut: expected one of the run's cuts {settings['cuts']}; "
                         f"got {args.cut!r}")
    results = []
    for path in sorted((args.run / "worlds").glob("world-*.json")):
        result = json.loads(path.read_text(encoding="utf-8"))
        if result.get("status") != "ok" or not isinstance(result.get("pokes"), dict):
            continue
        task = {"seed": settings["seed"], "index": result["world"]["index"],
                "families": settings["families"], "physics": settings["physics"],
                "max_pokes": settings["max_pokes"]}
        own = [r for r in result["rows"] if r["cut"] == args.cut]
        results.append({**result, "rows": own + _oracle_rows(task, result)})
    if not results:
        raise SystemExit(f"RUN: expected finished worlds with stored pokes in {args.run}; "
                         f"got none")
    k = settings["max_pokes"]
    combos = [(s, f, c) for s in settings["strategies"] for f in settings["fields"]
              for c in (args.cut, "oracle")]
    summary = summarise_worlds(results, combos, k)["strategies"]
    families = sorted({f for s in summary.values() for f in s["by_family"]})
    print(f"{len(results)} worlds of {args.run}, {k} pokes; median pokes to accuracy 0.9 "
          f"(never: {k + 1}) and the share of worlds reaching it\n")
    print("| strategy/field | classes | median pokes | reach | final accuracy | "
          + " | ".join(families) + " |")
    print("|---|---|---|---|---|" + "---|" * len(families))
    for strategy, field, cut in combos:
        s = summary[f"{strategy}/{field}/{cut}"]
        label = f"the run's ({cut})" if cut != "oracle" else "oracle (material under each poke)"
        by = " | ".join(f"{s['by_family'][f]['median_pokes_to_accuracy_0.9']:g}"
                        for f in families)
        print(f"| {strategy}/{field} | {label} | {s['median_pokes_to_accuracy_0.9']:g} | "
              f"{s['share_reaching_0.9']:.0%} | {s['final_accuracy_median']:.3f} | {by} |")


if __name__ == "__main__":
    main()
