"""Public entry points of the simulator: goals for given positions, and the poke equilibrium."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_instance, check_positive
from deformap.errors import InvalidArgumentError
from deformap.mechanics import TactileContact
from deformap.msm._clusters import Clusters
from deformap.msm._config import ShapeMatchingConfig
from deformap.msm._linsys import StepMatrices
from deformap.msm._poke import (
    Equilibrium,
    PokeSimulation,
    Solution,
    calibrate_stiffness,
    force_weights,
)

__all__ = ["PokeModel", "shape_matching_goals", "simulate_poke"]

Array = NDArray[np.float64]


def check_betas(betas: Any) -> Array:
    arr = check_array("betas", np.atleast_1d(betas), (None,), what="β values", min_rows=1)
    bad = (arr < 0.0) | (arr >= 1.0)
    if np.any(bad):
        raise InvalidArgumentError(f"`betas` must lie in [0, 1); got {arr[bad][:5]}")
    return arr


def _check_config(config: Any) -> ShapeMatchingConfig:
    return ShapeMatchingConfig() if config is None else check_instance(
        "config", config, ShapeMatchingConfig)


def _check_rest(rest: Any, k: int) -> Array:
    arr = check_array("rest", rest, (None, None, 3), what="particle positions in metres")
    if arr.shape[0] < k or arr.shape[1] < k:
        raise InvalidArgumentError(f"`rest` must hold at least cluster_size × cluster_size = {k}×{k} "
                                   f"particles; got a {arr.shape[0]}×{arr.shape[1]} grid")
    return arr


def shape_matching_goals(rest: Any, current: Any, betas: Any,
                         config: ShapeMatchingConfig | None = None) -> Array:
    """Müller's goals ``(B, ny, nx, 3)`` of particles at ``current (B, ny, nx, 3)`` for ``betas
    (B,)`` in [0, 1) and ``rest (ny, nx, 3)`` (equal masses), metres: ``g_i = (1/M_i) Σ_{c∋i}
    [((1 − β) R_c + β A_c) s_i + t_c]`` (Müller et al. 2005, Eqs. 7–9, §4.3; rigid: ``R_c``)."""
    cfg = _check_config(config)
    p0 = _check_rest(rest, cfg.cluster_size)
    b = check_betas(betas)
    x = check_array("current", current, (b.size, *p0.shape), what="particle positions in metres")
    k = cfg.cluster_size
    return Clusters(p0, np.ones(p0.shape[:2]), (k, k), cfg.mode, cfg.regularization).goals(x, b)


def _check_contact(contact: Any, rest: Array, fixed: NDArray[np.bool_], spacing: float) -> int:
    """The flat index of the particle nearest the (checked) contact."""
    cp = check_instance("contact", contact, TactileContact).contact_point
    lo = rest[..., :2].reshape(-1, 2).min(axis=0) - spacing
    hi = rest[..., :2].reshape(-1, 2).max(axis=0) + spacing
    if np.any(cp[:2] < lo) or np.any(cp[:2] > hi):
        raise InvalidArgumentError(
            f"`contact` must press inside the ROI [{lo[0] + spacing:.4f}, {hi[0] - spacing:.4f}] × "
            f"[{lo[1] + spacing:.4f}, {hi[1] - spacing:.4f}] m; got contact point xy "
            f"({cp[0]:.4f}, {cp[1]:.4f})")
    near = int(np.argmin(np.sum((rest[..., :2] - cp[:2]) ** 2, axis=-1)))
    if fixed.ravel()[near]:
        raise InvalidArgumentError(
            "`contact` presses on the ROI's fixed edge (its nearest particle is held at rest); "
            "centre the ROI on the contact")
    return near


def _rest_height_at(rest: Array, xy: Array) -> float:
    """Bilinear interpolation of the rest heightmap at ``xy``."""
    xs, ys = rest[0, :, 0], rest[:, 0, 1]
    i = int(np.clip(np.searchsorted(ys, xy[1]) - 1, 0, ys.size - 2))
    j = int(np.clip(np.searchsorted(xs, xy[0]) - 1, 0, xs.size - 2))
    ty = float(np.clip((xy[1] - ys[i]) / (ys[i + 1] - ys[i]), 0.0, 1.0))
    tx = float(np.clip((xy[0] - xs[j]) / (xs[j + 1] - xs[j]), 0.0, 1.0))
    z = rest[i : i + 2, j : j + 2, 2]
    return float((1 - ty) * ((1 - tx) * z[0, 0] + tx * z[0, 1])
                 + ty * ((1 - tx) * z[1, 0] + tx * z[1, 1]))


def simulate_poke(rest: Any, masses: Any, fixed: Any, contact: TactileContact, betas: Any,
                  config: ShapeMatchingConfig | None = None, *,
                  stiffness_n_per_m: float | None = None) -> PokeSimulation:
    """Static equilibrium under one poke for every β of ``betas (B,)`` in [0, 1); ``rest``,
    ``masses``, ``fixed`` as in :class:`ParticleGrid`. ``"pinned"`` holds the particle nearest the
    contact at the observed depth; ``"force"`` shares the force under the tip
    (:func:`force_weights`) on springs of the calibrated ``k`` (or ``stiffness_n_per_m``)."""
    cfg = _check_config(config)
    p0 = _check_rest(rest, cfg.cluster_size)
    b = check_betas(betas)
    model = PokeModel(p0, masses, fixed, contact, cfg, stiffness_n_per_m=stiffness_n_per_m)
    return model.solve(b)[0]


class PokeModel:
    """One poke on one ROI whose body, clusters, ``K_β`` and stiffness every :meth:`solve` shares."""

    def __init__(self, rest: Any, masses: Any, fixed: Any, contact: TactileContact,
                 config: ShapeMatchingConfig, *, stiffness_n_per_m: float | None = None):
        self.cfg = cfg = config
        p0 = _check_rest(rest, cfg.cluster_size)
        m = check_array("masses", masses, p0.shape[:2], what="particle masses")
        if np.any(m <= 0):
            raise InvalidArgumentError(f"`masses` must be > 0; got minimum {m.min()}")
        fx = np.asarray(fixed)
        if fx.shape != p0.shape[:2] or fx.dtype != np.bool_:
            raise InvalidArgumentError(f"`fixed` must be a {p0.shape[:2]} bool array; got "
                                       f"{np.asarray(fixed).dtype} array of shape {fx.shape}")
        if stiffness_n_per_m is not None:
            check_positive("stiffness_n_per_m", stiffness_n_per_m)
        self.odds = cfg.rigid_at_zero
        self.spacing = float(np.mean(np.linalg.norm(np.diff(p0[..., :2], axis=1), axis=-1)))
        near = _check_contact(contact, p0, fx, self.spacing)
        body, body_m, body_fixed, window = _body(p0, m, fx, self.spacing, cfg)
        self.clusters = Clusters(body, body_m, window, cfg.mode, cfg.regularization)
        flat = body.reshape(-1, 3)
        self.stiffness: float | None = None
        # the calibration's β = 0 equilibrium, a start for solves that have none closer
        self.start: Array | None = None
        self._calibrated: Solution | None = None
        if cfg.contact == "pinned":
            pinned = body_fixed.ravel().copy()
            pinned[near] = True  # the top layer comes first in the flat order
            self.fixed = pinned.reshape(body_fixed.shape)
            self.system = StepMatrices(self.clusters, self.fixed)
            self.x_fixed = flat[self.system.fix].copy()
            sink = contact.contact_point[2] - _rest_height_at(p0, contact.contact_point[:2])
            self.x_fixed[np.searchsorted(self.system.fix, near), 2] += sink
            self.force = np.zeros_like(flat)
            return
        self.fixed = body_fixed
        self.system = StepMatrices(self.clusters, self.fixed)
        weights = np.zeros(body_fixed.shape)
        weights[0] = force_weights(p0, fx, contact, self.spacing)
        self.x_fixed = flat[body_fixed.ravel()]
        self.force = weights.reshape(-1, 1) * contact.force[None, :]
        if stiffness_n_per_m is None:
            eq0 = Equilibrium(self.clusters, body_fixed, np.zeros(1), system=self.system)
            stiffness_n_per_m, self._calibrated = calibrate_stiffness(
                eq0, self.x_fixed, weights, contact, cfg, self.spacing)
            if self._calibrated is not None:
                self.start = self._calibrated[0]
        self.stiffness = float(stiffness_n_per_m)

    def load_scale(self, betas: Array) -> Array:
        """The share of the force each β's body carries: 1, or β on the ``"odds"`` scale."""
        b = np.asarray(betas, dtype=float)
        return b.copy() if self.odds else np.ones_like(b)

    def amplitude(self, beta: float) -> float:
        """How the dent deepens with β, about: ``1 / (1 − β)``, or the odds ``β / (1 − β)``."""
        return (beta if self.odds else 1.0) / (1.0 - beta)

    def calibrated(self, tol: float) -> tuple[PokeSimulation, Array] | None:
        """The calibration's converged β = 0 solve, if ``tol`` ≥ ``coarse_tol``; else ``None``."""
        solution = self._calibrated
        if solution is None or tol < self.cfg.coarse_tol or self.odds or not solution[3].all():
            return None
        return self._result(np.zeros(1), *solution)

    def _result(self, betas: Array, x: Array, it: NDArray[np.int64], res: Array,
                conv: NDArray[np.bool_]) -> tuple[PokeSimulation, Array]:
        return PokeSimulation(betas=betas, positions=x[:, 0], iterations=it, residual=res,
                              converged=conv, stiffness_n_per_m=self.stiffness), x

    def solve(self, betas: Array, x0: Array | None = None, tol: float | None = None, *,
              max_split: float = 0.0) -> tuple[PokeSimulation, Array]:
        """The surface's simulation and the body's positions for ``betas (B,)`` from ``x0 (B,
        *body, 3)`` (default :attr:`start`, else rest) to ``tol`` (default ``config.tol``)."""
        cfg = self.cfg
        betas = np.asarray(betas, dtype=float)
        rest = self.clusters.rest
        x = np.broadcast_to(rest, (len(betas), *rest.shape)).copy()
        it, res = np.zeros(len(betas), dtype=np.int64), np.zeros(len(betas))
        conv = np.ones(len(betas), dtype=bool)
        # on the odds scale β = 0 carries no load: the body at rest, exactly
        moving = self.load_scale(betas) > 0.0
        if moving.any():
            sub = betas[moving]
            if x0 is not None:
                x0 = np.asarray(x0)[moving]
            elif self.start is not None and self.odds:
                # the calibration's dent has amplitude 1 on the odds scale
                amp = np.array([self.amplitude(float(b)) for b in sub])
                x0 = rest + (self.start - rest) * amp.reshape(-1, *([1] * rest.ndim))
            elif self.start is not None:
                x0 = np.broadcast_to(self.start, (len(sub), *self.start.shape[1:]))
            eq = Equilibrium(self.clusters, self.fixed, sub, system=self.system,
                             max_split=max_split, load_scale=self.load_scale(sub))
            k = 1.0 if self.stiffness is None else self.stiffness
            x[moving], it[moving], res[moving], conv[moving] = eq.solve(
                self.x_fixed, self.force, k, cfg.tol if tol is None else tol, cfg.max_iter,
                self.spacing, x0=x0)
        return self._result(betas, x, it, res, conv)


def _body(p0: Array, masses: Array, fixed: NDArray[np.bool_], spacing: float,
          cfg: ShapeMatchingConfig) -> tuple[Array, Array, NDArray[np.bool_], tuple[int, ...]]:
    """The body: the surface sheet, or the surface over layers down to a fixed floor."""
    k, layers = cfg.cluster_size, cfg.body_layers
    if layers == 0:
        return p0[None], masses[None], fixed[None], (1, k, k)
    floor = 0.5 * min(float(np.ptp(p0[..., 0])), float(np.ptp(p0[..., 1])))
    steps = spacing * cfg.layer_growth ** np.arange(layers)
    depths = np.concatenate([[0.0], np.cumsum(steps)]) * (floor / np.sum(steps))
    body = np.repeat(p0[None], depths.size, axis=0)
    body[..., 2] -= depths[:, None, None]
    thick = np.gradient(depths) if depths.size > 1 else np.ones(1)
    body_m = masses[None] * thick[:, None, None] / spacing
    body_fixed = np.repeat(fixed[None], depths.size, axis=0)
    body_fixed[-1] = True
    return body, body_m, body_fixed, (2, k, k)
