"""β estimation: the β whose simulated poke best matches the observed deformed surface."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from deformap._validation import check_points
from deformap.mechanics import TactileContact
from deformap.msm._config import ShapeMatchingConfig
from deformap.msm._grid import ParticleGrid
from deformap.msm._poke import PokeSimulation
from deformap.msm._simulate import PokeModel, _check_config
from deformap.msm._uncertainty import bootstrap_beta_std, parabola_vertex, sample_beta_std

__all__ = ["BetaEstimate", "estimate_beta", "matching_error"]

logger = logging.getLogger(__name__)
Array = NDArray[np.float64]

# largest contraction (β − β′) / (1 − β′) at which β steps with β′'s factorisation (saves one)
_MAX_SPLIT = 0.3
_KEEP_FACTORS = 3  # banded factorisations a β search keeps (:attr:`StepMatrices.max_factors`)
_TIE_M = 1e-9  # E values within a nanometre are ties (round-off): β̂ is the most rigid of them


@dataclass(frozen=True, kw_only=True)
class BetaEstimate:
    """Result of :func:`estimate_beta`: ``beta`` minimises E(β) over the converged β solved to
    ``config.tol`` (all of them if none converged; ties within 1 nm to the most rigid), ``beta_std``
    ≥ ``beta_resolution / √12``; ``betas (n,)`` sorted, ``errors`` E(β) [m], each β's last solve
    (:class:`PokeSimulation`) and ``tolerances``; ``surface (ny, nx, 3)`` [m] the particles at β̂."""

    beta: float
    beta_std: float
    betas: Array
    errors: Array
    iterations: NDArray[np.int64]
    residual: Array
    converged: NDArray[np.bool_]
    tolerances: Array
    protocol: str
    mode: str
    stiffness_n_per_m: float | None = None
    surface: Array | None = None

    @property
    def all_converged(self) -> bool:
        """Whether every simulated β reached the fixed-point tolerance."""
        return bool(np.all(self.converged))


def particle_distances(positions: Array, tree: cKDTree) -> Array:
    """min_j ‖g_i(β) − x̄_j‖ of each particle: positions ``(B, ny, nx, 3)`` → ``(B, ny, nx)``."""
    d, _ = tree.query(positions.reshape(-1, 3), k=1)
    return np.asarray(d.reshape(positions.shape[:-1]))


def matching_error(positions: Array, tree: cKDTree) -> Array:
    """The paper's E(β) = (1/K) Σ_i min_j ‖g_i(β) − x̄_j‖, ``(B,)`` metres, of simulated
    ``positions (B, ny, nx, 3)`` against a ``tree`` of the observed points ``x̄ (n, 3)``."""
    d = particle_distances(positions, tree)
    return np.asarray(d.reshape(d.shape[0], -1).mean(axis=1))


class _Sweep:
    """E(β) of one poke, each β solved once per tolerance, started from the β already solved."""

    def __init__(self, model: PokeModel, tree: cKDTree):
        self.model, self.tree = model, tree
        model.system.max_factors = _KEEP_FACTORS  # the sweep moves on: reuse a few factors' arrays
        self.sims: dict[float, PokeSimulation] = {}
        self.errors: dict[float, float] = {}
        self.distances: dict[float, Array] = {}
        self.tols: dict[float, float] = {}
        self._body: dict[float, Array] = {}

    def solved(self, beta: float, tol: float) -> bool:
        return self.tols.get(beta, np.inf) <= tol

    def run(self, betas: Array, tol: float) -> None:
        """Solve, in order, those of ``betas (B,)`` not yet solved to ``tol``."""
        for b in np.round(np.asarray(betas, dtype=float), 10):
            key = float(b)
            if self.solved(key, tol):
                continue
            # β = 0: the stiffness calibration has solved it already
            done = self.model.calibrated(tol) if key == 0.0 else None
            if done is not None:
                sim, body = done
            else:
                x0 = self._start(key)
                sim, body = self.model.solve(np.array([key]), None if x0 is None else x0[None],
                                             tol, max_split=_MAX_SPLIT)
            dist = particle_distances(sim.positions, self.tree)[0]
            self.sims[key] = sim
            self.errors[key] = float(dist.mean())
            self.distances[key] = dist
            self.tols[key] = tol
            self._body[key] = body[0]

    def _start(self, beta: float) -> Array | None:
        """Start for ``beta``: its own loose equilibrium, else linear in :meth:`PokeModel.amplitude`
        through the two nearest solved β, else the nearest deformed one (or the calibration's
        dent) scaled by amplitude; ``None`` when none is solved."""
        if beta in self._body:
            return self._body[beta]
        if not self._body:
            return None
        known = np.fromiter(self._body, dtype=float)
        near = known[np.argsort(np.abs(known - beta), kind="stable")[:2]]
        amp = self.model.amplitude
        rest = self.model.clusters.rest
        if near.size == 2 and amp(float(near[0])) != amp(float(near[1])):
            b0, b1 = float(near[0]), float(near[1])
            t = (amp(beta) - amp(b0)) / (amp(b1) - amp(b0))
            return (1.0 - t) * self._body[b0] + t * self._body[b1]
        b0 = float(near[0]) if amp(float(near[0])) > 0.0 else float(known.max())
        if amp(b0) <= 0.0:  # only the rigid end solved: the calibration's dent, of amplitude 1
            start = self.model.start
            return None if start is None else rest + (start[0] - rest) * amp(beta)
        return rest + (self._body[b0] - rest) * (amp(beta) / amp(b0))

    def curve(self) -> tuple[Array, Array, NDArray[np.int64], Array, NDArray[np.bool_], Array]:
        """Sorted β, E(β), iterations, residuals, converged flags and tolerances of every β."""
        betas = np.array(sorted(self.sims))
        rows = [self.sims[float(b)] for b in betas]
        errors = np.array([self.errors[float(b)] for b in betas])
        its = np.array([sim.iterations[0] for sim in rows], dtype=np.int64)
        res = np.array([sim.residual[0] for sim in rows])
        conv = np.array([sim.converged[0] for sim in rows], dtype=bool)
        tols = np.array([self.tols[float(b)] for b in betas])
        return betas, errors, its, res, conv, tols


def _refine(sweep: _Sweep, step: float, resolution: float, tol: float, *,
            odds: bool = False) -> None:
    """Find the minimum of E (unimodal there) on the ``resolution`` grid within one ``step`` of the
    best swept β: solve to ``tol`` the parabola's vertex (:func:`_vertex`) on the grid, or when
    solved the lowest point's unsolved neighbour nearest it, until both neighbours are solved."""
    known = np.fromiter(sweep.errors, dtype=float)
    errs = np.fromiter(sweep.errors.values(), dtype=float)
    best = float(known[np.flatnonzero(errs <= errs.min() + _TIE_M)[0]])
    n = round(step / resolution)
    idx = np.arange(-n, n + 1)
    vals = np.round(best + resolution * idx, 10)
    inside = idx[(vals >= 0.0) & (vals < 1.0)]
    a, b = int(inside[0]), int(inside[-1])

    def key(i: int) -> float:
        return float(np.round(best + resolution * i, 10))

    while True:
        done = [i for i in range(a, b + 1) if sweep.solved(key(i), tol)]
        m, missing = 0, [i for i in (-1, 0, 1) if a <= i <= b]
        if done:
            e = np.array([sweep.errors[key(i)] for i in done])
            m = done[int(np.flatnonzero(e <= e.min() + _TIE_M)[0])]
            missing = [i for i in (m - 1, m + 1) if a <= i <= b and not sweep.solved(key(i), tol)]
            if not missing:
                return
        known = np.fromiter(sweep.errors, dtype=float)
        errs = np.fromiter(sweep.errors.values(), dtype=float)
        target = (_vertex(known, errs, odds=odds) - best) / resolution
        guess = int(np.clip(round(target), a, b))
        if sweep.solved(key(guess), tol):
            guess = min(missing, key=lambda i: abs(i - target))
        sweep.run(np.array([key(guess)]), tol)


def _vertex(betas: Array, errors: Array, *, odds: bool = False) -> float:
    """β of the vertex of the parabola through the lowest of ``errors`` and its nearest neighbours
    on either side (else the three nearest; the lowest β when it has no minimum), fitted in
    ``1 / (1 − β)`` (``β / (1 − β)`` with ``odds``), where the dent deepens about linearly."""
    c = int(np.flatnonzero(errors <= errors.min() + _TIE_M)[0])
    left, right = betas < betas[c], betas > betas[c]
    if left.any() and right.any():
        pick = [int(np.flatnonzero(left)[np.argmax(betas[left])]), c,
                int(np.flatnonzero(right)[np.argmin(betas[right])])]
    else:
        pick = np.argsort(np.abs(betas - betas[c]), kind="stable")[:3].tolist()
    if len(pick) < 3:
        return float(betas[c])
    order = np.argsort(betas[pick])
    b = betas[pick][order]
    x = (b if odds else 1.0) / (1.0 - b)
    e = errors[pick][order]
    vertex, ok = parabola_vertex(x, e)
    if not ok:
        return float(betas[c])
    v = float(vertex)
    if odds:
        return v / (1.0 + v) if v > 0.0 else 0.0
    return float(1.0 - 1.0 / v) if v >= 1.0 else 0.0


def _best_index(errors: Array, compared: NDArray[np.bool_], converged: NDArray[np.bool_]) -> int:
    """Index of β̂: the lowest E among the ``compared`` β (solved to ``tol``) that converged;
    among all compared β when none did."""
    usable = compared & converged
    if not usable.any():
        usable = compared
    masked = np.where(usable, errors, np.inf)
    return int(np.flatnonzero(masked <= masked.min() + _TIE_M)[0])


def _beta_std(betas: Array, errors: Array, tol: float, resolution: float) -> float:
    """Width / √12 of the β interval around β̂ where E ≤ E(β̂) + ``tol`` (ends interpolated
    linearly, width at least ``resolution``)."""
    i = int(np.flatnonzero(errors <= errors.min() + _TIE_M)[0])
    level = errors[i] + tol
    ok = errors <= level
    lo = hi = i
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    while hi < len(betas) - 1 and ok[hi + 1]:
        hi += 1
    left, right = float(betas[lo]), float(betas[hi])
    if lo > 0:
        t = (level - errors[lo - 1]) / (errors[lo] - errors[lo - 1])
        left = float(betas[lo - 1] + t * (betas[lo] - betas[lo - 1]))
    if hi < len(betas) - 1:
        t = (level - errors[hi]) / (errors[hi + 1] - errors[hi])
        right = float(betas[hi] + t * (betas[hi + 1] - betas[hi]))
    return float(max(right - left, resolution) / np.sqrt(12.0))


def estimate_beta(rest_xs: Any, rest_ys: Any, rest_z: Any, deformed_points: Any,
                  contact: TactileContact, config: ShapeMatchingConfig | None = None,
                  *, height_samples: Any = None) -> BetaEstimate:
    """Estimate β for one poke (Caccamo et al. 2016, §III-C): E(β) on the sweep ``β_j = j /
    n_beta``, then (``refine``) on the ``beta_resolution`` grid within one step of the best β.

    Parameters
    ----------
    rest_xs, rest_ys, rest_z : (nx,), (ny,), (ny, nx) float, metres
        The ROI's heightmap before the poke; its edges are held fixed.
    deformed_points : (m, 3) float, metres
        The observed deformed surface X̄.
    height_samples : (S, m) float, metres, optional
        S ≥ 2 vertical errors of ``deformed_points``: ``beta_std`` is β̂'s spread over them.
    """
    cfg = _check_config(config)
    grid = ParticleGrid.from_heightmap(rest_xs, rest_ys, rest_z)
    observed = check_points("deformed_points", deformed_points, min_rows=1)
    model = PokeModel(grid.rest, grid.masses, grid.fixed, contact, cfg)
    sweep = _Sweep(model, cKDTree(observed, balanced_tree=False))  # faster queries, same distances
    sweep.run(np.arange(cfg.n_beta) / cfg.n_beta, cfg.coarse_tol)
    if cfg.refines:
        _refine(sweep, 1.0 / cfg.n_beta, cfg.beta_resolution, cfg.tol, odds=model.odds)
    betas, errors, its, res, conv, tols = sweep.curve()
    best = _best_index(errors, tols <= cfg.tol, conv)
    if height_samples is not None:
        positions = np.stack([sweep.sims[float(b)].positions[0] for b in betas])
        beta_std = sample_beta_std(betas, positions, observed, height_samples,
                                   resolution=cfg.beta_resolution)  # fmt: skip
    elif cfg.uncertainty == "bootstrap":
        tile = max(1, round(cfg.bootstrap_tile_m / grid.spacing_m))
        distances = np.stack([sweep.distances[float(b)] for b in betas])
        beta_std = bootstrap_beta_std(betas, distances, tile=tile, resolution=cfg.beta_resolution)
    else:
        beta_std = _beta_std(betas, errors, cfg.error_tolerance_m, cfg.beta_resolution)
    return BetaEstimate(
        beta=float(betas[best]), beta_std=beta_std, betas=betas, errors=errors, iterations=its,
        residual=res, converged=conv, tolerances=tols, protocol=cfg.contact, mode=cfg.mode,
        stiffness_n_per_m=model.stiffness,
        surface=np.array(sweep.sims[float(betas[best])].positions[0]))
