"""How much the camera's noise moves the reconstructed dent: the touch GP's smoother on noise.

The GP's mean is linear in the data, ``m = W y`` with ``W = K*ₓ (K + Σ)⁻¹``, so the noise
``ε ~ N(0, Σ)`` leaves the error ``W ε``, drawn here without the data's values: the
reconstruction's sampling spread, not the posterior. The camera's points are binned onto the
ROI's grid (noise σₙ/√count per node); the tactile points enter as they are.

References
----------
Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes for Machine Learning, Eq. 2.23
and §2.6 (the mean as a linear smoother, :func:`deformap.gp.apply_smoother`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_int, check_positive
from deformap.errors import InvalidArgumentError
from deformap.gp import apply_smoother

__all__ = ["DENT_NOISE_SEED", "dent_error_samples"]

DENT_NOISE_SEED = 20161116  # a poke's uncertainty is a deterministic function of the poke


def dent_error_samples(xs: NDArray[np.float64], ys: NDArray[np.float64],
                       points_xy: NDArray[np.float64], points_noise_m: float,
                       extra_xy: NDArray[np.float64], extra_noise_m: float, *,
                       length_scale_m: float, signal_std_m: float,
                       n_samples: int) -> NDArray[np.float64]:
    """``(n_samples, ny * nx)`` draws [m] of the error data noise leaves in the touch GP's mean on
    the evenly spaced grid ``xs (nx,) × ys (ny,)``, row-major.

    ``points_xy (n, 2)`` (the camera's, binned onto the nearest node) and ``extra_xy (t, 2)`` (the
    tactile points, as they are) in metres with noise ``points_noise_m`` and ``extra_noise_m``;
    the GP's kernel ``length_scale_m``, ``signal_std_m``; ``n_samples ≥ 2``.
    """
    gx_, gy_ = check_array("xs", xs, (None,), min_rows=2), check_array("ys", ys, (None,), min_rows=2)
    pts = check_array("points_xy", points_xy, (None, 2), what="positions in metres")
    extra = check_array("extra_xy", extra_xy, (None, 2), what="positions in metres")
    for name, value in (("points_noise_m", points_noise_m), ("extra_noise_m", extra_noise_m),
                        ("length_scale_m", length_scale_m), ("signal_std_m", signal_std_m)):
        check_positive(name, value)
    check_int("n_samples", n_samples, minimum=2)
    if pts.shape[0] + extra.shape[0] == 0:
        raise InvalidArgumentError("`points_xy` and `extra_xy` are both empty: nothing was seen")
    nx, ny = gx_.size, gy_.size
    ix = np.clip(np.rint((pts[:, 0] - gx_[0]) / (gx_[1] - gx_[0])), 0, nx - 1).astype(np.int64)
    iy = np.clip(np.rint((pts[:, 1] - gy_[0]) / (gy_[1] - gy_[0])), 0, ny - 1).astype(np.int64)
    counts = np.bincount(iy * nx + ix, minlength=nx * ny)
    gx, gy = np.meshgrid(gx_, gy_)
    nodes = np.column_stack([gx.ravel(), gy.ravel()])
    seen = counts > 0
    data = np.vstack([nodes[seen], extra])
    noise = np.concatenate([points_noise_m / np.sqrt(counts[seen]),
                            np.full(extra.shape[0], extra_noise_m)])  # fmt: skip
    rng = np.random.default_rng(DENT_NOISE_SEED)
    noise_draws = noise[:, None] * rng.standard_normal((data.shape[0], n_samples))
    smoothed = apply_smoother(data, noise, nodes, noise_draws, length_scale=length_scale_m,
                              signal_std=signal_std_m, jitter=1e-10, max_jitter=1e-4)
    return np.asarray(smoothed.T)
