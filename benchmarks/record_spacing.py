"""How the spacing of the simulated force–travel record's samples changes what the estimator can
read: evenly in force (``WorldConfig.force_travel_spacing = "force"``) against evenly in travel
(``"travel"``), on the same presses, in the many-worlds benchmark's random worlds.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/record_spacing.py \
        [--worlds 12] [--seed 0] [--presses 8] [--physics linear-fem]

Each world is ``deformap.eval.draw_world(seed, i)`` (its layout, camera, thickness and force, the
default mesh; its own noise seed, not the benchmark's), built once; ``--presses`` places drawn
uniformly over its foam blocks are pressed with the world's force, and each press's record, solved
once per spacing (the same noise stream), is read by ``deformap.stiffness.estimate_stiffness`` with
the block's true thickness (the record alone: the surface model's thickness error is left out).
A row per spacing: records read, refused (by reason), the median relative error of E against the
block's modulus and the share within its claimed 2σ, over the records it read and over the
presses both spacings read (the like-for-like comparison: a spacing that refuses the hard
presses would look better on its own reads). A refused record leaves its poke to the camera, and
two at one place make a map on the modulus field fall back to β (``deformap.explore.Mapper``).
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import time
from collections import Counter

import numpy as np

from deformap.errors import DeformapError
from deformap.eval import draw_world
from deformap.stiffness import estimate_stiffness
from deformap.world import SimulatedWorld, WorldConfig, camera_preset

SPACINGS = ("force", "travel")


def reason(message: str) -> str:
    """A refusal's kind, without its numbers."""
    if "diameter" in message:
        return "tip buried (> 2R)"
    if "sample(s) lie within" in message:
        return "< 3 samples within R"
    if "χ" in message:
        return "too deep for the layer"
    return re.sub(r"[-+]?\d[\d.e-]*", "#", message)[:60]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--presses", type=int, default=8)
    parser.add_argument("--physics", default="linear-fem")
    args = parser.parse_args()
    rows: dict[str, dict[int, tuple[float, float]]] = {s: {} for s in SPACINGS}
    refused: dict[str, Counter[str]] = {s: Counter() for s in SPACINGS}
    t0 = time.perf_counter()
    n_presses = 0
    for index in range(args.worlds):
        draw = draw_world(args.seed, index, physics=(args.physics,))
        config = dataclasses.replace(WorldConfig(physics=draw.physics),
                                     camera=camera_preset(draw.camera))
        world = SimulatedWorld(draw.scenario, config=config,
                               rng=np.random.default_rng([args.seed, index]))
        rng = np.random.default_rng([args.seed, index, 7])
        lo, hi = np.asarray(world.workspace.lower), np.asarray(world.workspace.upper)
        places = []
        while len(places) < args.presses:
            xy = lo + (hi - lo) * rng.random(2)
            label = int(draw.scenario.labels(xy[:1], xy[1:])[0, 0])
            if label >= 0 and not draw.scenario.blocks[label].rigid:
                places.append((xy, draw.scenario.blocks[label]))
        for xy, block in places:
            dent = world.dent(xy, draw.force_n)
            n_presses += 1
            for spacing in SPACINGS:
                world.config = dataclasses.replace(config, force_travel_spacing=spacing)
                record = world.force_travel(xy, draw.force_n, dent)
                if record is None:
                    refused[spacing]["no record (world)"] += 1
                    continue
                try:
                    est = estimate_stiffness(record.travel_m, record.force_n,
                                             tip_radius_m=config.tip_radius_m,
                                             thickness_m=block.thickness_m,
                                             commanded_force_n=draw.force_n)
                except DeformapError as exc:
                    refused[spacing][reason(str(exc))] += 1
                    continue
                if est.rigid or est.modulus_pa is None or est.modulus_std_pa is None:
                    refused[spacing]["read as rigid"] += 1
                    continue
                error = est.modulus_pa / block.modulus_pa - 1.0
                rows[spacing][n_presses] = (error, est.modulus_std_pa / block.modulus_pa)
        world.config = config
    print(f"{n_presses} presses on {args.worlds} worlds (seed {args.seed}, {args.physics}), "
          f"{time.perf_counter() - t0:.0f} s")
    both = set.intersection(*(set(rows[s]) for s in SPACINGS))
    print(f"{'spacing':>8} {'read':>6} {'refused':>8} {'median |E err|':>15} {'within 2σ':>10} "
          f"{'on both (' + str(len(both)) + ')':>22}   refusals")
    for spacing in SPACINGS:
        own = _stats(list(rows[spacing].values()))
        shared = _stats([rows[spacing][k] for k in sorted(both)])
        why = ", ".join(f"{k}: {v}" for k, v in refused[spacing].most_common())
        print(f"{spacing:>8} {len(rows[spacing]):>6} {sum(refused[spacing].values()):>8} "
              f"{own[0]:>15.1%} {own[1]:>10.1%} {shared[0]:>12.1%} / {shared[1]:>6.1%}   {why}")


def _stats(read: list[tuple[float, float]]) -> tuple[float, float]:
    """Median |relative E error| and the share within the claimed 2σ (NaN for none)."""
    if not read:
        return float("nan"), float("nan")
    got = np.array(read)
    return (float(np.median(np.abs(got[:, 0]))),
            float(np.mean(np.abs(got[:, 0]) <= 2.0 * got[:, 1])))


if __name__ == "__main__":
    main()
