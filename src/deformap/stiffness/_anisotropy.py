"""The in-plane anisotropy a press's dent shows: its ratio and stiff axis, from the dent's shape.

An in-plane orthotropic foam of Huber's form (moduli ``E₁ = ratio · E`` along the stiff axis,
``E₂ = E₃ = E``; :mod:`deformap.world._materials`) is an isotropic one seen in coordinates
stretched by ``E_i^{1/4}`` along each axis (its elasticity tensor is the isotropic one scaled by
``(e_i e_j e_k e_l)^{1/4}``, so equilibrium in ``ξ_i = x_i / e_i^{1/4}`` is isotropic): outside
the contact, the dent of a press is an isotropic dent stretched by ``ratio^{1/4}`` along the stiff
axis — it reaches farther that way — and its depth contours are ellipses of that axis ratio.

:func:`dent_anisotropy` fits the surface seen during the press, the points ``1.2–6`` tip radii
from the press point (inside, the tip hides the surface and the contact patch follows the
sphere), with an isotropic dent profile on elliptic contours,
``z = z₀ − A exp(−ρ)``, ``ρ² = (u/L₁)² + (v/L₂)²`` in axes turned by ``θ`` (least squares; the
points more than :data:`CLIP_SIGMAS` robust σ off the first fit dropped, then refitted). The ratio
is ``(L₁/L₂)^4``, the stiff axis the direction of the longer ``L``; their σ by the delta method on
the fit's covariance ``s² (JᵀJ)⁻¹``. The profile need not be the dent's: contours of the right
ellipticity are what the ratio reads.

The class: *anisotropic* when the ratio exceeds :data:`ANISOTROPY_FLOOR` by :data:`N_SIGMA` of
its σ; *isotropic* when it lies below that floor by two of its σ; ``"unknown"`` otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from deformap.stiffness._phases import MAD_TO_SIGMA, N_SIGMA, press_surface

__all__ = ["ANISOTROPY_FLOOR", "ANISOTROPY_WINDOW_RADII", "CLIP_SIGMAS", "Anisotropy", "Isotropy",
           "dent_anisotropy"]

Isotropy = Literal["isotropic", "anisotropic", "unknown"]

#: Smallest in-plane ratio taken as the material's: one foam sheet's modulus varies from place to
#: place by about ±10 %, and a dent on square finite elements or in a camera's grid of pixels
#: reads a few per cent elongated with no anisotropy at all.
ANISOTROPY_FLOOR = 1.2
#: Residuals beyond this many robust σ of the first fit (flying pixels, the probe's edge) are
#: dropped before the second.
CLIP_SIGMAS = 4.0
#: The dent's shape is read this many tip radii around the tip, and from 1.2 of them out.
ANISOTROPY_WINDOW_RADII = 6.0
_INNER_RADII, _OUTER_RADII = 1.2, ANISOTROPY_WINDOW_RADII
_MIN_POINTS = 50


@dataclass(frozen=True)
class Anisotropy:
    """The dent's in-plane stiff-over-soft ratio and the stiff axis [degrees from x, in
    (−90, 90]], each with its σ, and the class with its evidence."""

    ratio: float
    ratio_sigma: float
    axis_deg: float
    axis_sigma_deg: float
    isotropy: Isotropy
    evidence: str


def _model(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    z0, amplitude, l1, l2, theta = p
    c, s = math.cos(theta), math.sin(theta)
    u = c * q[:, 0] + s * q[:, 1]
    v = -s * q[:, 0] + c * q[:, 1]
    rho = np.sqrt((u / np.exp(l1)) ** 2 + (v / np.exp(l2)) ** 2)
    return np.asarray(z0 - amplitude * np.exp(-rho))


def _fit(q: NDArray[np.float64], z: NDArray[np.float64], start: NDArray[np.float64],
         radius: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None:
    # lengths from a tenth of the tip's radius to the fitted window's ten times over
    low, high = math.log(0.1 * radius), math.log(10.0 * _OUTER_RADII * radius)
    bounds = ([-np.inf, 0.0, low, low, -np.inf], [np.inf, np.inf, high, high, np.inf])
    start = np.clip(start, [-np.inf, 0.0, low, low, -np.inf], [np.inf, np.inf, high, high, np.inf])
    try:
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            fit = least_squares(lambda p: _model(p, q) - z, start, bounds=bounds, method="trf")
    except (ValueError, np.linalg.LinAlgError, OverflowError, FloatingPointError):
        return None
    if not fit.success or not np.all(np.isfinite(fit.x)):
        return None
    dof = z.size - start.size
    s2 = float(fit.fun @ fit.fun) / dof
    jac = np.asarray(fit.jac)
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
    except np.linalg.LinAlgError:
        return None
    return np.asarray(fit.x), cov, np.asarray(fit.fun)


def dent_anisotropy(points: Any, tip_center: Any, tip_radius_m: float) -> Anisotropy | str:
    """The ratio, stiff axis and class the dent in ``points`` ``(n, 3)`` (the surface during the
    press, world frame, z up, the probe's own points removed) shows around the tip at
    ``tip_center`` (module docstring), or why none could be had."""
    pts, center = press_surface(points, tip_center, tip_radius_m)
    q = pts[:, :2] - center[:2]
    r = np.linalg.norm(q, axis=1)
    use = (r >= _INNER_RADII * tip_radius_m) & (r <= _OUTER_RADII * tip_radius_m)
    if int(use.sum()) < _MIN_POINTS:
        return (f"the surface during the press has {int(use.sum())} points "
                f"{_INNER_RADII:g}–{_OUTER_RADII:g} tip radii from the tip; needs {_MIN_POINTS}")
    q, z, r = q[use], pts[use, 2], r[use]
    far = r >= 0.75 * _OUTER_RADII * tip_radius_m
    z_far = float(np.median(z[far])) if far.any() else float(np.max(z))
    start = np.array([z_far, max(z_far - float(np.min(z)), 1e-4),
                      math.log(tip_radius_m), math.log(tip_radius_m), 0.3])
    got = _fit(q, z, start, tip_radius_m)
    if got is not None:
        resid = got[2]
        scale = MAD_TO_SIGMA * float(np.median(np.abs(resid - np.median(resid))))
        keep = np.abs(resid) <= CLIP_SIGMAS * max(scale, 1e-12)
        if int(keep.sum()) >= _MIN_POINTS:
            got = _fit(q[keep], z[keep], got[0], tip_radius_m)
    if got is None:
        return "the dent's shape fit did not converge"
    p, cov, _ = got
    if not p[1] > 0.0:
        return "the surface during the press shows no dent around the tip"
    l1, l2, theta = float(p[2]), float(p[3]), float(p[4])
    if l2 > l1:
        l1, l2, theta = l2, l1, theta + math.pi / 2.0
    grad = np.array([0.0, 0.0, 4.0, -4.0, 0.0])
    ratio = math.exp(4.0 * (l1 - l2))
    ratio_sigma = ratio * math.sqrt(max(float(grad @ cov @ grad), 0.0))
    axis = (math.degrees(theta) + 90.0) % 180.0 - 90.0
    axis = 90.0 if axis == -90.0 else axis
    axis_sigma = math.degrees(math.sqrt(max(float(cov[4, 4]), 0.0)))
    if not all(math.isfinite(v) for v in (ratio, ratio_sigma, axis, axis_sigma)):
        return "the dent's shape fit gave no finite ratio"
    said = (f"in-plane ratio {ratio:.3g} ± {ratio_sigma:.2g}, stiff axis {axis:.0f}° ± "
            f"{axis_sigma:.2g}°")
    isotropy: Isotropy
    if ratio - ANISOTROPY_FLOOR > N_SIGMA * ratio_sigma:
        isotropy, why = "anisotropic", f"the dent reaches farther one way ({said})"
    elif ratio + 2.0 * ratio_sigma < ANISOTROPY_FLOOR:
        isotropy, why = "isotropic", f"the dent is round within {ANISOTROPY_FLOOR:g} by 2 σ ({said})"
    else:
        isotropy, why = "unknown", f"the dent's shape neither shows nor rules out anisotropy ({said})"
    return Anisotropy(ratio=ratio, ratio_sigma=ratio_sigma, axis_deg=axis,
                      axis_sigma_deg=axis_sigma, isotropy=isotropy, evidence=why)
