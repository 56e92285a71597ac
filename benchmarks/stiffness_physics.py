"""Young's modulus read from noise-free force–travel records under each of the world's contact
physics, with the second physics' stiffening switched on and off: separates what the estimator
misreads because a foam stiffens from what it misreads because the physics is not an elastic
continuum at all.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/stiffness_physics.py \
        [--hardness 30 60 110 150 250] [--thickness 0.05] [--force 0.6] [--physics NAME ...]

Rows: ``linear-fem`` (3-D linear elasticity, the baseline measured in the same run),
``stiffening-foam`` with ``stiffening_exponent`` 0 (the Vlasov layer, linear: only its restricted
kinematics differ from elasticity) and 1 (the default: it also stiffens toward densification), and
``stiffening-fem`` (the same FEM as ``linear-fem``, of a foam that stiffens toward densification;
with exponent 0 it is ``linear-fem`` exactly, so its row is the stiffening's effect alone).
Each foam is a block over the default workspace, pressed once at its centre with every noise
source off; the record is read by ``deformap.stiffness.estimate_stiffness`` against the world's own
small-strain modulus.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from stiffness_mesh import block_scenario  # this folder's: the same block

from deformap.errors import InvalidArgumentError
from deformap.stiffness import estimate_stiffness
from deformap.world import SimulatedWorld, WorldConfig

CASES = (("linear-fem", 1.0), ("stiffening-foam", 0.0), ("stiffening-foam", 1.0),
         ("stiffening-fem", 1.0))


def block_world(hardness_n: float, thickness_m: float, physics: str,
                exponent: float) -> SimulatedWorld:
    scenario = block_scenario(hardness_n, thickness_m)
    config = WorldConfig(physics=physics, stiffening_exponent=exponent,  # type: ignore[arg-type]
                         noise=False)
    return SimulatedWorld(scenario, config=config, rng=np.random.default_rng(0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hardness", type=float, nargs="+",
                        default=[30.0, 60.0, 110.0, 150.0, 250.0])
    parser.add_argument("--thickness", type=float, default=0.05)
    parser.add_argument("--force", type=float, default=0.6)
    parser.add_argument("--physics", nargs="+", default=sorted({p for p, _ in CASES}),
                        help="Only the rows of these physics.")
    args = parser.parse_args()
    print(f"{'physics':>16} {'exponent':>8} {'foam [N]':>8} {'depth [mm]':>10} "
          f"{'E read [kPa]':>12} {'world E [kPa]':>13} {'error':>7} {'build+press [s]':>15}")
    for physics, exponent in CASES:
        if physics not in args.physics:
            continue
        for hardness in args.hardness:
            start = time.perf_counter()
            world = block_world(hardness, args.thickness, physics, exponent)
            center = np.asarray(world.workspace.center, dtype=float)[:2]
            record = world.force_travel(center, args.force)
            elapsed = time.perf_counter() - start
            assert record is not None
            true = world.scenario.blocks[0].modulus_pa
            try:
                est = estimate_stiffness(record.travel_m, record.force_n,
                                         tip_radius_m=world.config.tip_radius_m,
                                         thickness_m=args.thickness,
                                         commanded_force_n=args.force)
                read = "rigid" if est.modulus_pa is None else f"{est.modulus_pa / 1e3:.2f}"
                err = "" if est.modulus_pa is None else f"{est.modulus_pa / true - 1:+.1%}"
            except InvalidArgumentError as error:  # out of the contact model's range
                read, err = "refused", str(error)[:40]
            print(f"{physics:>16} {exponent:>8g} {hardness:>8g} "
                  f"{record.travel_m[-1] * 1e3:>10.2f} {read:>12} {true / 1e3:>13.2f} {err:>7} "
                  f"{elapsed:>15.1f}", flush=True)


if __name__ == "__main__":
    main()
