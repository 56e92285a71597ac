"""Young's modulus read from noise-free force–travel records of the simulated world, against the
world's FEM mesh size: separates the estimator's error from the world's discretisation.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/stiffness_mesh.py \
        [--hardness 150 250] [--element-size 0.0075 0.00375] [--force 0.6] [--thickness 0.05]

For each foam (a 5 cm block over the default workspace) and each in-plane element size, the world
is built with every noise source off, pressed once at the workspace's centre, and its force–travel
record read by ``deformap.stiffness.estimate_stiffness``. The baseline in each row is the world's own
material modulus; the dent depth shows how far the FEM's press has converged (a finer mesh lets
the tip sink deeper: a coarse mesh is too stiff on a contact patch smaller than its elements).
A finer mesh costs much more: 3.75 mm elements have about 5 times the unknowns of 7.5 mm ones.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from deformap.environment import Workspace
from deformap.stiffness import estimate_stiffness
from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig


def block_scenario(hardness_n: float, thickness_m: float) -> Scenario:
    """One foam block ``thickness_m`` thick over the default workspace."""
    ws = Workspace()
    (x0, y0), (x1, y1) = ws.lower, ws.upper
    polygon = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    block = Block(name=f"{hardness_n:g} N foam", polygon=polygon, hardness_n=hardness_n,
                  thickness_m=thickness_m)
    return Scenario(name=f"homogeneous-{hardness_n:g}", blocks=(block,), workspace=ws)


def block_world(hardness_n: float, element_size_m: float, thickness_m: float) -> SimulatedWorld:
    scenario = block_scenario(hardness_n, thickness_m)
    config = WorldConfig(element_size_m=element_size_m,
                         top_layer_m=min(WorldConfig().top_layer_m, element_size_m), noise=False)
    return SimulatedWorld(scenario, config=config, rng=np.random.default_rng(0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hardness", type=float, nargs="+", default=[60.0, 150.0, 250.0])
    parser.add_argument("--element-size", type=float, nargs="+", default=[0.0075, 0.00375])
    parser.add_argument("--force", type=float, default=0.6)
    parser.add_argument("--thickness", type=float, default=0.05)
    args = parser.parse_args()
    print(f"{'foam [N]':>8} {'element [mm]':>12} {'unknowns':>9} {'depth [mm]':>10} "
          f"{'E read [kPa]':>12} {'world E [kPa]':>13} {'error':>7} {'build+press [s]':>15}")
    for hardness in args.hardness:
        for size in args.element_size:
            start = time.perf_counter()
            world = block_world(hardness, size, args.thickness)
            center = np.asarray(world.workspace.center, dtype=float)[:2]
            record = world.force_travel(center, args.force)
            elapsed = time.perf_counter() - start
            assert record is not None
            est = estimate_stiffness(record.travel_m, record.force_n,
                                     tip_radius_m=world.config.tip_radius_m,
                                     thickness_m=args.thickness, commanded_force_n=args.force)
            true = world.scenario.blocks[0].modulus_pa
            read = "rigid" if est.modulus_pa is None else f"{est.modulus_pa / 1e3:.2f}"
            err = "" if est.modulus_pa is None else f"{est.modulus_pa / true - 1:+.1%}"
            print(f"{hardness:>8g} {size * 1e3:>12.2f} {world.n_dofs:>9d} "
                  f"{record.travel_m[-1] * 1e3:>10.2f} {read:>12} {true / 1e3:>13.2f} {err:>7} "
                  f"{elapsed:>15.1f}", flush=True)


if __name__ == "__main__":
    main()
