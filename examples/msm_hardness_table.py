"""β̂ per foam hardness for each poke protocol and mode, on analytic elastic (Hertz) dents.

Run: PYTHONPATH=src python examples/msm_hardness_table.py

The dents come from :func:`deformap.testing.elastic_dent` (linear-elastic half-space under a
1 cm-radius spherical tip, 0.5 N), never from shape matching. The ROI is 12 cm at 0.5 cm
(25 × 25 particles), centred on the poke, as in the exploration loop.

:func:`table` returns the numbers of one protocol (``tests/test_examples.py`` checks them against
reference values); :func:`main` prints every protocol's table.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from deformap.msm import BetaEstimate, ShapeMatchingConfig, estimate_beta
from deformap.testing import elastic_dent, hardness_to_modulus

HARDNESSES_N: tuple[float | None, ...] = (30.0, 60.0, 110.0, 150.0, 250.0, None)  # None: rigid

#: (contact, layers): layers=0 is the paper's surface sheet, layers=3 the default layered body.
PROTOCOLS: tuple[tuple[str, int], ...] = (("pinned", 0), ("pinned", 3), ("force", 0), ("force", 3))
MODES: tuple[str, ...] = ("linear", "quadratic")


class Row(NamedTuple):
    """One foam of a table."""

    hardness_n: float | None
    depth_m: float
    """Depth of the analytic dent under the tip."""
    estimate: BetaEstimate
    error_span_m: float
    """max E(β) − min E(β) over the β solved: how much the fit cares about β."""
    seconds: float


def roi(n: int = 25, spacing: float = 0.005,
        height: float = 0.05) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Grid ``xs, ys`` (n,) and flat rest heights ``z`` (n, n) centred on (0.30, 0.20) m."""
    xs = 0.30 + (np.arange(n) - (n - 1) / 2) * spacing
    ys = 0.20 + (np.arange(n) - (n - 1) / 2) * spacing
    return xs, ys, np.full((n, n), height)


def table(protocol: str, mode: str, layers: int, *,
          hardnesses: Sequence[float | None] = HARDNESSES_N, force_n: float = 0.5,
          tip_radius_m: float = 0.01) -> list[Row]:
    """Estimate β̂ on the Hertz dent of each foam with one protocol; one :class:`Row` each."""
    xs, ys, z = roi()
    centre = (z.shape[0] // 2, z.shape[1] // 2)
    rows = []
    for h in hardnesses:
        e = None if h is None else hardness_to_modulus(h)
        zd, contact = elastic_dent(xs, ys, z, (0.30, 0.20), force_n=force_n,
                                   tip_radius_m=tip_radius_m, modulus_pa=e)
        gx, gy = np.meshgrid(xs, ys)
        pts = np.column_stack([gx.ravel(), gy.ravel(), zd.ravel()])
        cfg = ShapeMatchingConfig(contact=protocol, mode=mode, layers=layers)  # type: ignore[arg-type]
        t = time.perf_counter()
        est = estimate_beta(xs, ys, z, pts, contact, cfg)
        dt = time.perf_counter() - t
        span = float(est.errors.max() - est.errors.min())
        rows.append(Row(h, float(z[centre] - zd[centre]), est, span, dt))
    return rows


def main(hardnesses: Sequence[float | None] = HARDNESSES_N) -> None:
    """Print the table of every protocol and mode."""
    for protocol, layers in PROTOCOLS:
        for mode in MODES:
            print(f"\n## contact={protocol}, mode={mode}, layers={layers}")
            print("| hardness N | dent mm | β̂ | β std | E(β̂) mm | E range mm | iters max "
                  "| all conv | s |")
            print("|---|---|---|---|---|---|---|---|---|")
            for h, depth, est, span, dt in table(protocol, mode, layers, hardnesses=hardnesses):
                name = "rigid" if h is None else f"{h:.0f}"
                print(f"| {name} | {1e3 * depth:.2f} | {est.beta:.2f} | {est.beta_std:.3f} | "
                      f"{1e3 * est.errors.min():.3f} | {1e3 * span:.4f} | {est.iterations.max()} | "
                      f"{est.all_converged} | {dt:.2f} |")


if __name__ == "__main__":
    main()
