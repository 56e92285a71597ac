"""Whether the standard errors a press's behaviour claims match the spread of its values: over
``--seeds`` worlds per material and thickness (seeds 100, 101, …; one press each at the behaviour
study's first place, 0.6 N, held ``--hold`` seconds (default the study's hold) and unloaded, the
PrimeSense preset), the loss ratio, the travel at zero force (the dent) and the hold's creep
fraction are read from each noisy record, and the spread of the values (their standard deviation
over the worlds) is set against the median σ they claim. Three readings of the same records in the
same run: "main", the baseline, as main (d4f59f9) reads them (one pooled force noise ``σ_F`` of
every stretch's second differences; the loss along every sample of the hold, its σ propagated at
the noisy samples); "pooled + product", the pooled ``σ_F`` with the product of the two noises
counted once in the loss's σ (the loss only); "load", as :func:`deformap.stiffness.press_behaviour`
now reads them, the force noise a function of the load (``σ_F(F)² = a² + (b F)²``,
:func:`deformap.stiffness._phases.force_noise`) and the product term counted once. The creep's σ is
the hold's exponential fit's, which none changes. The last two read the loss along the hold's last
sample alone, as the shipped reading does. ``exact`` is the value the noise-free record
gives, ``mean`` the mean of the "load" values.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/behaviour_calibration.py \
        [--seeds 30] [--thickness 0.03 0.1] [--hold 12] [--materials "elastic 30 N" ...]

A ratio spread/claimed above 1 is a σ that undercovers.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from deformap.environment import ForceTravel, Workspace
from deformap.eval import DEFAULT_POSITIONS, FULL_BEHAVIOUR_MATERIALS, material_scenario
from deformap.run._studies import BEHAVIOUR_HOLD_S  # the study's own hold
from deformap.stiffness._phases import (
    ForceNoise,
    _trapz_grad,
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
FORCE_N = 0.6


def _main_loss(record: ForceTravel, sigma_f: float, sigma_t: float) -> tuple[float, float]:
    """The loss ratio and its σ as main (d4f59f9) gave them: every sample of the hold, one pooled
    σ_F, linear propagation at the noisy samples, no product term taken back."""
    parts: list[Any] = [record, record.hold, record.unloading]
    x = np.concatenate([np.asarray(p.travel_m) for p in parts])
    y = np.concatenate([np.asarray(p.force_n) for p in parts])
    n_in = record.travel_m.size + record.hold.travel_m.size
    loop, gx, gy = _trapz_grad(x, y)
    work, gx_w, gy_w = _trapz_grad(x[:n_in], y[:n_in])
    gx[:n_in] -= loop / work * gx_w
    gy[:n_in] -= loop / work * gy_w
    return loop / work, float(np.sqrt(sigma_t**2 * (gx @ gx) + sigma_f**2 * (gy @ gy)) / work)


def _read(record: ForceTravel, noisy: bool) -> dict[str, list[tuple[float, float]]]:
    """Each quantity's value and σ as main reads it, with the pooled force noise and the
    product term taken back (the loss only), and with the load's force noise."""
    parts = [record, record.hold, record.unloading]
    sigma_f = noise([np.asarray(p.force_n) for p in parts])
    sigma_t = noise([np.asarray(p.travel_m) for p in parts])
    pooled = ForceNoise(sigma_f)
    load = force_noise([np.asarray(p.force_n) for p in parts]) if noisy else pooled
    hold = hold_with_start(record)
    creep = hold_travel(hold, sigma_t)
    out: dict[str, list[tuple[float, float]]] = {}
    for name in ("loss", "dent"):
        got: list[tuple[float, float]] = []
        for model in (pooled, load):
            m = (loop_loss(record, model, sigma_t) if name == "loss"
                 else zero_force_travel(record, model, sigma_t, creep))
            got.append((np.nan, np.nan) if isinstance(m, str) else (m.value, m.sigma))
        if name == "loss":
            got.insert(0, _main_loss(record, sigma_f, sigma_t))
        else:
            got.insert(0, got[0])
        out[name] = got
    frac, _, _, _ = hold_fraction(hold, sigma_f, sigma_t)
    out["creep"] = [(np.nan, np.nan) if frac is None else (frac.value, frac.sigma)] * 3
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--thickness", type=float, nargs="+", default=[0.03, 0.1])
    parser.add_argument("--hold", type=float, default=BEHAVIOUR_HOLD_S)
    parser.add_argument("--materials", nargs="+", default=MATERIALS)
    args = parser.parse_args()
    by_name = {m.name: m for m in FULL_BEHAVIOUR_MATERIALS}
    config = WorldConfig(camera=camera_preset("primesense"), hold_s=args.hold, unload=True)
    xy = np.asarray(DEFAULT_POSITIONS[0])
    print("| material | thickness | quantity | exact | mean | spread | claimed main | "
          "spread/claimed main | claimed pooled + product | spread/claimed | spread load | "
          "claimed load | spread/claimed load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.materials:
        for thickness in args.thickness:
            start = time.perf_counter()
            scenario = material_scenario(by_name[name], Workspace(), thickness)
            rows: dict[str, list[list[tuple[float, float]]]] = {}
            exact: dict[str, list[tuple[float, float]]] | None = None
            for i in range(args.seeds):
                world = SimulatedWorld(scenario, config=config, rng=np.random.default_rng(100 + i))
                if exact is None:
                    exact = _read(world.force_travel(xy, FORCE_N, exact=True), noisy=False)
                for key, value in _read(world.force_travel(xy, FORCE_N), noisy=True).items():
                    rows.setdefault(key, []).append(value)
            assert exact is not None
            for key, unit, fmt in (("loss", 1.0, "{:.4f}"), ("dent", 1e3, "{:.3f} mm"),
                                   ("creep", 1.0, "{:.4f}")):
                a = np.asarray(rows[key], dtype=float) * unit  # (seeds, estimate, value/σ)
                ok = np.all(np.isfinite(a[:, :, 0]), axis=1)
                cells = [fmt.format(exact[key][2][0] * unit),
                         fmt.format(float(np.mean(a[ok, 2, 0])))]
                for k in range(3):
                    spread = float(np.std(a[ok, k, 0], ddof=1))
                    claimed = float(np.median(a[ok, k, 1]))
                    if k in (0, 2):
                        cells.append(fmt.format(spread))
                    cells += [fmt.format(claimed), f"{spread / claimed:.2f}"]
                label = key if ok.all() else f"{key} ({int(ok.sum())}/{ok.size} read)"
                print(f"| {name} | {thickness * 100:g} cm | {label} | " + " | ".join(cells) + " |",
                      flush=True)
            print(f"<!-- {name} {thickness:g} m: {time.perf_counter() - start:.0f} s -->",
                  flush=True)


if __name__ == "__main__":
    main()
