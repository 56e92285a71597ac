"""Strategies and cuts compared: region accuracy after every poke.

Each run explores one world to ``--max-pokes`` pokes with one strategy, then replays its pokes
one at a time into a fresh :class:`deformap.explore.Mapper` and scores every cut
(``isopleth``, ``nearest``, ``indicator-kriging``) against the world's ground truth after each
poke (:func:`deformap.eval.region_scores`). The strategies run with ``T_h`` lowered to 1e-9 so
that none stops before ``--max-pokes`` (``paper`` is then a random reachable cell); the poke at
which the map field's largest variance first fell under the default ``T_h`` is recorded too
(``t_h_poke``). ``planned+boundary`` is ``planned`` at the default ``T_h`` followed by boundary
pokes (the straddle score) up to ``--max-pokes``.

Worlds: the heterogeneous scenarios of the paper's Table I and ``--random-worlds`` worlds of
:func:`deformap.world.random_scenario` (generator seeded 0, 1, …), each with the run seeds
``--seeds``. One JSON per run in ``--out`` (a finished run is not redone); the summary is printed.

    PYTHONPATH=src python benchmarks/strategies.py --out /tmp/strategies --max-pokes 20
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from deformap.eval import region_scores
from deformap.explore import ExplorationConfig, Mapper, explore, map_regions
from deformap.run import run_generators
from deformap.world import SimulatedWorld, WorldConfig, load_scenario, random_scenario

CUTS = ("isopleth", "nearest", "indicator-kriging")
STRATEGIES = ("paper", "planned", "level-set", "planned+boundary")
TABLE_I = ("heterogeneous-60-150", "heterogeneous-110-150", "heterogeneous-150-rigid",
           "heterogeneous-60-110-rigid")


def _config(strategy: str, max_pokes: int) -> ExplorationConfig:
    if strategy == "planned+boundary":
        return ExplorationConfig(strategy="planned", max_pokes=max_pokes,
                                 boundary_pokes=max_pokes)
    return ExplorationConfig(strategy=strategy, max_pokes=max_pokes,  # type: ignore[arg-type]
                             threshold=1e-9)


def _scores(world: SimulatedWorld, mapper: Mapper) -> dict[str, Any]:
    xs, ys = mapper.grid.xs, mapper.grid.ys
    truth = world.ground_truth_labels(xs, ys)
    grid_h = world.ground_truth_hardness(xs, ys)
    hardness = {int(k): float(grid_h[truth == k][0]) for k in np.unique(truth)}
    field = mapper.map_field
    sign = -1.0 if field.name == "modulus" else 1.0
    out: dict[str, Any] = {"max_variance": mapper.max_variance(), "field": field.name}
    for cut in CUTS:
        config = dataclasses.replace(mapper.config, region_labels=cut)
        found = map_regions(field.mean, field.pokes, mapper.grid.cells_xy, config, field.name)
        score = region_scores(found.labels, truth, sign * field.mean, hardness)
        out[cut] = {"accuracy": score.accuracy, "mean_iou": score.mean_iou,
                    "found": score.found, "true": score.true}
    return out


def run_one(name: str, scenario: Any, seed: int, strategy: str, max_pokes: int) -> dict[str, Any]:
    world_rng, explore_rng = run_generators(seed)
    world = SimulatedWorld(scenario, config=WorldConfig(), rng=world_rng)
    config = _config(strategy, max_pokes)
    t0 = time.perf_counter()
    result = explore(world, config, rng=explore_rng)
    seconds = time.perf_counter() - t0
    mapper = Mapper(world.workspace, config)
    default_th = ExplorationConfig().threshold
    curve, t_h_poke = [], None
    for poke in result.pokes:
        mapper.add(poke)
        row = _scores(world, mapper)
        ratio = mapper.threshold / config.threshold  # the field's T_h over the β T_h asked
        if t_h_poke is None and row["max_variance"] <= default_th * ratio:
            t_h_poke = len(mapper.pokes)
        curve.append(row)
    return {"world": name, "seed": seed, "strategy": strategy, "seconds": seconds,
            "targets": [p.record.contact_xy for p in result.pokes], "t_h_poke": t_h_poke,
            "curve": curve}


def _accuracy(run: dict[str, Any], cut: str, max_pokes: int) -> np.ndarray:
    """Accuracy after each poke, the last one held to ``max_pokes`` (a run that stopped)."""
    acc = [c[cut]["accuracy"] for c in run["curve"]]
    return np.array(acc + acc[-1:] * (max_pokes - len(acc)))


def _summary(runs: list[dict[str, Any]], max_pokes: int, goal: float) -> None:
    """A markdown table: per strategy and cut, over the runs, the median pokes to ``goal`` (a run
    that never reaches it counts ``max_pokes + 1``), how many reach it, and the accuracy after 5,
    10 and ``max_pokes`` pokes (median, min)."""
    at = sorted(k for k in {5, 10, max_pokes} if k <= max_pokes)
    print(f"| strategy | cut | runs | median pokes to {goal} | runs reaching {goal} | "
          + " | ".join(f"accuracy at {k}: median (min)" for k in at) + " |")
    print("|---|---|---|---|---|" + "---|" * len(at))
    for strategy in STRATEGIES:
        mine = [r for r in runs if r["strategy"] == strategy]
        if not mine:
            continue
        for cut in CUTS:
            acc = np.array([_accuracy(r, cut, max_pokes) for r in mine])
            reach = [int(np.argmax(a >= goal)) + 1 if np.any(a >= goal) else max_pokes + 1
                     for a in acc]
            cells = " | ".join(f"{np.median(acc[:, k - 1]):.3f} ({acc[:, k - 1].min():.3f})"
                               for k in at)
            print(f"| {strategy} | {cut} | {len(mine)} | {np.median(reach):g} | "
                  f"{sum(r <= max_pokes for r in reach)} | {cells} |")
    print()
    for strategy in STRATEGIES:
        mine = [r for r in runs if r["strategy"] == strategy]
        if mine:
            th = [r["t_h_poke"] or max_pokes + 1 for r in mine]
            seconds = np.median([r["seconds"] for r in mine])
            print(f"{strategy}: the default T_h reached after {np.median(th):g} pokes (median; "
                  f"range {min(th)}–{max(th)}); run time {seconds:.0f} s (median)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--max-pokes", type=int, default=20)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--random-worlds", type=int, default=2)
    parser.add_argument("--strategies", nargs="+", default=list(STRATEGIES))
    parser.add_argument("--goal", type=float, default=0.9)
    parser.add_argument("--summary-only", action="store_true")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    worlds = [(name, load_scenario(name)) for name in TABLE_I]
    worlds += [(f"random-{i}", random_scenario(np.random.default_rng(i)))
               for i in range(args.random_worlds)]
    if not args.summary_only:
        for name, scenario in worlds:
            for seed in args.seeds:
                for strategy in args.strategies:
                    path = args.out / f"{name}-s{seed}-{strategy}.json"
                    if path.exists():
                        continue
                    run = run_one(name, scenario, seed, strategy, args.max_pokes)
                    path.write_text(json.dumps(run))
                    last = run["curve"][-1]
                    print(f"{path.name}: {run['seconds']:.0f} s, final "
                          + ", ".join(f"{c} {last[c]['accuracy']:.3f}" for c in CUTS), flush=True)
    runs = [json.loads(p.read_text()) for p in sorted(args.out.glob("*.json"))]
    _summary(runs, args.max_pokes, args.goal)


if __name__ == "__main__":
    main()
