"""One press: the dent reconstructed from the cloud seen while pressing, and its β.

1. The ROI is cropped from the cloud; the robot's points (hull and tip ball with margins), steep
   faces and points more than ``above_surface_m`` above the surface model are removed.
2. The touch GP is fitted to those points and the tactile points on the cap touching at the
   indentation δ (the force–travel record's, 0 if rigid, else the tip's depth below the surface
   model; with ``depth_anchor="record"`` they hang from the surface minus δ) and read on the ROI's
   grid: the deformed heightmap X̄.
3. Shape matching gives β̂ (:func:`deformap.msm.estimate_beta`); under ``camera-noise`` its σ is
   the camera's noise (the points' MAD about X̄) carried through the estimate
   (:mod:`deformap.explore._dent_noise`). A dent the camera cannot see (:func:`dent_visible`)
   claims a uniform β's σ = 1/√12; a press the record reads rigid reports β = 0 with the β grid's
   quantisation σ where β = 0 is rigid.

References
----------
Caccamo et al. (2016), Sec. III-B and III-C.
"""

from __future__ import annotations

import logging
import time

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import contact_cap, height_field_mask, points_in_hull, tactile_points
from deformap.environment import PressObservation, TactileContact
from deformap.errors import DeformapError
from deformap.explore._config import ExplorationConfig
from deformap.explore._dent_noise import dent_error_samples
from deformap.explore._records import (
    ContactRecord,
    Dent,
    PokeRecord,
    PokeResult,
    PokeTimings,
    poke_behaviour,
)
from deformap.explore._surface import SurfaceModel, crop_to
from deformap.gp import GaussianRandomField
from deformap.mechanics import layer_indentation_force
from deformap.msm import estimate_beta
from deformap.stiffness import DentSamples, StiffnessEstimate, estimate_stiffness

__all__ = ["dent_visible", "measure_press", "roi_grid"]

logger = logging.getLogger(__name__)

_MAD_TO_STD = 1.4826  # standard deviation per median absolute deviation of a normal
#: Standard deviation of a uniform β over [0, 1): a poke whose dent the camera cannot see.
UNINFORMED_BETA_STD = 1.0 / np.sqrt(12.0)
# the dent's flank, where the camera must see it: within two tip radii of the contact (the tip
# and stick hide the part inside one radius from most views)
_FLANK_TIP_RADII = 2.0


def _force_fit(obs: PressObservation, stiffness: StiffnessEstimate | None,
               thickness: float | None, config: ExplorationConfig) -> NDArray[np.float64] | None:
    """``(2, 60)`` travel [m] and force ``E g(t + δ₀)`` [N] of the fitted bonded-layer model (its
    own ``E``, whose ``δ₀`` the estimate carries), or ``None``."""
    record = obs.force_travel
    if record is None or stiffness is None or stiffness.modulus_pa is None or thickness is None:
        return None
    modulus = next((f.modulus_pa for f in stiffness.model_fits if f.name == "bonded-layer"),
                   stiffness.modulus_pa)
    travel = np.linspace(0.0, float(np.max(record.travel_m)), 60)
    depth = np.maximum(travel + (stiffness.contact_offset_m or 0.0), 0.0)
    force = layer_indentation_force(depth, obs.contact.tip_radius_m, thickness, modulus,
                                    config.stiffness.poisson_ratio)
    return np.vstack([travel, force])


def _robust_std(residuals: NDArray[np.float64], floor: float = 1e-6) -> float:
    """Scatter of ``residuals`` as a normal σ from their MAD (robust to flying pixels), ≥ ``floor``."""
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
    cfg, contact = config.touch, obs.contact
    center, half = contact.contact_point[:2], cfg.roi_size_m / 2
    pts = crop_to(obs.cloud.points, center - half, center + half, config.surface)
    robot = points_in_hull(pts, obs.robot_points, tolerance_m=cfg.robot_margin_m)
    robot |= np.linalg.norm(pts - contact.tip_center, axis=1) < contact.tip_radius_m + cfg.tip_margin_m
    pts = pts[~robot]
    k = config.surface.outlier_k
    if pts.shape[0] >= k:
        pts = pts[height_field_mask(pts, k, cfg.max_slope_deg)]
    rest_at = surface.gp.predict(pts[:, :2])
    on_surface = pts[:, 2] - rest_at <= cfg.above_surface_m
    return pts[on_surface], rest_at[on_surface]


def _stiffness(obs: PressObservation, surface: SurfaceModel, config: ExplorationConfig,
               roi: NDArray[np.float64], rest_at: NDArray[np.float64],
               ) -> tuple[StiffnessEstimate | None, float | None, str | None]:
    """The force–travel record's estimate, the layer thickness it was read with (the surface's
    height above z = 0 at the contact), and why a record gave none; all ``None`` without one.
    The ROI's points (``roi``, the surface at rest under them ``rest_at``) give the dent's
    shape, their correlation tested over the touch model's length scale."""
    record = obs.force_travel
    if record is None:
        return None, None, None
    center = obs.contact.contact_point[:2]
    dent = DentSamples.of(roi[:, :2] - center, rest_at - roi[:, 2], config.touch.length_scale_m)
    mean, std = surface.gp.predict(center[None, :], return_std=True)
    thickness = float(np.asarray(mean).reshape(-1)[0])
    try:
        estimate = estimate_stiffness(record.travel_m, record.force_n,
                                      tip_radius_m=obs.contact.tip_radius_m,
                                      thickness_m=thickness, commanded_force_n=obs.force_n,
                                      thickness_std_m=float(np.asarray(std).reshape(-1)[0]),
                                      config=config.stiffness, dent=dent)  # fmt: skip
    except DeformapError as exc:
        logger.warning("force–travel record not used (the camera alone reads this poke): %s", exc)
        return None, thickness, str(exc)
    return estimate, thickness, None


def dent_visible(indentation_m: float, camera_noise_m: float, n_points: int, sigmas: float) -> bool:
    """Whether the dent's depth at the contact's edge, half of ``indentation_m`` (Hertz), reaches
    ``sigmas`` times ``camera_noise_m / √n_points``; ``False`` without points."""
    if n_points <= 0:
        return False
    return bool(indentation_m / 2.0 >= sigmas * camera_noise_m / np.sqrt(n_points))


def _indentation(obs: PressObservation, surface: SurfaceModel, config: ExplorationConfig,
                 stiffness: StiffnessEstimate | None
                 ) -> tuple[float, float | None, TactileContact]:
    """The indentation δ, the noise of tactile points anchored to it (``None`` when not anchored),
    and the contact with the tip moved to that anchor."""
    contact, point = obs.contact, obs.contact.contact_point
    rest = float(np.asarray(surface.gp.predict(point[None, :2])).reshape(-1)[0])
    if stiffness is None:
        return max(rest - float(point[2]), 0.0), None, contact
    if stiffness.rigid:
        depth, std = 0.0, config.stiffness.travel_noise_m
    else:
        depth = max(float(stiffness.depth_m), 0.0)
        # δ ∝ E^(−2/3) at a fixed force (Hertz), so E's relative σ moves δ by 2/3 of it
        rel = float(stiffness.modulus_std_pa or 0.0) / float(stiffness.modulus_pa or 1.0)
        std = float(np.hypot(config.stiffness.travel_noise_m, 2.0 / 3.0 * depth * rel))
    if config.touch.depth_anchor != "record":
        return depth, None, contact
    shift = np.array([0.0, 0.0, (rest - depth) - float(point[2])])
    anchored = TactileContact(tip_center=contact.tip_center + shift, force=contact.force,
                              tip_radius_m=contact.tip_radius_m)
    return depth, std, anchored


def measure_press(obs: PressObservation, index: int, surface: SurfaceModel,
                  config: ExplorationConfig) -> PokeResult:
    """Reconstruct the dent of press ``obs`` (the ``index``-th of its run) on ``surface`` and
    estimate its β; the record is not yet in a field (no ``purpose``, variance or field time)."""
    t0 = time.perf_counter()
    cfg = config.touch
    contact = obs.contact
    center = contact.contact_point[:2]
    roi_xs, roi_ys = roi_grid(center, cfg.roi_size_m, config.surface.grid_spacing_m)
    roi, rest_at = _roi_points(obs, surface, config)
    t_stiff = time.perf_counter()
    stiffness, thickness, stiffness_error = _stiffness(obs, surface, config, roi, rest_at)
    t_stiff = time.perf_counter() - t_stiff
    depth, anchored_noise, anchored = _indentation(obs, surface, config, stiffness)
    half_angle, n_tactile = (contact_cap(contact.tip_radius_m, depth, cfg.n_tactile)
                             if cfg.tactile_cap == "contact" else (30.0, cfg.n_tactile))
    tactile = tactile_points(anchored.tip_center, anchored.force, anchored.tip_radius_m,
                             n=n_tactile, cap_half_angle_deg=half_angle)  # fmt: skip
    tactile_noise = cfg.tactile_noise_std_m if anchored_noise is None else anchored_noise
    t1 = time.perf_counter()
    rest_z = np.asarray(surface.gp.predict_grid(roi_xs, roi_ys))
    data = np.vstack([roi, tactile])
    noise = np.concatenate([np.full(len(roi), cfg.noise_std_m), np.full(len(tactile), tactile_noise)])
    target = data[:, 2]
    if cfg.model == "residual":
        target = target - np.concatenate([rest_at, surface.gp.predict(tactile[:, :2])])
    touch = GaussianRandomField(length_scale=cfg.length_scale_m, signal_std=cfg.signal_std_m,
                                noise_std=cfg.noise_std_m, method="auto",
                                ).fit(data[:, :2], target, noise_std=noise)  # fmt: skip
    deformed_z = np.asarray(touch.predict_grid(roi_xs, roi_ys))
    if cfg.model == "residual":
        deformed_z = deformed_z + rest_z
    gx, gy = np.meshgrid(roi_xs, roi_ys)
    deformed = np.column_stack([gx.ravel(), gy.ravel(), deformed_z.ravel()])
    t2 = time.perf_counter()
    samples, camera_noise, visible = None, None, None
    if config.beta_uncertainty == "camera-noise":
        # the camera's noise here, measured (the touch GP's σₙ is a prior setting)
        fitted = np.asarray(touch.predict(roi[:, :2])) if len(roi) else np.zeros(0)
        camera_noise = _robust_std(np.asarray(target[: len(roi)]) - fitted)
        samples = dent_error_samples(roi_xs, roi_ys, roi[:, :2], camera_noise, tactile[:, :2],
                                     tactile_noise, length_scale_m=cfg.length_scale_m,
                                     signal_std_m=cfg.signal_std_m, n_samples=cfg.noise_samples)
        near = np.linalg.norm(roi[:, :2] - center, axis=1) <= _FLANK_TIP_RADII * contact.tip_radius_m
        visible = dent_visible(depth, camera_noise, int(near.sum()), cfg.dent_visible_sigmas)
    est = estimate_beta(roi_xs, roi_ys, rest_z, deformed, anchored, config.shape_matching,
                        height_samples=samples)  # fmt: skip
    beta, beta_std = float(est.beta), float(est.beta_std)
    rigid = stiffness is not None and stiffness.rigid
    # a surface the record reads rigid needs no dent seen: β = 0 to the β grid's resolution
    if rigid and config.shape_matching.rigid_at_zero:
        beta, beta_std = 0.0, config.shape_matching.beta_resolution / np.sqrt(12.0)
    if visible is False and not rigid:
        beta_std = max(beta_std, UNINFORMED_BETA_STD)
    t3 = time.perf_counter()
    record = PokeRecord(
        index=index, target_xy=(float(obs.target_xy[0]), float(obs.target_xy[1])),
        contact_xy=(float(center[0]), float(center[1])), contact=ContactRecord.of(contact),
        force_n=float(obs.force_n), beta=beta, beta_std=beta_std,
        betas=tuple(float(b) for b in np.asarray(est.betas)),
        errors=tuple(float(e) for e in np.asarray(est.errors)),
        iterations=int(np.max(est.iterations)), residual=float(np.max(est.residual)),
        converged=bool(np.all(est.converged)), n_roi_points=len(roi), camera_noise_m=camera_noise,
        timings=PokeTimings(filter_s=t1 - t0, touch_gp_s=t2 - t1, beta_s=t3 - t2,
                            stiffness_s=None if obs.force_travel is None else t_stiff),
        stiffness=stiffness, layer_thickness_m=thickness, stiffness_error=stiffness_error,
        indentation_m=depth, depth_anchored=anchored_noise is not None, dent_visible=visible,
        behaviour=poke_behaviour(obs, stiffness),
    )
    dent = Dent(roi_xs, roi_ys, rest_z, deformed_z, roi, tactile, obs.force_travel,
                _force_fit(obs, stiffness, thickness, config))
    return PokeResult(record, dent, est)
