"""β̂ per foam hardness for each poke protocol and mode, on analytic elastic (Hertz) dents.

Run: PYTHONPATH=src python examples/msm_hardness_table.py

The dents come from :func:`deformap.testing.elastic_dent` (linear-elastic half-space under a
1 cm-radius spherical tip, 0.5 N), never from shape matching. The ROI is 12 cm at 0.5 cm
(25 × 25 particles), centred on the poke, as in the exploration loop.
"""

from __future__ import annotations

import time

import numpy as np

from deformap.msm import ShapeMatchingConfig, estimate_beta
from deformap.testing import elastic_dent, hardness_to_modulus

HARDNESSES_N = (30.0, 60.0, 110.0, 150.0, 250.0, None)  # None: rigid


def roi(n: int = 25, spacing: float = 0.005, height: float = 0.05):
    xs = 0.30 + (np.arange(n) - (n - 1) / 2) * spacing
    ys = 0.20 + (np.arange(n) - (n - 1) / 2) * spacing
    return xs, ys, np.full((n, n), height)


def table(protocol: str, mode: str, layers: int, *, force_n: float = 0.5,
          tip_radius_m: float = 0.01):
    xs, ys, z = roi()
    rows = []
    for h in HARDNESSES_N:
        e = None if h is None else hardness_to_modulus(h)
        zd, contact = elastic_dent(xs, ys, z, (0.30, 0.20), force_n=force_n,
                                   tip_radius_m=tip_radius_m, modulus_pa=e)
        gx, gy = np.meshgrid(xs, ys)
        pts = np.column_stack([gx.ravel(), gy.ravel(), zd.ravel()])
        cfg = ShapeMatchingConfig(contact=protocol, mode=mode, layers=layers)
        t = time.perf_counter()
        est = estimate_beta(xs, ys, z, pts, contact, cfg)
        dt = time.perf_counter() - t
        span = est.errors.max() - est.errors.min()
        rows.append((h, z[12, 12] - zd[12, 12], est, span, dt))
    return rows


def main() -> None:
    # layers=0: the paper's surface sheet; layers=3: the default layered body.
    for protocol, layers in (("pinned", 0), ("pinned", 3), ("force", 0), ("force", 3)):
        for mode in ("linear", "quadratic"):
            print(f"\n## contact={protocol}, mode={mode}, layers={layers}")
            print("| hardness N | dent mm | β̂ | β std | E(β̂) mm | E range mm | iters max "
                  "| all conv | s |")
            print("|---|---|---|---|---|---|---|---|---|")
            for h, depth, est, span, dt in table(protocol, mode, layers):
                name = "rigid" if h is None else f"{h:.0f}"
                print(f"| {name} | {1e3 * depth:.2f} | {est.beta:.2f} | {est.beta_std:.3f} | "
                      f"{1e3 * est.errors.min():.3f} | {1e3 * span:.4f} | {est.iterations.max()} | "
                      f"{est.all_converged} | {dt:.2f} |")


if __name__ == "__main__":
    main()
