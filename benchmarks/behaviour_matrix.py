"""What each press of a simulated world reveals beyond its stiffness, against the world's truth:
the behaviour class :func:`deformap.explore.poke_behaviour` reads from a press that holds its force
and unloads, per camera preset and foam thickness, on one table of three 60 N blocks (elastic;
viscoelastic, a standard linear solid with g∞ = 0.5 and τ = 1 s; plastic, yield 1 kPa, hardening
2 kPa). The baseline is the truth of each press, in the same run.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/behaviour_matrix.py \
        [--cameras primesense kinect-v1 realsense-d435] [--thickness 0.03 0.1] [--force 0.6]
"""

from __future__ import annotations

import argparse
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np
import yaml

from deformap.explore import poke_behaviour
from deformap.world import SimulatedWorld, WorldConfig, camera_preset, load_scenario

PRESSES = [((0.1, 0.2), "elastic"), ((0.05, 0.1), "elastic"), ((0.3, 0.2), "viscoelastic"),
           ((0.25, 0.3), "viscoelastic"), ((0.5, 0.2), "plastic"), ((0.55, 0.1), "plastic")]


def _scenario(thickness: float, folder: Path):  # type: ignore[no-untyped-def]
    blocks = [
        {"name": "elastic", "rect": [0, 0, 0.2, 0.4], "hardness_n": 60},
        {"name": "memory", "rect": [0.2, 0, 0.4, 0.4], "hardness_n": 60,
         "viscoelastic": {"relaxed_ratio": 0.5, "times_s": [1.0]}},
        {"name": "clay", "rect": [0.4, 0, 0.6, 0.4], "hardness_n": 60,
         "plastic": {"yield_stress_pa": 1000, "hardening_pa": 2000}},
    ]
    for block in blocks:
        block["thickness_m"] = thickness
    path = folder / f"mix-{thickness:g}.yaml"
    path.write_text(yaml.safe_dump({"name": "mix", "blocks": blocks}))
    return load_scenario(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cameras", nargs="+", default=["primesense", "kinect-v1", "realsense-d435"])
    parser.add_argument("--thickness", nargs="+", type=float, default=[0.03, 0.1])
    parser.add_argument("--force", type=float, default=0.6)
    args = parser.parse_args()
    counts: Counter[tuple[str, str]] = Counter()
    with tempfile.TemporaryDirectory() as tmp:
        for camera in args.cameras:
            for thickness in args.thickness:
                world = SimulatedWorld(_scenario(thickness, Path(tmp)),
                                       config=WorldConfig(hold_s=3.0, unload=True,
                                                          camera=camera_preset(camera)),
                                       rng=np.random.default_rng(1))
                row = []
                for xy, truth in PRESSES:
                    read = poke_behaviour(world.press(xy, args.force)).behaviour
                    world.release()
                    counts[truth, read] += 1
                    row.append(f"{truth}→{read}")
                print(f"{camera:>15} {thickness:5.3f} m  " + "  ".join(row), flush=True)
    reads = ["elastic", "viscoelastic", "plastic", "unknown"]
    print(f"\n{'truth (baseline)':>16} | " + " | ".join(f"{r:>12}" for r in reads) + " | presses")
    for truth in reads[:3]:
        total = sum(counts[truth, r] for r in reads)
        print(f"{truth:>16} | " + " | ".join(f"{counts[truth, r]:>12}" for r in reads)
              + f" | {total:>7}")


if __name__ == "__main__":
    main()
