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
from deformap.msm._parabola import parabola_vertex
from deformap.msm._poke import PokeSimulation
from deformap.msm._simulate import PokeModel, _check_config
from deformap.msm._uncertainty import bootstrap_beta_std, sample_beta_std

__all__ = ["BetaEstimate", "estimate_beta", "matching_error"]

logger = logging.getLogger(__name__)
Array = NDArray[np.float64]

_MAX_SPLIT = 0.3
"""A β steps with the factorisation of a smaller β already factorised when the splitting's
contraction bound ``(β − β′) / (1 − β′)`` is at most this (:meth:`StepMatrices.solve`): a
splitting that removes at least 70 % of the error per step costs the β only a few iterations more
than its own factorisation would, and saves that factorisation."""

_KEEP_FACTORS = 3
"""Banded factorisations a β search keeps (:attr:`StepMatrices.max_factors`)."""

_TIE_M = 1e-9
"""E values within a nanometre are ties (round-off): β̂ is then the smallest, most rigid β."""


@dataclass(frozen=True, kw_only=True)
class BetaEstimate:
    """Result of :func:`estimate_beta`.

    Parameters
    ----------
    beta : float
        β̂, the minimiser of E(β) over the converged β solved to ``config.tol`` (over all of
        them if none converged); E values within 1 nm are ties and the most rigid is taken, so a
        flat E(β) gives β̂ = 0.
    beta_std : float
        Standard deviation of β̂ (``config.uncertainty``, or the spread over ``height_samples``),
        at least ``beta_resolution / √12``.
    betas : (n,) float
        Every β simulated, sorted (the uniform sweep plus the refinement).
    errors : (n,) float, metres
        E(β) at those β.
    iterations : (n,) int
    residual : (n,) float
    converged : (n,) bool
        Convergence of each β's simulation (see :class:`PokeSimulation`), of its last solve: to
        ``config.tol`` for every β the refinement compared (and for all β without refinement),
        to ``config.sweep_tol`` for the other swept β.
    tolerances : (n,) float
        The relative fixed-point tolerance each β was last solved to.
    protocol : str
        ``"force"`` or ``"pinned"``.
    mode : str
    stiffness_n_per_m : float or None
        Calibrated spring stiffness of the force protocol.
    surface : (ny, nx, 3) float, metres, or None
        The simulated body's surface particles at β̂ (at rest on the ROI grid): the dent shape
        matching explains the observed one with, for figures and recordings.
    """

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
    """The paper's E(β) = (1/K) Σ_i min_j ‖g_i(β) − x̄_j‖ of each simulated body.

    Parameters
    ----------
    positions : (B, ny, nx, 3) float, metres
        Simulated particle positions for ``B`` values of β (``PokeSimulation.positions``).
    tree : scipy.spatial.cKDTree
        Built on the observed deformed points ``x̄`` (``(n, 3)``, metres).

    Returns
    -------
    (B,) float, metres
        Mean distance from the ``K`` particles to their nearest observed point.
    """
    d = particle_distances(positions, tree)
    return np.asarray(d.reshape(d.shape[0], -1).mean(axis=1))


class _Sweep:
    """E(β) of one poke, each β solved once per tolerance and started from the β already solved.

    A β first solved to a loose tolerance (the coarse sweep) is solved again, from its own
    equilibrium, when it is asked for at a tighter one. A β steps with the banded factorisation
    of a smaller β already factorised when the splitting's contraction bound is at most
    ``_MAX_SPLIT`` (see :meth:`StepMatrices.solve`), else with its own.
    """

    def __init__(self, model: PokeModel, tree: cKDTree):
        self.model, self.tree = model, tree
        # each solve needs one factorisation and the sweep moves on through β: a few kept
        # suffice, and reusing their arrays spares fresh memory (whose page faults cost about as
        # much as a banded factorisation)
        model.system.max_factors = _KEEP_FACTORS
        self.sims: dict[float, tuple[PokeSimulation, int]] = {}
        self.errors: dict[float, float] = {}
        self.distances: dict[float, Array] = {}
        self.tols: dict[float, float] = {}
        self._body: dict[float, Array] = {}

    def solved(self, beta: float, tol: float) -> bool:
        """Whether ``beta`` has been solved to ``tol`` or tighter."""
        return self.tols.get(beta, np.inf) <= tol

    def run(self, betas: Array, tol: float) -> None:
        """Solve those of ``betas (B,)`` not yet solved to ``tol``, one after another in the given
        order, each started from the β already solved (:meth:`_start`)."""
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
            self.sims[key] = (sim, 0)
            self.errors[key] = float(dist.mean())
            self.distances[key] = dist
            self.tols[key] = tol
            self._body[key] = body[0]

    def _start(self, beta: float) -> Array | None:
        """Starting positions for ``beta``: its own loosely solved equilibrium; else linear in the dent's
        amplitude ``v`` (:meth:`PokeModel.amplitude`) through the two nearest solved β; else the
        nearest deformed one's displacements (or, with only β = 0 solved, the calibration's dent of
        amplitude 1) scaled by the ratio of ``v``; ``None`` (the model's own start) when none is solved.
        """
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
        """Sorted β, E(β), iterations, residuals, converged flags and tolerances of every β
        solved (its latest, tightest solve)."""
        betas = np.array(sorted(self.sims))
        rows = [self.sims[float(b)] for b in betas]
        errors = np.array([self.errors[float(b)] for b in betas])
        its = np.array([sim.iterations[j] for sim, j in rows], dtype=np.int64)
        res = np.array([sim.residual[j] for sim, j in rows])
        conv = np.array([sim.converged[j] for sim, j in rows], dtype=bool)
        tols = np.array([self.tols[float(b)] for b in betas])
        return betas, errors, its, res, conv, tols


def _refine(sweep: _Sweep, step: float, resolution: float, tol: float, *,
            odds: bool = False) -> None:
    """Find the minimum of E on the ``resolution`` grid within one ``step`` of the best swept β.

    E(β) is smooth, so there it is unimodal, and a grid point whose two grid neighbours are both
    higher is the minimum. The search solves one grid point at a time: the vertex of the
    parabola (:func:`_vertex`) through the lowest β solved so far and its nearest solved
    neighbours, rounded to the grid, or, when that point is already solved to ``tol``, the
    unsolved grid neighbour of the lowest point solved to ``tol`` nearest that vertex; it stops
    when that lowest point has both grid neighbours solved to ``tol``: a few solves instead of the
    ``2 step / resolution`` of an exhaustive grid, with the same grid minimum. Every β compared is
    solved to ``tol``; the loosely swept β only guide the parabola.
    """
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
    """β of the vertex of the parabola through the lowest of ``errors`` and its nearest
    neighbours in ``betas`` on either side (the three nearest β when one side has none); the
    lowest β itself when that parabola has no minimum.

    The parabola is fitted in ``v = 1 / (1 − β)``: the β-dependent part of the goals stiffens
    the body in proportion to ``1 − β`` (``K_β``'s smallest eigenvalues, see
    :mod:`deformap.msm._linsys`), so the simulated dent deepens, and E changes, about linearly
    in ``v``; a parabola in β puts the vertex systematically on the rigid side. With ``odds``
    (the odds scale, springs ``k / β``) the dent goes as ``v = β / (1 − β)`` instead.
    """
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
    """Index of β̂: the lowest E among the β the refinement compared (solved to ``tol``; a loosely
    swept β's E is good to the sweep tolerance only and may fall below the converged minimum)
    that also converged (a β stopped by ``max_iter`` has an E of a state that is not its
    equilibrium); among all compared β when none converged (``all_converged`` then says so)."""
    usable = compared & converged
    if not usable.any():
        usable = compared
    masked = np.where(usable, errors, np.inf)
    return int(np.flatnonzero(masked <= masked.min() + _TIE_M)[0])


def _beta_std(betas: Array, errors: Array, tol: float, resolution: float) -> float:
    """Width / √12 of the β interval around β̂ where E ≤ E(β̂) + ``tol``; its ends are found by
    linear interpolation of E between the sampled β, so that the width does not depend on how
    densely the sweep sampled the curve (at least ``resolution``)."""
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
    """Estimate β for one poke (Caccamo et al. 2016, Eq. for E(β)).

    Parameters
    ----------
    rest_xs : (nx,) float, rest_ys : (ny,) float, rest_z : (ny, nx) float, metres
        The ROI's heightmap before the poke (the surface GP's mean); its edges are held fixed.
    deformed_points : (m, 3) float, metres
        The observed deformed surface X̄ (e.g. the touch GP's mean on the ROI grid).
    contact : TactileContact
        The poke's tip position, force and tip radius.
    config : ShapeMatchingConfig
    height_samples : (S, m) float, metres, optional
        Plausible vertical errors of ``deformed_points`` (for example draws from the touch GP's
        posterior), S ≥ 2. When given, ``beta_std`` is the spread of β̂ over the observed surfaces
        they give (:func:`deformap.msm._uncertainty.sample_beta_std`: the observation noise
        propagated through the estimate) and ``config.uncertainty`` is not used.

    Returns
    -------
    BetaEstimate

    Notes
    -----
    E(β) is evaluated on a uniform sweep ``β_j = j / n_beta`` over ``[0, 1)``, each β started
    from the equilibria of those already solved, then (``refine``) on a ``beta_resolution`` grid
    within one sweep step of the best β (a parabolic search that ends at the grid minimum). Each
    particle's simulated position is its equilibrium position, which equals its goal ``g_i(β)``
    except on the particles that carry the tactile force.

    References
    ----------
    Caccamo, S. et al. (2016). Active Perception and Modeling of Deformable Surfaces using Gaussian
    Processes and Position-based Dynamics. IEEE-RAS Humanoids, §III-C.
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
        positions = np.stack([sweep.sims[float(b)][0].positions[sweep.sims[float(b)][1]]
                              for b in betas])  # fmt: skip
        beta_std = sample_beta_std(betas, positions, observed, height_samples,
                                   resolution=cfg.beta_resolution)  # fmt: skip
    elif cfg.uncertainty == "bootstrap":
        tile = max(1, round(cfg.bootstrap_tile_m / grid.spacing_m))
        distances = np.stack([sweep.distances[float(b)] for b in betas])
        beta_std = bootstrap_beta_std(betas, distances, tile=tile, resolution=cfg.beta_resolution)
    else:
        beta_std = _beta_std(betas, errors, cfg.error_tolerance_m, cfg.beta_resolution)
    return BetaEstimate(
        beta=float(betas[best]),
        beta_std=beta_std,
        betas=betas, errors=errors, iterations=its, residual=res, converged=conv,
        tolerances=tols, protocol=cfg.contact, mode=cfg.mode, stiffness_n_per_m=model.stiffness,
        surface=_surface_at(sweep, float(betas[best])),
    )


def _surface_at(sweep: _Sweep, beta: float) -> Array:
    """The surface particles ``(ny, nx, 3)`` of the body solved at ``beta``."""
    sim, j = sweep.sims[beta]
    return np.array(sim.positions[j])
