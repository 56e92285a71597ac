"""What reading one force–travel record costs: ``deformap.stiffness.estimate_stiffness`` with its
default contact models (with and without a dent from the camera) against the bonded layer alone,
timed in the same run.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/stiffness_cost.py [--repeat 20]

The record is one noisy press at the centre of a 5 cm block of 60 N foam (the world's default
physics); the dent is the half-space's surface about that press at the read depth, sampled on a
1 mm grid out to 15 mm, with 0.3 mm of noise. Each row is the median over ``--repeat`` calls.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
from stiffness_mesh import block_scenario  # this folder's: the same block

from deformap.stiffness import DentSamples, StiffnessConfig, estimate_stiffness
from deformap.world import SimulatedWorld, WorldConfig

THICKNESS_M = 0.05


def _dent(depth: float, radius: float, rng: np.random.Generator) -> DentSamples:
    grid = np.arange(-0.015, 0.0151, 0.001)
    xy = np.stack(np.meshgrid(grid, grid), axis=-1).reshape(-1, 2)
    r = np.hypot(xy[:, 0], xy[:, 1])
    a = np.sqrt(radius * depth)
    rho = np.maximum(r / a, 1.0)
    outside = depth / np.pi * ((2.0 - rho**2) * np.arcsin(1.0 / rho) + np.sqrt(rho**2 - 1.0))
    sink = np.where(r <= a, depth - r * r / (2.0 * radius), outside)
    return DentSamples.of(xy, sink + rng.normal(0.0, 3e-4, r.size), 0.003)


def _median_time(call: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    world = SimulatedWorld(block_scenario(60.0, THICKNESS_M), config=WorldConfig(),
                           rng=np.random.default_rng(0))
    center = np.asarray(world.workspace.center, dtype=float)[:2]
    record = world.force_travel(center, 0.6)
    assert record is not None
    radius = world.config.tip_radius_m
    dent = _dent(float(record.travel_m[-1]), radius, np.random.default_rng(1))
    rows = (("bonded layer only", StiffnessConfig(contact_models=("bonded-layer",)), None),
            ("default models", StiffnessConfig(), None),
            ("default models + dent", StiffnessConfig(), dent))
    print(f"{'case':>22} {'median [s]':>10} {'E [kPa]':>8}")
    for name, config, samples in rows:
        def call(config: StiffnessConfig = config, samples: DentSamples | None = samples) -> object:
            return estimate_stiffness(record.travel_m, record.force_n, tip_radius_m=radius,
                                      thickness_m=THICKNESS_M, thickness_std_m=0.002,
                                      commanded_force_n=0.6, config=config, dent=samples)
        est = call()
        modulus = getattr(est, "modulus_pa", None)
        shown = "rigid" if modulus is None else f"{modulus / 1e3:.2f}"
        print(f"{name:>22} {_median_time(call, args.repeat):>10.4f} {shown:>8}", flush=True)


if __name__ == "__main__":
    main()
