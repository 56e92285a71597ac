"""Speed benchmark of the surface GP: exact Cholesky against the grid (DTC/Kronecker) path.

The problem is the paper's surface model at the size of a depth-camera cloud: N noisy points over
the 60 × 40 cm workspace, σ_w = 4 cm, σₙ = 2 mm, mean and standard deviation on the 0.5 cm grid
(120 × 80 cell centres). Both paths run on the same data in the same process.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_int
from deformap.errors import InvalidArgumentError
from deformap.gp import GaussianRandomField

__all__ = ["bench_surface_gp"]

_LOG = logging.getLogger(__name__)

LENGTH_SCALE_M = 0.04
NOISE_STD_M = 0.002
#: Prior std of the relief: a foam block's surface varies by about a centimetre.
SIGNAL_STD_M = 0.01
WORKSPACE_M = (0.6, 0.4)
CELL_M = 0.005
GRID_REPEATS = 3


def _relief(xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """A smooth height field (metres) with features a few centimetres wide."""
    x, y = xy[:, 0], xy[:, 1]
    return (0.05 + 0.008 * np.sin(x / 0.04) * np.cos(y / 0.05)
            + 0.006 * np.exp(-((x - 0.35) ** 2 + (y - 0.2) ** 2) / 0.06**2))


def surface_problem(n: int, rng: np.random.Generator) -> tuple[NDArray[np.float64], ...]:
    """``xy, z, xs, ys``: ``n`` noisy points of the relief and the grid's cell centres."""
    xy = rng.uniform((0.0, 0.0), WORKSPACE_M, size=(n, 2))
    z = _relief(xy) + NOISE_STD_M * rng.standard_normal(n)
    xs = np.arange(CELL_M / 2, WORKSPACE_M[0], CELL_M)
    ys = np.arange(CELL_M / 2, WORKSPACE_M[1], CELL_M)
    return xy, z, xs, ys


def timed_fit_predict(method: str, xy: NDArray[np.float64], z: NDArray[np.float64], xs: Any,
                      ys: Any) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Seconds to fit the surface GP by ``method`` and predict mean and std on the grid, and
    those."""
    field = GaussianRandomField(length_scale=LENGTH_SCALE_M, signal_std=SIGNAL_STD_M,
                                noise_std=NOISE_STD_M, method=method)
    start = time.perf_counter()
    field.fit(xy, z)
    mean, std = field.predict_grid(xs, ys, return_std=True)
    return time.perf_counter() - start, mean, std


def bench_surface_gp(n_points_list: Sequence[int] = (3000, 6000, 12000), *,
                     rng: np.random.Generator) -> list[dict[str, float | int]]:
    """Time exact and grid GP regression of a noisy surface cloud of each size N in
    ``n_points_list`` (drawn with ``rng``) and compare their outputs. One row per N:
    ``"n_points"``, ``"exact_s"`` (fit + mean and std on the grid, one run), ``"grid_s"`` (best of
    3), ``"speedup"``, ``"max_mean_dev_m"`` (largest |mean_grid − mean_exact|, metres) and
    ``"max_rel_std_dev"`` (largest |std_grid − std_exact| / std_exact)."""
    if not isinstance(rng, np.random.Generator):
        raise InvalidArgumentError(f"`rng` must be a numpy.random.Generator; got {type(rng)}")
    sizes = [check_int("n_points_list[i]", n, minimum=2) for n in n_points_list]
    rows: list[dict[str, float | int]] = []
    for n in sizes:
        xy, z, xs, ys = surface_problem(n, rng)
        exact_s, m_exact, s_exact = timed_fit_predict("exact", xy, z, xs, ys)
        grid_runs = [timed_fit_predict("grid", xy, z, xs, ys) for _ in range(GRID_REPEATS)]
        grid_s = min(run[0] for run in grid_runs)
        _, m_grid, s_grid = grid_runs[0]
        row: dict[str, float | int] = {
            "n_points": n, "exact_s": exact_s, "grid_s": grid_s, "speedup": exact_s / grid_s,
            "max_mean_dev_m": float(np.max(np.abs(m_grid - m_exact))),
            "max_rel_std_dev": float(np.max(np.abs(s_grid - s_exact) / s_exact)),
        }  # fmt: skip
        _LOG.info("surface GP bench: %s", row)
        rows.append(row)
    return rows
