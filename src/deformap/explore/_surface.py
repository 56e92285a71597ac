"""The surface model ("GPR world"): the first observation, cropped to the workspace and
``[z_min_m, z_max_m]``, cleaned of outliers and steep faces, as a Gaussian random field whose
hyperparameters are fitted by maximum marginal likelihood (RW2006 Sec. 5.4), and its heightmap.

References
----------
Caccamo et al. (2016), Sec. III-A. Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes
for Machine Learning, Sec. 5.4.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud, crop_box, height_field_mask, statistical_outlier_mask
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore._config import SurfaceGPConfig
from deformap.gp import GaussianRandomField, GPHyperparameters, default_bounds, fit_hyperparameters

__all__ = ["SurfaceModel", "crop_to", "fit_surface"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class SurfaceModel:
    """The surface GP and its heightmap on the workspace grid."""

    gp: GaussianRandomField
    hyperparameters: GPHyperparameters
    height: NDArray[np.float64]  # (ny, nx)
    height_std: NDArray[np.float64]  # (ny, nx)
    n_raw: int
    points: NDArray[np.float64]  # (n, 3) the cropped, outlier-filtered cloud the GP was fitted to


def crop_to(points: NDArray[np.float64], lower_xy: NDArray[np.float64] | tuple[float, float],
            upper_xy: NDArray[np.float64] | tuple[float, float],
            config: SurfaceGPConfig) -> NDArray[np.float64]:
    """The ``(n, 3)`` points inside the box ``lower_xy``–``upper_xy`` and the configured heights."""
    lo = [lower_xy[0], lower_xy[1], config.z_min_m]
    hi = [upper_xy[0], upper_xy[1], config.z_max_m]
    return points[crop_box(points, lo, hi)]


def fit_surface(cloud: PointCloud, workspace: Workspace, xs: NDArray[np.float64],
                ys: NDArray[np.float64], config: SurfaceGPConfig,
                rng: np.random.Generator) -> SurfaceModel:
    """Crop and filter ``cloud`` (world frame, metres) to ``workspace``, fit the surface GP to it
    (``rng`` for the fit's subset and restarts) and read it on ``xs (nx,) × ys (ny,)``.

    Raises :class:`InvalidArgumentError` if no more than ``outlier_k`` points lie on the workspace.
    """
    pts = crop_to(cloud.points, workspace.lower, workspace.upper, config)
    if pts.shape[0] <= config.outlier_k:
        raise InvalidArgumentError(f"`cloud` must have more than {config.outlier_k} points on the "
                                   f"workspace; got {pts.shape[0]} (is it in the world frame, in "
                                   "metres?)")
    kept = pts[statistical_outlier_mask(pts, config.outlier_k, config.outlier_std_ratio)]
    if kept.shape[0] >= config.outlier_k:
        kept = kept[height_field_mask(kept, config.outlier_k, config.max_slope_deg)]
    hyper = init = GPHyperparameters(length_scale=config.length_scale_m,
                                     signal_std=config.signal_std_m, noise_std=config.noise_std_m,
                                     log_marginal_likelihood=float("nan"))
    if config.fit_hyperparameters:
        bounds = default_bounds(kept[:, :2], kept[:, 2])
        bounds[0] = np.maximum(bounds[0], config.min_length_scale_m)
        hyper = fit_hyperparameters(kept[:, :2], kept[:, 2], rng=rng, init=init, bounds=bounds,
                                    max_points=config.max_fit_points, n_restarts=config.fit_restarts)
    gp = GaussianRandomField(length_scale=hyper.length_scale, signal_std=hyper.signal_std,
                             noise_std=hyper.noise_std).fit(kept[:, :2], kept[:, 2])
    height, std = gp.predict_grid(xs, ys, return_std=True)
    logger.info("surface GP: %d of %d points kept, %s", kept.shape[0], len(cloud), hyper)
    return SurfaceModel(gp, hyper, height, std, cloud.points.shape[0], kept)
