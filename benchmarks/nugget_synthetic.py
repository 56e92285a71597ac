"""The β-field's nugget on synthetic pokes, without a world or a planner.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/nugget_synthetic.py [--sets 100]

1. Regions counted right by the region test with the former floor (0.015, no nugget), the
   default floor alone (the β grid's 0.01 / √12) and the floor with the nugget
   (:func:`deformap.explore.with_nugget`), on one, two or three materials (β 0.72; 0.72, 0.80;
   0.63, 0.72, 0.80), 3 or 5 pokes each, each poke claiming σ uniform in 0.004–0.015 and reading
   β plus that σ plus a place-to-place scatter τ, rounded to the β grid (0.01).
2. The nugget from the β-field's marginal likelihood (σₑ 0.3 and σ_w 0.2 m fixed, the same
   half-Cauchy prior) against the within-class estimate, on a 0.6 × 0.4 m table of one material
   or two (left and right halves, β 0.72 and 0.84), 6 or 20 pokes placed at random.
"""

from __future__ import annotations

import argparse

import numpy as np

from deformap.explore import ExplorationConfig, PokeSet, beta_noise_floor, segment_regions
from deformap.explore._nugget import with_nugget

CONFIG = ExplorationConfig(field="beta")
FLOOR = beta_noise_floor(CONFIG)  # the β grid's resolution / √12
FLAT = np.zeros((1, 1))


def _classes(b: np.ndarray, noise: np.ndarray, floor: float) -> int:
    return segment_regions(FLAT, b, noise, floor=floor).n_regions


def region_counts(sets: int, rng: np.random.Generator) -> None:
    print("materials | pokes each | τ | old floor 0.015 | floor alone | nugget (median τ̂)")
    print("|---|---|---|---|---|---|")
    for means in ([0.72], [0.72, 0.80], [0.63, 0.72, 0.80]):
        for n in (3, 5):
            for tau in (0.0, 0.01, 0.02, 0.03):
                right, taus = np.zeros(3), []
                for _ in range(sets):
                    s = rng.uniform(0.004, 0.015, n * len(means))
                    b = np.repeat(means, n) + rng.standard_normal(s.size) * np.hypot(s, tau)
                    b = np.round(b, 2)
                    k = len(means)
                    right[0] += _classes(b, s, 0.015) == k
                    right[1] += _classes(b, np.maximum(s, FLOOR), FLOOR) == k
                    pokes = with_nugget(PokeSet(np.zeros((b.size, 2)), b, np.maximum(s, FLOOR)),
                                        CONFIG)  # fmt: skip
                    taus.append(pokes.nugget)
                    right[2] += _classes(b, pokes.noise, FLOOR) == k
                r = right / sets
                print(f"| {len(means)} | {n} | {tau} | {r[0]:.2f} | {r[1]:.2f} | {r[2]:.2f} "
                      f"({np.median(taus):.3f}) |", flush=True)


def _gp_nugget(xy: np.ndarray, b: np.ndarray, s: np.ndarray) -> float:
    d2 = np.sum((xy[:, None] - xy[None]) ** 2, axis=2)
    k = 0.3**2 * np.exp(-d2 / 0.2**2)
    scale = float(np.median(s))
    best, arg = -np.inf, 0.0
    for t in np.concatenate([[0.0], np.geomspace(scale * 1e-3, 0.3, 200)]):
        v = s**2 + t**2
        w = 1.0 / v
        chol = np.linalg.cholesky(k + np.diag(v))
        a = np.linalg.solve(chol, b - np.sum(w * b) / np.sum(w))
        lp = -0.5 * a @ a - np.sum(np.log(np.diag(chol))) - np.log1p((t / scale) ** 2)
        if lp > best:
            best, arg = lp, float(t)
    return arg


def likelihood_against_classes(sets: int, rng: np.random.Generator) -> None:
    print("\nmaterials | pokes | τ | β-field marginal likelihood τ̂ | within-class τ̂ "
          "(median [10 %, 90 %])")
    print("|---|---|---|---|---|")
    for means in ([0.72], [0.72, 0.84]):
        for n in (6, 20):
            for tau in (0.0, 0.02):
                gp, within = [], []
                for _ in range(sets):
                    xy = rng.uniform((0.0, 0.0), (0.6, 0.4), (n, 2))
                    side = (xy[:, 0] >= 0.3).astype(int) if len(means) == 2 else np.zeros(n, int)
                    s = np.maximum(rng.uniform(0.004, 0.015, n), FLOOR)
                    b = np.array(means)[side] + rng.standard_normal(n) * np.hypot(s, tau)
                    gp.append(_gp_nugget(xy, b, s))
                    within.append(with_nugget(PokeSet(xy, b, s), CONFIG).nugget)

                def q(a: list[float]) -> str:
                    lo, hi = np.quantile(a, [0.1, 0.9])
                    return f"{np.median(a):.3f} [{lo:.3f}, {hi:.3f}]"

                print(f"| {len(means)} | {n} | {tau} | {q(gp)} | {q(within)} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=100, help="synthetic maps per row")
    args = parser.parse_args()
    region_counts(args.sets, np.random.default_rng(0))
    likelihood_against_classes(max(1, args.sets * 6 // 10), np.random.default_rng(0))


if __name__ == "__main__":
    main()
