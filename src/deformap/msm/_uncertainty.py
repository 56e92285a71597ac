"""How well one poke pins down β: a paired block bootstrap of E(β) over the ROI (resampling whole
tiles of particles, so that correlated neighbours move together; Künsch 1989; Efron & Tibshirani
1993, §8.6), or E(β) against perturbed observations.

References
----------
Künsch, H. R. (1989). The jackknife and the bootstrap for general stationary observations.
The Annals of Statistics 17(3), 1217–1241.
Efron, B., Tibshirani, R. J. (1993). An Introduction to the Bootstrap. Chapman & Hall.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from deformap._validation import check_array, check_int, check_positive
from deformap.errors import InvalidArgumentError

__all__ = ["BOOTSTRAP_SEED", "bootstrap_beta_std", "parabola_vertex", "sample_beta_std"]

BOOTSTRAP_SEED = 20161115  # a deterministic statistic, not a source of randomness


def parabola_vertex(x: NDArray[np.float64], e: NDArray[np.float64]
                    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:  # fmt: skip
    """Vertex abscissae of the parabolas through ``(x[..., k], e[..., k])``, k = 0, 1, 2 (``x``
    increasing), and whether each has a minimum (else the vertex is NaN)."""
    x0, x1, x2 = x[..., 0], x[..., 1], x[..., 2]
    e0, e1, e2 = e[..., 0], e[..., 1], e[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        curv = ((e2 - e1) / (x2 - x1) - (e1 - e0) / (x1 - x0)) / (x2 - x0)
        slope = (e1 - e0) / (x1 - x0) - curv * (x0 + x1)
        ok = curv > 0.0
        vertex = np.where(ok, -slope / (2.0 * curv), np.nan)
    return np.asarray(vertex, dtype=float), np.asarray(ok, dtype=bool)


def _tile_sums(distances: NDArray[np.float64], tile: int) -> NDArray[np.float64]:
    """``(B, ny, nx)`` → ``(B, n_tiles)`` sums over ``tile × tile`` blocks (edge blocks smaller)."""
    n_beta, ny, nx = distances.shape
    rows, cols = np.arange(ny) // tile, np.arange(nx) // tile
    index = (rows[:, None] * (int(cols[-1]) + 1) + cols[None, :]).ravel()
    n_tiles = int(index.max()) + 1
    sums = np.zeros((n_beta, n_tiles))
    for b in range(n_beta):  # n_beta rows of one bincount each: cheap, and keeps memory flat
        sums[b] = np.bincount(index, weights=distances[b].ravel(), minlength=n_tiles)
    return sums


def bootstrap_beta_std(betas: NDArray[np.float64], distances: NDArray[np.float64], *, tile: int,
                       resolution: float, n_boot: int = 256) -> float:
    """Std of β̂ (≥ ``resolution / √12``) over ``n_boot`` resamples of ``tile × tile`` blocks of
    ``distances (B, ny, nx)`` metres, particle to observed surface, at increasing ``betas (B,)``."""
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


_CANDIDATES = 8  # nearest observed points per particle searched for a moved one's nearest


def sample_beta_std(betas: NDArray[np.float64], positions: NDArray[np.float64],
                    observed: NDArray[np.float64], height_samples: NDArray[np.float64], *,
                    resolution: float) -> float:
    """Std of β̂ (≥ ``resolution / √12``) over ``observed (m, 3)`` moved vertically by each row of
    ``height_samples (S, m)``: E(β) of ``positions (B, ny, nx, 3)`` at increasing ``betas (B,)``,
    each particle's nearest sought among its 8 nearest unmoved points."""
    b = check_array("betas", betas, (None,), min_rows=2)
    if np.any(np.diff(b) <= 0):
        raise InvalidArgumentError("`betas` must be strictly increasing")
    pos = check_array("positions", positions, (b.size, None, None, 3), what="positions in metres")
    obs = check_array("observed", observed, (None, 3), min_rows=1, what="points in metres")
    dz = check_array("height_samples", height_samples, (None, obs.shape[0]), min_rows=2,
                     what="height errors in metres")  # fmt: skip
    floor = check_positive("resolution", resolution) / np.sqrt(12.0)
    k = min(_CANDIDATES, obs.shape[0])
    particles = pos.reshape(b.size, -1, 3)
    _, near = cKDTree(obs).query(particles.reshape(-1, 3), k=k)
    near = near.reshape(b.size, -1, k)
    offset = obs[near] - particles[:, :, None, :]  # (B, K, k, 3) to the unmoved candidates
    planar = offset[..., 0] ** 2 + offset[..., 1] ** 2
    curves = np.empty((dz.shape[0], b.size))
    for s, row in enumerate(dz):  # one sample at a time keeps memory at one (B, K, k) array
        curves[s] = np.sqrt(planar + (offset[..., 2] + row[near]) ** 2).min(axis=2).mean(axis=1)
    return float(max(_argmins(b, curves).std(ddof=1), floor))


def _argmins(betas: NDArray[np.float64], curves: NDArray[np.float64]) -> NDArray[np.float64]:
    """Minimiser of each row of ``curves (S, B)``: the parabola's vertex through its lowest sample
    and the two beside it, in ``u = −log(1 − β)``, kept between those two."""
    s_idx = np.arange(curves.shape[0])
    lowest = np.argmin(curves, axis=1)
    i = np.clip(lowest, 1, betas.size - 2)
    u = -np.log1p(-betas)
    three = np.stack([i - 1, i, i + 1], axis=1)
    vertex, ok = parabola_vertex(u[three], curves[s_idx[:, None], three])
    vertex = np.clip(np.where(ok, vertex, u[lowest]), u[i - 1], u[i + 1])
    return np.asarray(-np.expm1(-vertex))
