"""Convergence of the β estimation on harder Hertz dents than the tests use.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/msm_convergence.py [--quick] [--cases N]

Each case is a Hertz dent of an elastic half-space (``deformap.testing.elastic_dent``) on an
n × n ROI, observed with 0.1 mm of seeded noise, and estimated with ``estimate_beta``. A row
reports β̂, whether every β converged, the β that did not (with their last residual and steps),
the largest step count and the estimate's time.
"""

from __future__ import annotations

import argparse
import itertools
import logging
import time

import numpy as np

from deformap.msm import ShapeMatchingConfig, estimate_beta
from deformap.testing import elastic_dent, hardness_to_modulus

logging.getLogger("deformap").setLevel(logging.ERROR)


def dent(n: int, spacing: float, force: float, tip: float, hardness: float, seed: int = 0):
    xs = 0.30 + (np.arange(n) - (n - 1) / 2) * spacing
    ys = 0.20 + (np.arange(n) - (n - 1) / 2) * spacing
    z = np.full((n, n), 0.05)
    zd, contact = elastic_dent(xs, ys, z, (0.30, 0.20), force_n=force, tip_radius_m=tip,
                               modulus_pa=hardness_to_modulus(hardness))
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.column_stack([gx.ravel(), gy.ravel(),
                           (zd + rng.normal(scale=1e-4, size=zd.shape)).ravel()])
    return xs, ys, z, pts, contact


def run_case(n, spacing, force, tip, hardness, n_beta):
    xs, ys, z, pts, contact = dent(n, spacing, force, tip, hardness)
    t0 = time.perf_counter()
    est = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig(n_beta=n_beta))
    dt = time.perf_counter() - t0
    bad = ~est.converged
    return {"n": n, "h_mm": spacing * 1e3, "F": force, "tip_mm": tip * 1e3, "hard": hardness,
            "n_beta": n_beta, "beta": est.beta, "ok": est.all_converged,
            "failed": [(round(float(b), 3), int(i), float(r)) for b, i, r in
                       zip(est.betas[bad], est.iterations[bad], est.residual[bad], strict=True)],
            "max_it": int(est.iterations.max()), "sum_it": int(est.iterations.sum()),
            "time_s": dt}


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true", help="a few cases only")
    p.add_argument("--cases", type=int, default=0, help="a random subset of this many cases")
    args = p.parse_args()
    grid = list(itertools.product([40, 25], [0.004, 0.005], [0.5, 1.0, 2.0, 3.0],
                                  [0.005, 0.010, 0.015], [30.0, 60.0, 120.0, 250.0], [50, 10]))
    if args.quick:
        grid = [(40, 0.004, 2.0, 0.010, h, 50) for h in (30.0, 60.0, 120.0, 250.0)]
    elif args.cases:
        pick = np.random.default_rng(1).choice(len(grid), size=args.cases, replace=False)
        grid = [grid[i] for i in sorted(pick)]
    print("   n  h_mm    F tip_mm  hard nb   beta_hat ok  max_it sum_it  time_s"
          "  failed β (steps, resid)")
    for case in grid:
        r = run_case(*case)
        fails = " ".join(f"{b:g}({i},{res:.1e})" for b, i, res in r["failed"])
        print(f"{r['n']:4d} {r['h_mm']:5.1f} {r['F']:4.1f} {r['tip_mm']:6.0f} {r['hard']:5.0f} "
              f"{r['n_beta']:2d} {r['beta']:10.3f} {'Y' if r['ok'] else 'N':>2} {r['max_it']:7d} "
              f"{r['sum_it']:6d} {r['time_s']:7.2f}  {fails}", flush=True)


if __name__ == "__main__":
    main()
