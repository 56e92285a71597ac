"""How few pokes a good map could take: pokes placed knowing the layout, cut by nearest poke.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/oracle_placement.py [--worlds 100]
        [--seed 0] [--max-pokes 20] [--run RUN] [--placements layout,maximin,boundary]

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

Two more placements read every poke perfectly too (the class of the material under it) but do
not know the layout, as a strategy does not: what better readings alone could give.

- ``maximin``: each poke at the candidate farthest from every poke so far (a space-filling design
  that ignores what the pokes read).
- ``boundary``: four maximin pokes, then each at the candidate with the highest nearest-poke
  boundary score ``d₁ − 2 (d₂ − d₁)`` (``d₁`` the distance to the nearest poke, ``d₂`` to the
  nearest poke of another class: far from every poke and close to where the map's classes
  meet; while all pokes read one class, maximin). Of the five variants tried on the 100 default
  worlds of seed 0 (1 or 4 or 6 maximin pokes first, weight 0.5, 1 or 2), this one needed the
  fewest pokes: an optimistic bound for such a rule, chosen on the worlds it is measured on.

With ``--run``, a bench worlds folder of the same seed and families, it prints beside the oracle
the run's own medians per combination (its ``nearest`` cut), as the baseline on the same worlds.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace
from pathlib import Path
from typing import Any

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from deformap.errors import ConfigError  # noqa: E402
from deformap.eval import (  # noqa: E402
    WorldResult,
    WorldTask,
    material_truth,
    region_scores,
    summarise_worlds,
)
from deformap.explore import MapGrid  # noqa: E402
from deformap.run import load_worlds  # noqa: E402
from deformap.world import LAYOUT_FAMILIES  # noqa: E402

GOOD = 0.9


PLACEMENTS = ("layout", "maximin", "boundary")
BOUNDARY_FIRST = 4  # maximin pokes before the boundary score
BOUNDARY_WEIGHT = 2.0


def _world(task: WorldTask) -> tuple[Any, NDArray[np.int64], Any, Any, NDArray[np.float64],
                                          NDArray[np.float64], NDArray[np.float64],
                                          NDArray[np.int64]]:
    """The world's draw, its true labels on the grid (and as the grid's shape), its hardness, the
    grid's cells, the planner's candidates, their distances ``(c, n)`` to the cells and the
    material under each candidate."""
    draw = task.draw()
    grid = MapGrid.build(draw.scenario.workspace, task.exploration_for(draw))
    labels, hardness, _ = material_truth(draw.scenario, grid.xs, grid.ys)
    truth = labels.reshape(-1)
    cells = grid.cells_xy
    candidates = grid.plan_candidates
    dist = np.hypot(*(cells[None, :, :] - candidates[:, None, :]).transpose(2, 0, 1))  # (c, n)
    return draw, truth, labels, hardness, cells, candidates, dist, truth[np.argmin(dist, axis=1)]


def blind_curve(task: WorldTask, placement: str) -> tuple[str, list[float]]:
    """The world's family and the region accuracy after each of ``max_pokes`` pokes placed by
    ``maximin`` or ``boundary`` (module docstring), each read as the material under it."""
    draw, _, labels, hardness, _, candidates, dist, cand_label = _world(task)
    centre = np.asarray(draw.scenario.workspace.center, float)
    pokes = [int(np.argmin(np.hypot(*(candidates - centre).T)))]
    curve = []
    for _ in range(task.max_pokes):
        found = cand_label[pokes][np.argmin(dist[pokes], axis=0)].reshape(labels.shape)
        curve.append(region_scores(found, labels, found.astype(float), hardness).accuracy)
        apart = np.hypot(*(candidates[:, None, :] - candidates[None, pokes, :]).transpose(2, 0, 1))
        d1 = apart.min(axis=1)
        own = cand_label[pokes][np.argmin(apart, axis=1)]
        other = np.where(cand_label[pokes][None, :] != own[:, None], apart, np.inf).min(axis=1)
        score = d1.copy()
        if placement == "boundary" and len(pokes) >= BOUNDARY_FIRST and np.isfinite(other).any():
            # a candidate with no other class in sight ranks below every one that has
            score = np.where(np.isfinite(other), d1 - BOUNDARY_WEIGHT * (other - d1),
                             d1 - 1e3)  # fmt: skip
        score[pokes] = -np.inf
        pokes.append(int(np.argmax(score)))
    return draw.family, curve


def greedy_curve(task: WorldTask) -> tuple[str, list[float]]:
    """The world's family and the region accuracy after each of ``max_pokes`` oracle pokes."""
    draw, truth, labels, hardness, cells, _, dist, cand_label = _world(task)

    def place(xy: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        d = np.hypot(*(cells - xy).T)
        return d, np.full(len(cells), truth[int(np.argmin(d))])

    near, label = place(np.asarray(draw.scenario.workspace.center, float))
    curve = []
    for _ in range(task.max_pokes):
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
    parser.add_argument("--placements", default="layout",
                        help=f"comma-separated, of {', '.join(PLACEMENTS)} (default layout)")
    args = parser.parse_args()
    if args.worlds < 1 or args.max_pokes < 1:
        raise SystemExit(f"--worlds, --max-pokes: expected integers >= 1; got {args.worlds}, "
                         f"{args.max_pokes}")
    placements = list(dict.fromkeys(p for p in args.placements.split(",") if p))
    if not placements or not set(placements) <= set(PLACEMENTS):
        raise SystemExit(f"--placements: expected some of {', '.join(PLACEMENTS)}; got "
                         f"{args.placements!r}")
    base = WorldTask(seed=args.seed, families=LAYOUT_FAMILIES, physics=("linear-fem",),
                     max_pokes=args.max_pokes)
    run = None
    if args.run is not None:
        try:
            run, stored = load_worlds(args.run)
        except ConfigError as exc:
            raise SystemExit(f"--run: {exc}") from None
        if run.seed != args.seed or "nearest" not in run.cuts:
            raise SystemExit(f"--run: expected a run of seed {args.seed} scored under the nearest "
                             f"cut; got seed {run.seed}, cuts {list(run.cuts)}")
        base = replace(base, families=run.families, physics=run.physics)
    results = []
    for index in range(args.worlds):
        task = replace(base, index=index)
        rows: list[dict[str, Any]] = []
        for placement in placements:
            family, curve = (greedy_curve(task) if placement == "layout"
                             else blind_curve(task, placement))
            rows += [{"appearance": "plain", "prior": "auto", "strategy": "oracle",
                      "field": placement, "cut": "nearest", "poke": k + 1, "accuracy": a,
                      "modulus_error": None} for k, a in enumerate(curve)]
        results.append(WorldResult(world={"index": index, "family": family}, rows=tuple(rows)))
    combos = [("oracle", placement, "nearest") for placement in placements]
    if run is not None:
        own = {r.index: [x for x in r.rows if x["cut"] == "nearest" and x["poke"] <= args.max_pokes]
               for r in stored if r.status == "ok" and r.index < args.worlds}
        if set(own) != set(range(args.worlds)):
            raise SystemExit(f"--run: expected worlds 0..{args.worlds - 1} finished; got "
                             f"{len(own)}")
        results = [replace(r, rows=(*r.rows, *own[r.index])) for r in results]
        combos += [(s, f, "nearest") for s in run.strategies for f in run.fields]
    summary = summarise_worlds(results, combos, args.max_pokes)["strategies"]
    names = sorted({f for s in summary.values() for f in s["by_family"]})
    print(f"{args.worlds} worlds of seed {args.seed}, {args.max_pokes} pokes; median pokes to "
          f"region accuracy {GOOD} (never: {args.max_pokes + 1}), the share reaching it, and the "
          f"mean accuracy after 5 / 10 / 20 pokes\n")
    print("| placement | median pokes (95 % interval) | mean pokes | reach | mean accuracy 5 / 10 "
          "/ 20 | " + " | ".join(names) + " |")
    print("|---|---|---|---|---|" + "---|" * len(names))
    labels = {"layout": "oracle (knows the layout)",
              "maximin": "maximin, perfect readings (no layout)",
              "boundary": "boundary score, perfect readings (no layout)"}
    for s, f, c in combos:
        entry = summary[f"{s}/{f}/{c}"]
        means = []
        for k in (5, 10, 20):
            acc = [x["accuracy"] for r in results for x in r.rows
                   if (x["strategy"], x["field"], x["cut"], x["poke"]) == (s, f, c, k)]
            means.append(f"{np.mean(acc):.3f}" if acc else "–")
        label = labels[f] if s == "oracle" else f"{s}/{f}"
        low, high = entry["median_pokes_ci95"]
        print(f"| {label} | {entry['median_pokes_to_accuracy_0.9']:g} ({low:g}–{high:g}) | "
              f"{entry['mean_pokes_to_accuracy_0.9']:.1f} | "
              f"{entry['share_reaching_0.9']:.0%} | {' / '.join(means)} | "
              + " | ".join(f"{entry['by_family'][n]['median_pokes_to_accuracy_0.9']:g}"
                           for n in names) + " |")


if __name__ == "__main__":
    main()
