"""One press: the dent reconstructed from the cloud seen while pressing, and its β.

1. The ROI, a square of ``roi_size_m`` centred on the contact, is cropped from the cloud; the
   robot's points are removed (the convex hull of its stick and hand plus ``robot_margin_m``, a
   ball of the tip's radius plus ``tip_margin_m``), then steep faces, then every point more than
   ``above_surface_m`` above the surface model (a dent goes down).
2. The touch GP ("GPR-touch") is fitted to those points and ``n_tactile`` tactile points on the
   tip's cap, by default as the change of height against the surface model (``model="residual"``),
   and read on the ROI's grid: the deformed heightmap X̄.
3. Shape matching from the ROI's heightmap before the press gives β̂
   (:func:`deformap.msm.estimate_beta`). Its uncertainty is the camera's noise, measured in the
   ROI by the points' median absolute deviation about X̄, carried through the estimate
   (:func:`deformap.explore._dent_noise.dent_error_samples`) when ``beta_uncertainty`` is
   ``camera-noise``; else the shape matcher's own (``shape_matching.uncertainty``).

References
----------
Caccamo et al. (2016), Sec. III-B and III-C.
"""

from __future__ import annotations

import logging
import time

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import height_field_mask, points_in_hull, tactile_points
from deformap.environment import PressObservation
from deformap.errors import DeformapError
from deformap.explore._config import ExplorationConfig
from deformap.explore._dent_noise import dent_error_samples
from deformap.explore._records import ContactRecord, Dent, PokeRecord, PokeResult, PokeTimings
from deformap.explore._stiffness import StiffnessEstimate, estimate_stiffness
from deformap.explore._surface import SurfaceModel, crop_to
from deformap.gp import GaussianRandomField
from deformap.msm import estimate_beta

__all__ = ["measure_press", "roi_grid"]

logger = logging.getLogger(__name__)

_MAD_TO_STD = 1.4826
"""Standard deviation per median absolute deviation of a normal distribution."""


def _robust_std(residuals: NDArray[np.float64], floor: float = 1e-6) -> float:
    """Scatter of ``residuals`` as a normal standard deviation, from their median absolute
    deviation (so flying pixels and the dent's rim do not inflate it); at least ``floor``."""
    if residuals.size == 0:
        return floor
    mad = float(np.median(np.abs(residuals - np.median(residuals))))
    return max(_MAD_TO_STD * mad, floor)


def roi_grid(center_xy: NDArray[np.float64], roi_size_m: float,
             spacing_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Node coordinates ``(xs, ys)`` of the square ROI (odd count, so the centre is a node)."""
    half = round(roi_size_m / spacing_m / 2)
    offsets = np.arange(-half, half + 1) * spacing_m
    return center_xy[0] + offsets, center_xy[1] + offsets


def _roi_points(obs: PressObservation, surface: SurfaceModel, config: ExplorationConfig
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The ROI's surface points while pressing, ``(m, 3)``, and the surface model under them."""
    cfg = config.touch
    contact = obs.contact
    center = contact.contact_point[:2]
    half = cfg.roi_size_m / 2
    pts = crop_to(obs.cloud.points, center - half, center + half, config.surface)
    robot = points_in_hull(pts, obs.robot_points, tolerance_m=cfg.robot_margin_m)
    tip = contact.tip_radius_m + cfg.tip_margin_m
    robot |= np.linalg.norm(pts - contact.tip_center, axis=1) < tip
    pts = pts[~robot]
    k = config.surface.outlier_k
    if pts.shape[0] >= k:
        pts = pts[height_field_mask(pts, k, cfg.max_slope_deg)]
    rest_at = surface.gp.predict(pts[:, :2])
    on_surface = pts[:, 2] - rest_at <= cfg.above_surface_m
    return pts[on_surface], rest_at[on_surface]


def _stiffness(obs: PressObservation, surface: SurfaceModel, config: ExplorationConfig
               ) -> tuple[StiffnessEstimate | None, float | None, str | None]:
    """Stiffness and modulus from the press's force–travel record, the layer thickness they were
    read with (the surface model's height above the table, z = 0, at the contact), and why a
    record gave none (the poke then stands on the camera alone); all ``None`` without a record."""
    record = obs.force_travel
    if record is None:
        return None, None, None
    center = obs.contact.contact_point[:2]
    mean, std = surface.gp.predict(center[None, :], return_std=True)
    thickness = float(np.asarray(mean).reshape(-1)[0])
    try:
        estimate = estimate_stiffness(record.travel_m, record.force_n,
                                      tip_radius_m=obs.contact.tip_radius_m,
                                      thickness_m=thickness, commanded_force_n=obs.force_n,
                                      thickness_std_m=float(np.asarray(std).reshape(-1)[0]),
                                      config=config.stiffness)  # fmt: skip
    except DeformapError as exc:
        logger.warning("force–travel record not used (the camera alone reads this poke): %s", exc)
        return None, thickness, str(exc)
    return estimate, thickness, None


def measure_press(obs: PressObservation, index: int, surface: SurfaceModel,
                  config: ExplorationConfig) -> PokeResult:
    """Reconstruct the dent of one press and estimate its β.

    Parameters
    ----------
    obs : PressObservation
        What the environment returned for the press (world frame, SI units).
    index : int
        The poke's place in its run.
    surface : SurfaceModel
        The surface before any poke.
    config : ExplorationConfig
        Its ``touch``, ``surface`` and ``shape_matching`` settings are used.

    Returns
    -------
    PokeResult
        The record (not yet in a β-field: no ``purpose``, ``max_variance_after`` or field time),
        the dent and the full estimate.
    """
    t0 = time.perf_counter()
    cfg = config.touch
    contact = obs.contact
    center = contact.contact_point[:2]
    roi_xs, roi_ys = roi_grid(center, cfg.roi_size_m, config.surface.grid_spacing_m)
    roi, rest_at = _roi_points(obs, surface, config)
    tactile = tactile_points(contact.tip_center, contact.force, contact.tip_radius_m,
                             n=cfg.n_tactile)  # fmt: skip
    t1 = time.perf_counter()
    rest_z = np.asarray(surface.gp.predict_grid(roi_xs, roi_ys))
    data = np.vstack([roi, tactile])
    noise = np.concatenate(
        [np.full(len(roi), cfg.noise_std_m), np.full(len(tactile), cfg.tactile_noise_std_m)]
    )
    target = data[:, 2]
    if cfg.model == "residual":
        target = target - np.concatenate([rest_at, surface.gp.predict(tactile[:, :2])])
    touch = GaussianRandomField(
        length_scale=cfg.length_scale_m, signal_std=cfg.signal_std_m,
        noise_std=cfg.noise_std_m, method="auto",
    ).fit(data[:, :2], target, noise_std=noise)  # fmt: skip
    deformed_z = np.asarray(touch.predict_grid(roi_xs, roi_ys))
    if cfg.model == "residual":
        deformed_z = deformed_z + rest_z
    gx, gy = np.meshgrid(roi_xs, roi_ys)
    deformed = np.column_stack([gx.ravel(), gy.ravel(), deformed_z.ravel()])
    t2 = time.perf_counter()
    samples, camera_noise = None, None
    if config.beta_uncertainty == "camera-noise":
        # The camera's noise here, from the points' scatter about the reconstruction; the touch
        # GP's σₙ is a prior setting, not a measurement.
        fitted = np.asarray(touch.predict(roi[:, :2])) if len(roi) else np.zeros(0)
        camera_noise = _robust_std(np.asarray(target[: len(roi)]) - fitted)
        samples = dent_error_samples(
            roi_xs, roi_ys, roi[:, :2], camera_noise, tactile[:, :2],
            cfg.tactile_noise_std_m, length_scale_m=cfg.length_scale_m,
            signal_std_m=cfg.signal_std_m, n_samples=cfg.noise_samples,
        )  # fmt: skip
    est = estimate_beta(roi_xs, roi_ys, rest_z, deformed, contact, config.shape_matching,
                        height_samples=samples)  # fmt: skip
    t3 = time.perf_counter()
    stiffness, thickness, stiffness_error = _stiffness(obs, surface, config)
    t4 = time.perf_counter()
    target_xy = obs.target_xy
    record = PokeRecord(
        index=index,
        target_xy=(float(target_xy[0]), float(target_xy[1])),
        contact_xy=(float(center[0]), float(center[1])),
        contact=ContactRecord.of(contact),
        force_n=float(obs.force_n),
        beta=float(est.beta),
        beta_std=float(est.beta_std),
        betas=tuple(float(b) for b in np.asarray(est.betas)),
        errors=tuple(float(e) for e in np.asarray(est.errors)),
        iterations=int(np.max(est.iterations)),
        residual=float(np.max(est.residual)),
        converged=bool(np.all(est.converged)),
        n_roi_points=len(roi),
        camera_noise_m=camera_noise,
        timings=PokeTimings(filter_s=t1 - t0, touch_gp_s=t2 - t1, beta_s=t3 - t2,
                            stiffness_s=None if obs.force_travel is None else t4 - t3),
        stiffness=stiffness, layer_thickness_m=thickness, stiffness_error=stiffness_error,
    )
    dent = Dent(roi_xs, roi_ys, rest_z, deformed_z, roi, tactile)
    return PokeResult(record, dent, est)
