"""Whether the standard errors a press's behaviour claims match the scatter of its values: over
``--seeds`` worlds per material and thickness (seeds 100, 101, …; one press each at the behaviour
study's first place, 0.6 N, held 3 s and unloaded, the PrimeSense preset), the loss ratio, the
travel at zero force (the dent) and the hold's creep fraction are read from each noisy record as
:func:`deformap.stiffness.press_behaviour` reads them, and the spread of the values (their
standard deviation over the worlds) is set against the median σ they claim. The baseline, in the
same run on the same records, is the pooled constant force noise (``σ_F`` of every stretch's
second differences together); "load" is the force noise as a function of the load
(``σ_F(F)² = a² + (b F)²``, :func:`deformap.stiffness._phases.force_noise`). The creep's σ is
the hold's exponential fit's, which neither changes. ``exact`` is the value the noise-free record
gives (the world's truth for the estimator).

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/behaviour_calibration.py \
        [--seeds 30] [--thickness 0.03 0.1] [--materials "elastic 30 N" ...]

A ratio spread/claimed above 1 is a σ that undercovers.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from deformap.environment import ForceTravel, Workspace
from deformap.eval import DEFAULT_POSITIONS, FULL_BEHAVIOUR_MATERIALS, material_scenario
from deformap.stiffness._phases import (
    ForceNoise,
    force_noise,
    hold_fraction,
    hold_travel,
    hold_with_start,
    loop_loss,
    noise,
    zero_force_travel,
)
from deformap.world import SimulatedWorld, WorldConfig, camera_preset

MATERIALS = ["elastic 30 N", "elastic 250 N", "viscoelastic g∞ 0.8 τ 2 s", "plastic yield 3000 Pa"]
HOLD_S = 3.0  # the behaviour study's hold (deformap.run's BEHAVIOUR_HOLD_S)
FORCE_N = 0.6


def _read(record: ForceTravel, noisy: bool) -> dict[str, tuple[float, float, float, float]]:
    """Each quantity's value and σ with the pooled force noise, then with the load's."""
    parts = [record, record.hold, record.unloading]
    sigma_f = noise([np.asarray(p.force_n) for p in parts])
    sigma_t = noise([np.asarray(p.travel_m) for p in parts])
    pooled = ForceNoise(sigma_f)
    load = force_noise([np.asarray(p.force_n) for p in parts]) if noisy else pooled
    hold = hold_with_start(record)
    creep = hold_travel(hold, sigma_t)
    out: dict[str, tuple[float, float, float, float]] = {}
    for name in ("loss", "dent"):
        got: list[float] = []
        for model in (pooled, load):
            m = (loop_loss(record, model, sigma_t) if name == "loss"
                 else zero_force_travel(record, model, sigma_t, creep))
            got += [np.nan, np.nan] if isinstance(m, str) else [m.value, m.sigma]
        out[name] = (got[0], got[1], got[2], got[3])
    frac, _, _, _ = hold_fraction(hold, sigma_f, sigma_t)
    out["creep"] = ((np.nan,) * 4 if frac is None
                    else (frac.value, frac.sigma, frac.value, frac.sigma))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--thickness", type=float, nargs="+", default=[0.03, 0.1])
    parser.add_argument("--materials", nargs="+", default=MATERIALS)
    args = parser.parse_args()
    by_name = {m.name: m for m in FULL_BEHAVIOUR_MATERIALS}
    config = WorldConfig(camera=camera_preset("primesense"), hold_s=HOLD_S, unload=True)
    xy = np.asarray(DEFAULT_POSITIONS[0])
    print("| material | thickness | quantity | exact | mean | spread | claimed | spread/claimed "
          "| spread (load) | claimed (load) | spread/claimed (load) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.materials:
        for thickness in args.thickness:
            start = time.perf_counter()
            scenario = material_scenario(by_name[name], Workspace(), thickness)
            rows: dict[str, list[tuple[float, float, float, float]]] = {}
            exact = None
            for i in range(args.seeds):
                world = SimulatedWorld(scenario, config=config, rng=np.random.default_rng(100 + i))
                if exact is None:
                    exact = _read(world.force_travel(xy, FORCE_N, exact=True), noisy=False)
                for key, value in _read(world.force_travel(xy, FORCE_N), noisy=True).items():
                    rows.setdefault(key, []).append(value)
            assert exact is not None
            for key, unit, fmt in (("loss", 1.0, "{:.4f}"), ("dent", 1e3, "{:.3f} mm"),
                                   ("creep", 1.0, "{:.4f}")):
                a = np.asarray(rows[key], dtype=float) * unit
                ok = np.isfinite(a[:, 0]) & np.isfinite(a[:, 2])
                cells = [fmt.format(exact[key][0] * unit), fmt.format(float(np.mean(a[ok, 2])))]
                for col in (0, 2):
                    spread = float(np.std(a[ok, col], ddof=1))
                    claimed = float(np.median(a[ok, col + 1]))
                    cells += [fmt.format(spread), fmt.format(claimed), f"{spread / claimed:.2f}"]
                label = key if ok.all() else f"{key} ({int(ok.sum())}/{ok.size} read)"
                print(f"| {name} | {thickness * 100:g} cm | {label} | " + " | ".join(cells) + " |",
                      flush=True)
            print(f"<!-- {name} {thickness:g} m: {time.perf_counter() - start:.0f} s -->",
                  flush=True)


if __name__ == "__main__":
    main()
