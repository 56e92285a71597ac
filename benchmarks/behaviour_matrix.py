"""What each press of a simulated world reveals beyond its stiffness, against the world's truth:
the behaviour class :func:`deformap.explore.poke_behaviour` reads from a press that holds its force
and unloads, per camera preset and foam thickness, on one table of three 60 N blocks (elastic;
viscoelastic, a standard linear solid with g∞ = 0.5 and τ = 1 s; plastic, yield 1 kPa, hardening
2 kPa), with the residual dent read against the world's (the deepest point of the surface the
press left); then the in-plane anisotropy read from the dent's shape on a second table of three
60 N blocks (isotropic; ratio 1.5 with the stiff axis at 30°; ratio 3 at −45°), two presses
each, per camera preset (and a camera with no noise, ``none``) and thickness. Each camera's worlds
draw their noise (record and camera) from a stream of their own. The baseline is the truth of each
press, in the same run.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/behaviour_matrix.py \
        [--cameras primesense kinect-v1 realsense-d435] [--thickness 0.03 0.1] [--force 0.6] \
        [--levels 8] [--no-anisotropy]

``--levels`` is the load levels the world solves the ramp at (``WorldConfig.force_travel_levels``;
the world's default 8); the ramp, the hold and the unloading are read between them at
``WorldConfig.sample_rate_hz`` (100 Hz: about 30 ramp samples over a 0.3 s ramp). Each press's
line gives its class; the table counts them.
"""

from __future__ import annotations

import argparse
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np
import yaml

from deformap.explore import poke_behaviour
from deformap.stiffness import estimate_stiffness
from deformap.world import SimulatedWorld, WorldConfig, camera_preset, load_scenario

ANISOTROPIC = [((0.1, 0.2), 1.0, None), ((0.1, 0.1), 1.0, None), ((0.3, 0.2), 1.5, 30.0),
               ((0.3, 0.3), 1.5, 30.0), ((0.5, 0.2), 3.0, -45.0), ((0.5, 0.1), 3.0, -45.0)]
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


def _anisotropic(thickness: float, folder: Path):  # type: ignore[no-untyped-def]
    blocks = [
        {"name": "round", "rect": [0, 0, 0.2, 0.4], "hardness_n": 60},
        {"name": "ribbed", "rect": [0.2, 0, 0.4, 0.4], "hardness_n": 60,
         "anisotropy": {"ratio": 1.5, "axis_deg": 30}},
        {"name": "woven", "rect": [0.4, 0, 0.6, 0.4], "hardness_n": 60,
         "anisotropy": {"ratio": 3, "axis_deg": -45}},
    ]
    for block in blocks:
        block["thickness_m"] = thickness
    path = folder / f"aniso-{thickness:g}.yaml"
    path.write_text(yaml.safe_dump({"name": "aniso", "blocks": blocks}))
    return load_scenario(path)


def _anisotropy_table(args: argparse.Namespace, tmp: Path) -> None:
    counts: Counter[tuple[str, str]] = Counter()
    ratio_ok = axis_ok = n_aniso = 0
    for c, camera in enumerate([*args.cameras, "none"]):
        config = (WorldConfig(noise=False) if camera == "none"
                  else WorldConfig(camera=camera_preset(camera)))
        for thickness in args.thickness:
            world = SimulatedWorld(_anisotropic(thickness, tmp), config=config,
                                   rng=np.random.default_rng([1, c]))
            row = []
            for xy, ratio, axis in ANISOTROPIC:
                got = poke_behaviour(world.press(xy, args.force))
                world.release()
                truth = "isotropic" if ratio == 1.0 else "anisotropic"
                counts[truth, got.isotropy or "unknown"] += 1
                if got.anisotropy_ratio is None or got.anisotropy_axis_deg is None:
                    row.append(f"{ratio:g}→none")
                    continue
                text = f"{ratio:g}→{got.anisotropy_ratio:.2f}±{got.anisotropy_ratio_sigma:.2f}"
                if axis is not None:
                    n_aniso += 1
                    off = abs((got.anisotropy_axis_deg - axis + 90.0) % 180.0 - 90.0)
                    ratio_ok += abs(got.anisotropy_ratio / ratio - 1.0) <= 0.15
                    axis_ok += off <= 10.0
                    text += f"@{got.anisotropy_axis_deg:.0f}°(Δ{off:.0f}°)"
                row.append(f"{text} {got.isotropy}")
            print(f"{camera:>15} {thickness:5.3f} m  " + "  ".join(row), flush=True)
    reads = ["isotropic", "anisotropic", "unknown"]
    print(f"\n{'truth (baseline)':>16} | " + " | ".join(f"{r:>12}" for r in reads) + " | presses")
    for truth in reads[:2]:
        total = sum(counts[truth, r] for r in reads)
        print(f"{truth:>16} | " + " | ".join(f"{counts[truth, r]:>12}" for r in reads)
              + f" | {total:>7}")
    print(f"anisotropic presses: ratio within 15 % {ratio_ok}/{n_aniso}, axis within 10° "
          f"{axis_ok}/{n_aniso}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cameras", nargs="+", default=["primesense", "kinect-v1", "realsense-d435"])
    parser.add_argument("--thickness", nargs="+", type=float, default=[0.03, 0.1])
    parser.add_argument("--force", type=float, default=0.6)
    parser.add_argument("--levels", type=int, default=8)
    parser.add_argument("--no-anisotropy", action="store_true")
    args = parser.parse_args()
    counts: Counter[tuple[str, str]] = Counter()
    dent_errors: dict[str, list[float]] = {"elastic": [], "viscoelastic": [], "plastic": []}
    moduli: dict[str, list[tuple[float, float]]] = {"elastic": [], "viscoelastic": [], "plastic": []}
    with tempfile.TemporaryDirectory() as tmp:
        for c, camera in enumerate(args.cameras):
            for thickness in args.thickness:
                # a stream of its own per camera: the record's noise differs from camera to camera
                world = SimulatedWorld(_scenario(thickness, Path(tmp)),
                                       config=WorldConfig(hold_s=3.0, unload=True,
                                                          camera=camera_preset(camera),
                                                          force_travel_levels=args.levels),
                                       rng=np.random.default_rng([1, c]))
                row = []
                for xy, truth in PRESSES:
                    obs = world.press(xy, args.force)
                    record = obs.force_travel
                    assert record is not None
                    stiffness = estimate_stiffness(record.travel_m, record.force_n,
                                                   tip_radius_m=obs.contact.tip_radius_m,
                                                   thickness_m=thickness,
                                                   commanded_force_n=obs.force_n)
                    got = poke_behaviour(obs, stiffness)
                    read = got.behaviour
                    if got.modulus_instantaneous_pa and got.modulus_relaxed_pa and record.hold:
                        # the world's modulus, and its relaxed value at the hold's end
                        e0 = float(world.ground_truth_modulus(*np.array(xy)[:, None])[0, 0])
                        block = world.scenario.blocks[int(world.ground_truth_labels(
                            *np.array(xy)[:, None])[0, 0])]
                        late = (1.0 if block.viscoelastic is None else
                                float(block.viscoelastic.relaxation(float(record.hold.time_s[-1]))))
                        moduli[truth].append((got.modulus_instantaneous_pa / e0,
                                              got.modulus_relaxed_pa / (e0 * late)))
                    world.release()
                    kept = -float(np.min(world.released_displacement(0.0)[:, 2]))
                    if got.residual_dent_m is not None:
                        dent_errors[truth].append(abs(got.residual_dent_m - kept))
                    counts[truth, read] += 1
                    row.append(f"{truth}→{read}")
                print(f"{camera:>15} {thickness:5.3f} m  " + "  ".join(row), flush=True)
    reads = ["elastic", "viscoelastic", "plastic", "unknown"]
    print(f"\n{'truth (baseline)':>16} | " + " | ".join(f"{r:>12}" for r in reads) + " | presses")
    for truth in reads[:3]:
        total = sum(counts[truth, r] for r in reads)
        print(f"{truth:>16} | " + " | ".join(f"{counts[truth, r]:>12}" for r in reads)
              + f" | {total:>7}")
    for truth, errors in dent_errors.items():
        if errors:
            print(f"{truth}: residual dent error median {np.median(errors) * 1e3:.2f} mm, "
                  f"largest {np.max(errors) * 1e3:.2f} mm ({len(errors)} presses)")
    for truth, pairs in moduli.items():
        if pairs:
            inst, relaxed = np.median(np.array(pairs), axis=0)
            print(f"{truth}: median E_instantaneous / E₀ {inst:.2f}, E_relaxed / E(hold's end) "
                  f"{relaxed:.2f} ({len(pairs)} presses)")
    if not args.no_anisotropy:
        print()
        with tempfile.TemporaryDirectory() as tmp:
            _anisotropy_table(args, Path(tmp))


if __name__ == "__main__":
    main()
