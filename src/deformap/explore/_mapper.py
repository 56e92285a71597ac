"""The mapper: surface GP and β-field state, updated one poke at a time.

The live loop (:mod:`deformap.explore._loop`) and a recorded session (:mod:`deformap.replay`) feed
the same mapper, so a poke gives the same β whichever way it arrives.

References
----------
Caccamo et al. (2016), Sec. III-D (the process flow this class follows).
Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes for Machine Learning, Eq. 2.24.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from deformap.cloud import (
    PointCloud,
    crop_box,
    height_field_mask,
    points_in_hull,
    statistical_outlier_mask,
    tactile_points,
)
from deformap.environment import PressObservation, TactileContact, Workspace
from deformap.errors import EnvironmentStateError, InvalidArgumentError
from deformap.explore._acquisition import boundary_score, choose_target
from deformap.explore._config import ExplorationConfig
from deformap.explore._dent_noise import dent_error_samples
from deformap.explore._planning import PokePlan, VarianceDesign, plan_pokes
from deformap.explore._regions import RegionMap, segment_regions
from deformap.gp import (
    GaussianRandomField,
    GPHyperparameters,
    default_bounds,
    fit_hyperparameters,
)
from deformap.msm import BetaEstimate, estimate_beta

__all__ = ["Mapper", "PokeResult", "SurfaceModel"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class SurfaceModel:
    """The surface GP ("GPR world") and its heightmap on the workspace grid."""

    gp: GaussianRandomField
    hyperparameters: GPHyperparameters
    height: NDArray[np.float64]  # (ny, nx)
    height_std: NDArray[np.float64]  # (ny, nx)
    n_raw: int
    points: NDArray[np.float64]  # (n, 3) the cropped, outlier-filtered cloud the GP was fitted to


@dataclass
class PokeResult:
    """One processed poke: its record for the journal and the arrays for its figure."""

    record: dict[str, Any]
    roi_xs: NDArray[np.float64] | None = None
    roi_ys: NDArray[np.float64] | None = None
    rest_z: NDArray[np.float64] | None = None
    deformed_z: NDArray[np.float64] | None = None
    roi_points: NDArray[np.float64] | None = None
    tactile: NDArray[np.float64] | None = None
    estimate: BetaEstimate | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def xy(self) -> NDArray[np.float64]:
        return np.asarray(self.record["contact_xy"], dtype=float)


_MAD_TO_STD = 1.4826
"""Standard deviation per median absolute deviation of a normal distribution."""


def _robust_std(residuals: NDArray[np.float64], floor: float = 1e-6) -> float:
    """Scatter of ``residuals`` as a normal standard deviation, from their median absolute
    deviation (so flying pixels and the dent's rim do not inflate it); at least ``floor``."""
    if residuals.size == 0:
        return floor
    mad = float(np.median(np.abs(residuals - np.median(residuals))))
    return max(_MAD_TO_STD * mad, floor)


def _contact_record(contact: TactileContact) -> dict[str, Any]:
    return {
        "tip_center": contact.tip_center.tolist(),
        "force": contact.force.tolist(),
        "tip_radius_m": contact.tip_radius_m,
    }


_PLAN_DOMAIN_M = 0.02
_PLAN_CANDIDATE_M = 0.02
_BOUNDARY_SPACING_ROI = 0.25
"""Boundary pokes keep this many ROI sizes (3 cm with the 12 cm ROI) from every poke: a dent
spreads a few centimetres, so closer pokes would measure much the same foam again."""


def _strided(nx: int, ny: int, step_m: float, spacing_m: float,
             within: NDArray[np.bool_] | None = None) -> NDArray[np.int64]:
    """Flat indices of the ``(ny, nx)`` grid's cells about ``step_m`` apart, its first and last
    rows and columns included (of the cells in ``within`` only, which must be a non-empty
    rectangle of cells, as the workspace and its targets are; the lattice then spans it)."""
    inside = np.ones(ny * nx, dtype=bool) if within is None else within
    rows, cols = np.nonzero(inside.reshape(ny, nx))
    stride = max(1, round(step_m / spacing_m))

    def keep(lo: int, hi: int) -> NDArray[np.int64]:
        return np.unique(np.append(np.arange(lo, hi + 1, stride), hi))

    ys, xs = keep(rows.min(), rows.max()), keep(cols.min(), cols.max())
    flat = (ys[:, None] * nx + xs[None, :]).ravel()
    return flat[inside[flat]]


class Mapper:
    """State of one exploration: the surface model and the β-field over the poked places.

    Parameters
    ----------
    workspace : Workspace
        The rectangle to map; its 0.5 cm grid carries every map.
    config : ExplorationConfig
        Settings of every stage.
    """

    def __init__(self, workspace: Workspace, config: ExplorationConfig) -> None:
        self.workspace = workspace
        self.config = config
        self.xs, self.ys = workspace.grid(config.surface.grid_spacing_m)
        gx, gy = np.meshgrid(self.xs, self.ys)
        self.cells_xy = np.column_stack([gx.ravel(), gy.ravel()])
        # Targets keep half a ROI inside the workspace, so that each ROI lies on the surveyed
        # surface (not over its edge, where shape matching would have to explain a cliff).
        margin = min(config.touch.roi_size_m / 2, 0.25 * min(workspace.size))
        lo, hi = np.asarray(workspace.lower) + margin, np.asarray(workspace.upper) - margin
        self.target_mask = np.all((self.cells_xy >= lo) & (self.cells_xy <= hi), axis=1)
        # where the variance must fall below T_h
        self.stop_mask = (self.target_mask if config.stop_region == "targets"
                          else np.ones(len(self.cells_xy), dtype=bool))
        # the planner's grids, every 2 cm (edges included): of the stop region, where the variance
        # must fall (the σw = 0.2 m field's largest variance on it was within 1.2e-4 of the 0.5 cm
        # grid's on the 60×40 cm table; a plan short by that is planned again), and of the
        # targets, where a poke may be planned
        self._plan_domain = self.cells_xy[_strided(self.xs.size, self.ys.size, _PLAN_DOMAIN_M,
                                                   config.surface.grid_spacing_m,
                                                   within=self.stop_mask)]
        sub = _strided(self.xs.size, self.ys.size, _PLAN_CANDIDATE_M,
                       config.surface.grid_spacing_m, within=self.target_mask)
        self._plan_candidates = self.cells_xy[sub]
        self.last_plan: PokePlan | None = None
        # why the last target of next_target was chosen: "variance" (the strategy, until T_h)
        # or "boundary" (a boundary poke after it)
        self.last_purpose = "variance"
        self.surface: SurfaceModel | None = None
        self.pokes: list[PokeResult] = []
        self._field: GaussianRandomField | None = None

    # -- the surface ---------------------------------------------------------------------------
    def initialise(self, cloud: PointCloud, rng: np.random.Generator) -> SurfaceModel:
        """Crop and filter the first observation and fit the surface GP to it."""
        cfg = self.config.surface
        pts = self._crop(cloud.points, margin=0.0)
        if pts.shape[0] <= cfg.outlier_k:
            raise InvalidArgumentError(
                f"`cloud` must have more than {cfg.outlier_k} points on the workspace; "
                f"got {pts.shape[0]} (is it in the world frame, in metres?)"
            )
        kept = pts[statistical_outlier_mask(pts, cfg.outlier_k, cfg.outlier_std_ratio)]
        if kept.shape[0] >= cfg.outlier_k:
            kept = kept[height_field_mask(kept, cfg.outlier_k, cfg.max_slope_deg)]
        init = GPHyperparameters(
            length_scale=cfg.length_scale_m,
            signal_std=cfg.signal_std_m,
            noise_std=cfg.noise_std_m,
            log_marginal_likelihood=float("nan"),
        )
        hyper = init
        if cfg.fit_hyperparameters:
            bounds = default_bounds(kept[:, :2], kept[:, 2])
            bounds[0] = np.maximum(bounds[0], cfg.min_length_scale_m)
            hyper = fit_hyperparameters(
                kept[:, :2],
                kept[:, 2],
                rng=rng,
                init=init,
                max_points=cfg.max_fit_points,
                n_restarts=cfg.fit_restarts,
                bounds=bounds,
            )
        gp = GaussianRandomField(
            length_scale=hyper.length_scale,
            signal_std=hyper.signal_std,
            noise_std=hyper.noise_std,
        ).fit(kept[:, :2], kept[:, 2])
        height, std = gp.predict_grid(self.xs, self.ys, return_std=True)
        self.surface = SurfaceModel(gp, hyper, height, std, cloud.points.shape[0], kept)
        logger.info("surface GP: %d of %d points kept, %s", kept.shape[0], len(cloud), hyper)
        return self.surface

    def _crop(self, points: NDArray[np.float64], margin: float) -> NDArray[np.float64]:
        cfg = self.config.surface
        lo = [self.workspace.lower[0] - margin, self.workspace.lower[1] - margin, cfg.z_min_m]
        hi = [self.workspace.upper[0] + margin, self.workspace.upper[1] + margin, cfg.z_max_m]
        return points[crop_box(points, lo, hi)]

    # -- one poke ------------------------------------------------------------------------------
    def roi_grid(self, center_xy: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
        """Node coordinates of the square ROI (odd count, so the centre is a node)."""
        spacing = self.config.surface.grid_spacing_m
        half = round(self.config.touch.roi_size_m / spacing / 2)
        offsets = np.arange(-half, half + 1) * spacing
        return center_xy[0] + offsets, center_xy[1] + offsets

    def process_press(self, obs: PressObservation, index: int) -> PokeResult:
        """Reconstruct the dent of one press and estimate its β (the β-field is not touched)."""
        if self.surface is None:
            raise EnvironmentStateError("the mapper needs `initialise(cloud)` before a poke")
        t0 = time.perf_counter()
        cfg = self.config.touch
        contact = obs.contact
        center = contact.contact_point[:2]
        roi_xs, roi_ys = self.roi_grid(center)
        pts = obs.cloud.points
        half = cfg.roi_size_m / 2
        lo = [center[0] - half, center[1] - half, self.config.surface.z_min_m]
        hi = [center[0] + half, center[1] + half, self.config.surface.z_max_m]
        pts = pts[crop_box(pts, lo, hi)]
        robot = points_in_hull(pts, obs.robot_points, tolerance_m=cfg.robot_margin_m)
        tip = contact.tip_radius_m + cfg.tip_margin_m
        robot |= np.linalg.norm(pts - contact.tip_center, axis=1) < tip
        pts = pts[~robot]
        k = self.config.surface.outlier_k
        if pts.shape[0] >= k:
            pts = pts[height_field_mask(pts, k, cfg.max_slope_deg)]
        rest_at = self.surface.gp.predict(pts[:, :2])
        on_surface = pts[:, 2] - rest_at <= cfg.above_surface_m
        roi, rest_at = pts[on_surface], rest_at[on_surface]
        tactile = tactile_points(
            contact.tip_center, contact.force, contact.tip_radius_m, n=cfg.n_tactile
        )
        t1 = time.perf_counter()
        rest_z = np.asarray(self.surface.gp.predict_grid(roi_xs, roi_ys))
        data = np.vstack([roi, tactile])
        noise = np.concatenate(
            [np.full(len(roi), cfg.noise_std_m), np.full(len(tactile), cfg.tactile_noise_std_m)]
        )
        target = data[:, 2]
        if cfg.model == "residual":
            target = target - np.concatenate([rest_at, self.surface.gp.predict(tactile[:, :2])])
        touch = GaussianRandomField(
            length_scale=cfg.length_scale_m,
            signal_std=cfg.signal_std_m,
            noise_std=cfg.noise_std_m,
            method="auto",
        ).fit(data[:, :2], target, noise_std=noise)
        deformed_z = np.asarray(touch.predict_grid(roi_xs, roi_ys))
        if cfg.model == "residual":
            deformed_z = deformed_z + rest_z
        gx, gy = np.meshgrid(roi_xs, roi_ys)
        deformed = np.column_stack([gx.ravel(), gy.ravel(), deformed_z.ravel()])
        t2 = time.perf_counter()
        samples, camera_noise = None, None
        if cfg.noise_samples:
            # The camera's noise here, from the points' scatter about the reconstruction (robust:
            # median absolute deviation); the touch GP's σₙ is a prior setting, not a measurement.
            fitted = np.asarray(touch.predict(roi[:, :2])) if len(roi) else np.zeros(0)
            camera_noise = _robust_std(np.asarray(target[: len(roi)]) - fitted)
            samples = dent_error_samples(
                roi_xs, roi_ys, roi[:, :2], camera_noise, tactile[:, :2],
                cfg.tactile_noise_std_m, length_scale_m=cfg.length_scale_m,
                signal_std_m=cfg.signal_std_m, n_samples=cfg.noise_samples,
            )  # fmt: skip
        est = estimate_beta(roi_xs, roi_ys, rest_z, deformed, contact, self.config.shape_matching,
                            height_samples=samples)  # fmt: skip
        t3 = time.perf_counter()
        record = {
            "index": index,
            "target_xy": obs.target_xy.tolist(),
            "contact_xy": center.tolist(),
            "contact": _contact_record(contact),
            "force_n": obs.force_n,
            "beta": float(est.beta),
            "beta_std": float(est.beta_std),
            "betas": np.asarray(est.betas).tolist(),
            "errors": np.asarray(est.errors).tolist(),
            "iterations": int(np.max(est.iterations)),
            "residual": float(np.max(est.residual)),
            "converged": bool(np.all(est.converged)),
            "n_roi_points": len(roi),
            "camera_noise_m": camera_noise,
            "timings": {
                "filter_s": t1 - t0,
                "touch_gp_s": t2 - t1,
                "beta_s": t3 - t2,
            },
        }
        return PokeResult(record, roi_xs, roi_ys, rest_z, deformed_z, roi, tactile, est)

    def add(self, poke: PokeResult) -> None:
        """Add a processed (or journalled) poke to the β-field."""
        t0 = time.perf_counter()
        self.pokes.append(poke)
        self._field = self._fit_field(len(self.pokes))
        poke.record["max_variance_after"] = self.max_variance()
        poke.record.setdefault("timings", {})["field_s"] = time.perf_counter() - t0

    # -- the β-field ---------------------------------------------------------------------------
    def field(self, upto: int | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """β-field mean and variance on the workspace grid, each ``(ny, nx)``.

        ``upto`` gives the field as it was after that many pokes (for recordings and figures).
        """
        gp = self._field if upto is None or upto == len(self.pokes) else self._fit_field(upto)
        if gp is None:
            prior = self.config.beta_field.signal_std**2
            shape = (self.ys.size, self.xs.size)
            return np.full(shape, np.nan), np.full(shape, prior)
        mean, std = gp.predict_grid(self.xs, self.ys, return_std=True)
        return mean, std**2

    def _fit_field(self, upto: int) -> GaussianRandomField | None:
        if upto == 0:
            return None
        cfg = self.config.beta_field
        pokes = self.pokes[:upto]
        xy = np.array([p.xy for p in pokes])
        beta = np.array([p.record["beta"] for p in pokes])
        noise = np.maximum([p.record["beta_std"] for p in pokes], cfg.noise_floor)
        return GaussianRandomField(
            length_scale=cfg.length_scale_m,
            signal_std=cfg.signal_std,
            noise_std=cfg.noise_floor,
            method="exact",
        ).fit(xy, beta, noise_std=noise)

    def max_variance(self) -> float:
        """The β-field's largest variance where it must fall below ``T_h`` (``stop_region``)."""
        return float(self.field()[1].ravel()[self.stop_mask].max())

    def next_target(self, rng: np.random.Generator) -> NDArray[np.float64] | None:
        """The next target by the configured strategy until the variance is under ``T_h``, then
        the boundary pokes (``boundary_pokes``; ``last_purpose`` says which); ``None`` when the
        variance is under ``T_h`` and no boundary poke is owed or none has a place left
        (``planned``: the plan a target came from is kept in ``last_plan``)."""
        self.last_plan = None
        self.last_purpose = "variance"
        mean, var = self.field()
        variance = var.ravel()
        if variance[self.stop_mask].max() <= self.config.threshold:
            if self.boundary_owed() == 0:
                return None
            self.last_purpose = "boundary"
            target = self._boundary_target(mean, var)
            if target is None:
                logger.warning(
                    "%d of %d boundary pokes left undone: no reachable place is %.3g m from "
                    "every poke", self.boundary_owed(), self.config.boundary_pokes,
                    _BOUNDARY_SPACING_ROI * self.config.touch.roi_size_m)
            return target
        cells, reachable = self.cells_xy[self.target_mask], variance[self.target_mask]
        if reachable.max() <= self.config.threshold:
            # Only the edge band, where no poke fits, is still uncertain. The plan covers it;
            # the other strategies poke the reachable cell of largest variance, the one nearest
            # the band's worst corner. (Poking where one poke leaves the least largest variance
            # instead is myopic: it splits the difference between two corners and took 12 pokes
            # with `paper` on homogeneous-60, seed 0, where this rule took 10.)
            if self.config.strategy == "planned":
                return self._planned_target()
            return np.array(cells[int(np.argmax(reachable))], dtype=float)
        return choose_target(
            self.config.strategy,
            cells,
            reachable,
            self.config.threshold,
            rng,
            look_ahead=self._max_variance_after,
            planner=self._planned_target,
        )

    def boundary_owed(self) -> int:
        """Boundary pokes still to make (``boundary_pokes`` less those made)."""
        made = sum(p.record.get("purpose") == "boundary" for p in self.pokes)
        return max(0, self.config.boundary_pokes - made)

    def _boundary_target(self, mean: NDArray[np.float64],
                         var: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Where a region boundary is least certain (:func:`boundary_score`) on the current
        β-field (``mean``, ``var``), among the reachable cells at least a quarter ROI from every
        poke; ``None`` when no such cell is left."""
        xy, _ = self._poked()
        spacing = _BOUNDARY_SPACING_ROI * self.config.touch.roi_size_m
        allowed = self.target_mask & (cKDTree(xy).query(self.cells_xy, k=1)[0] >= spacing)
        if not allowed.any():
            return None
        score = boundary_score(mean.ravel()[allowed], np.sqrt(var.ravel()[allowed]),
                               self._classes(mean).levels)
        return np.array(self.cells_xy[allowed][int(np.argmax(score))], dtype=float)

    def _planned_target(self) -> NDArray[np.float64]:
        """The next poke of the plan with the fewest further pokes (``planned`` strategy)."""
        cfg = self.config.beta_field
        xy, noise = self._poked()
        self.last_plan = plan_pokes(
            xy, noise, self._plan_candidates, self._plan_domain,
            signal_std=cfg.signal_std, length_scale=cfg.length_scale_m,
            new_noise=cfg.noise_floor, threshold=self.config.threshold,
            max_new=max(1, self.config.max_pokes - len(self.pokes)),
        )  # fmt: skip
        return np.array(self.last_plan.targets[0], dtype=float)

    def _max_variance_after(self, candidates: NDArray[np.float64]) -> NDArray[np.float64]:
        """Largest posterior variance where it must fall below ``T_h`` (``stop_region``) if each
        candidate were poked next (``min-max-variance``): an exact rank-one update of the
        posterior (the variance does not depend on the β that the poke will give), the new
        poke's noise at the floor."""
        cfg = self.config.beta_field
        xy, noise = self._poked()
        design = VarianceDesign(xy, noise, candidates, self.cells_xy[self.stop_mask],
                                cfg.signal_std, cfg.length_scale_m, cfg.noise_floor)
        return design.after([], self.config.threshold)[1]

    def _poked(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Where the pokes were, ``(p, 2)``, and the noise the β-field gives each, ``(p,)``."""
        floor = self.config.beta_field.noise_floor
        xy = np.array([p.xy for p in self.pokes], dtype=float).reshape(-1, 2)
        noise = np.maximum([p.record["beta_std"] for p in self.pokes], floor)
        return xy, np.asarray(noise, dtype=float).reshape(-1)

    def _classes(self, mean: NDArray[np.float64]) -> RegionMap:
        """The pokes' classes and the isopleth labels of the β-field mean ``mean``."""
        beta = np.array([p.record["beta"] for p in self.pokes])
        floor = self.config.beta_field.noise_floor
        std = np.maximum([p.record["beta_std"] for p in self.pokes], floor)
        return segment_regions(
            mean, beta, std, floor=floor, max_regions=self.config.max_regions,
            prior_dof=self.config.region_prior_dof,
        )  # fmt: skip

    def regions(self) -> RegionMap:
        """Cut the current β-field into regions (see :mod:`deformap.explore._regions`)."""
        if self._field is None:
            raise EnvironmentStateError("no poke yet: the β-field has no regions")
        found = self._classes(self.field()[0])
        if self.config.region_labels == "nearest":
            return found.nearest_poke(self._poked()[0], self.cells_xy)
        return found
