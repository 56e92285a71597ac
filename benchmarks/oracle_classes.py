"""What limits a worlds benchmark's maps: the classes found, or where the pokes went.

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
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from deformap.errors import ConfigError
from deformap.eval import WorldResult, WorldTask, material_truth, region_scores, summarise_worlds
from deformap.explore import MapGrid
from deformap.run import load_worlds


def _oracle_rows(task: WorldTask, result: WorldResult) -> list[dict[str, Any]]:
    """Rows of the oracle cut (``cut`` "oracle") after every poke of every stored combination."""
    draw = task.draw()
    grid = MapGrid.build(draw.scenario.workspace, task.exploration_for(draw))
    labels, hardness, _ = material_truth(draw.scenario, grid.xs, grid.ys)
    cells = grid.cells_xy
    under = cKDTree(cells)
    rows = []
    for combo, data in result.pokes.items():
        appearance, prior, strategy, field = combo.split("/")  # WorldResult.run_key
        xy = np.column_stack([data["x"], data["y"]])
        index = np.asarray(data["index"], dtype=np.int64)
        truth_at_poke = labels.reshape(-1)[under.query(xy)[1]] if len(xy) else index
        for poke in range(1, task.max_pokes + 1):
            keep = index < poke
            if not keep.any():
                continue
            nearest = cKDTree(xy[keep]).query(cells)[1]
            found = truth_at_poke[keep][nearest].reshape(labels.shape)
            # the map's "values" order the found classes as the materials are ordered
            scores = region_scores(found, labels, found.astype(float), hardness)
            rows.append({"appearance": appearance, "prior": prior, "strategy": strategy,
                         "field": field, "cut": "oracle", "poke": poke,
                         "accuracy": scores.accuracy, "modulus_error": None})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="a bench worlds folder with stored pokes")
    parser.add_argument("--cut", default="nearest", help="the run's cut shown beside the oracle")
    args = parser.parse_args()
    try:
        config, stored = load_worlds(args.run)
    except ConfigError as exc:
        raise SystemExit(f"RUN: {exc}") from None
    if args.cut not in config.cuts:
        raise SystemExit(f"--cut: expected one of the run's cuts {list(config.cuts)}; "
                         f"got {args.cut!r}")
    results = []
    for result in stored:
        if result.status != "ok":
            continue
        own = [r for r in result.rows if r["cut"] == args.cut]
        oracle = _oracle_rows(config.task(result.index), result)
        results.append(replace(result, rows=(*own, *oracle)))
    if not results:
        raise SystemExit(f"RUN: expected finished worlds with stored pokes in {args.run}; "
                         f"got none")
    k = config.max_pokes
    combos = [(s, f, c) for s in config.strategies for f in config.fields
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
