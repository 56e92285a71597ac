"""How well one poke pins down β: a paired block bootstrap of E(β) over the ROI.

E(β) is a mean over the ROI's particles of the distance from each simulated particle to the observed
surface. Most of the ROI is undisturbed and adds nearly the same distance at every β, so the *level*
of E says little about which β fits; what matters is how consistently the particles prefer one β.
Resampling whole tiles of particles (blocks of about the touch GP's correlation length, so that
neighbouring, correlated particles move together) and taking the argmin of each resampled curve
gives the spread of β̂ that the observation supports: tight for a deep, clear dent, wide for a
shallow one whose E(β) is flat (Künsch 1989; Efron & Tibshirani 1993, §8.6).

The resampling uses a fixed internal seed, so the uncertainty is a deterministic function of the
poke (the same poke always gets the same β-field noise).

References
----------
Künsch, H. R. (1989). The jackknife and the bootstrap for general stationary observations.
The Annals of Statistics 17(3), 1217–1241.
Efron, B., Tibshirani, R. J. (1993). An Introduction to the Bootstrap. Chapman & Hall.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_int, check_positive
from deformap.errors import InvalidArgumentError

__all__ = ["BOOTSTRAP_SEED", "bootstrap_beta_std"]

BOOTSTRAP_SEED = 20161115
"""The fixed seed of the resampling (a deterministic statistic, not a source of randomness)."""


def _tile_sums(distances: NDArray[np.float64], tile: int) -> NDArray[np.float64]:
    """``(B, ny, nx)`` → ``(B, n_tiles)`` sums over ``tile × tile`` blocks (edge blocks smaller)."""
    n_beta, ny, nx = distances.shape
    rows = np.arange(ny) // tile
    cols = np.arange(nx) // tile
    n_cols = int(cols[-1]) + 1
    index = (rows[:, None] * n_cols + cols[None, :]).ravel()
    n_tiles = int(index.max()) + 1
    sums = np.zeros((n_beta, n_tiles))
    for b in range(n_beta):  # n_beta rows of one bincount each: cheap, and keeps memory flat
        sums[b] = np.bincount(index, weights=distances[b].ravel(), minlength=n_tiles)
    return sums


def bootstrap_beta_std(
    betas: NDArray[np.float64],
    distances: NDArray[np.float64],
    *,
    tile: int,
    resolution: float,
    n_boot: int = 256,
) -> float:
    """Standard deviation of β̂ under a block bootstrap of the ROI's particles.

    Parameters
    ----------
    betas : (B,) float
        The β values simulated, increasing.
    distances : (B, ny, nx) float, metres
        For each β, each surface particle's distance to the observed surface (E(β) is their mean).
    tile : int
        Side of a resampled block, in particles.
    resolution : float
        The β resolution of the estimate; the result is never below ``resolution / sqrt(12)``.
    n_boot : int
        Number of resamples.
    """
    b = check_array("betas", betas, (None,), min_rows=2)
    d = check_array("distances", distances, (b.size, None, None), what="distances in metres")
    if np.any(np.diff(b) <= 0):
        raise InvalidArgumentError("`betas` must be strictly increasing")
    check_int("tile", tile, minimum=1)
    floor = check_positive("resolution", resolution) / np.sqrt(12.0)
    check_int("n_boot", n_boot, minimum=2)
    sums = _tile_sums(d, tile)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    n_tiles = sums.shape[1]
    counts = rng.multinomial(n_tiles, np.full(n_tiles, 1.0 / n_tiles), size=n_boot)
    resampled = counts @ sums.T  # (n_boot, B): each row a resampled E(β), up to a constant factor
    picks = b[np.argmin(resampled, axis=1)]
    return float(max(picks.std(ddof=1), floor))
