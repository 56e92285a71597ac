"""β̂ per hardness with the default protocol on a harder case than the table's.

Run: PYTHONPATH=src python examples/msm_robustness.py

The rest surface is tilted (about 5.7°) and curved, the contact lies between particles, and the
observed dent (a Hertz dent, not shape matching) carries 0.1 mm of seeded Gaussian noise.

:func:`estimates` returns the numbers (``tests/test_examples.py`` checks them against reference
values); :func:`main` prints them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from deformap.msm import BetaEstimate, ShapeMatchingConfig, estimate_beta
from deformap.testing import elastic_dent, hardness_to_modulus

HARDNESSES_N: tuple[float | None, ...] = (30.0, 60.0, 110.0, 150.0, 250.0, None)  # None: rigid


def estimates(hardnesses: Sequence[float | None] = HARDNESSES_N, *,
              seed: int = 1) -> list[tuple[float | None, BetaEstimate]]:
    """``(hardness, estimate)`` for each foam, in order; ``seed`` draws the observation noise
    (one generator for all foams, drawn in order)."""
    n = 25
    xs = 0.30 + (np.arange(n) - 12) * 0.005
    ys = 0.20 + (np.arange(n) - 12) * 0.005
    gx, gy = np.meshgrid(xs, ys)
    z = 0.05 + 0.1 * (gx - 0.3) + 2.0 * (gy - 0.2) ** 2
    rng = np.random.default_rng(seed)
    out = []
    for hardness in hardnesses:
        e = None if hardness is None else hardness_to_modulus(hardness)
        zd, contact = elastic_dent(xs, ys, z, (0.3023, 0.2017), force_n=0.5,
                                   tip_radius_m=0.01, modulus_pa=e)
        noisy = zd + rng.normal(scale=1e-4, size=zd.shape)
        pts = np.column_stack([gx.ravel(), gy.ravel(), noisy.ravel()])
        out.append((hardness, estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig())))
    return out


def main() -> None:
    """Print the table."""
    print("| hardness N | β̂ | β std | all converged |")
    print("|---|---|---|---|")
    for hardness, est in estimates():
        name = "rigid" if hardness is None else f"{hardness:.0f}"
        print(f"| {name} | {est.beta:.2f} | {est.beta_std:.3f} | {est.all_converged} |")


if __name__ == "__main__":
    main()
