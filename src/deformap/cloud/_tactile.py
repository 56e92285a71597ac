"""Tactile points: where the probe's spherical tip touches the surface while it presses.

The paper adds ten points from the touch sensor to the cloud seen while pressing, because the tip
and stick hide the dent; they are "virtually generated considering the position and shape of the
spherical surface of the sensor along with the contact force direction": here, points on the
tip's cap that faces along the contact force. A sphere of radius ``R`` pressed ``δ`` deep touches
within the Hertz contact radius ``a = √(R δ)`` (Johnson 1985, §4.2); :func:`contact_cap` gives
that cap and how many points keep the paper's density on it (ten on a 30° cap).

References
----------
Caccamo et al., "Active Perception and Modeling of Deformable Surfaces using Gaussian Processes
and Position-based Dynamics", HUMANOIDS 2016, Sec. III ("The algorithm process flow").
Johnson, K. L. (1985). Contact Mechanics, §4.2. Cambridge University Press.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_int, check_positive, check_slope_deg, check_vector
from deformap.errors import InvalidArgumentError

__all__ = ["DEFAULT_CAP_HALF_ANGLE_DEG", "contact_cap", "tactile_points", "tip_in_view"]

#: Half-angle of the touching cap from the force direction: 30° reaches 0.13 r up from the pole,
#: the depth over which a soft surface wraps a pressing sphere beyond first contact.
DEFAULT_CAP_HALF_ANGLE_DEG = 30.0

_GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))



def contact_cap(tip_radius_m: float, indentation_m: float, n: int = 10) -> tuple[float, int]:
    """The cap of the tip (radius ``R > 0``) touching at an indentation ``δ >= 0``.

    Returns the half-angle ``asin(min(a / R, 1))`` in degrees (a small positive angle at ``δ = 0``),
    and how many points sample it at the density of ``n`` points on the default cap (area
    ``∝ 1 − cos θ``), rounded, between 1 and ``n``.
    """
    radius = check_positive("tip_radius_m", tip_radius_m)
    depth = check_positive("indentation_m", indentation_m, allow_zero=True)
    most = check_int("n", n, minimum=1)
    ratio = min(np.sqrt(radius * depth) / radius, 1.0)
    half_angle = max(float(np.degrees(np.arcsin(ratio))), 1e-3)
    area = (1.0 - np.cos(np.radians(half_angle))) / (
        1.0 - np.cos(np.radians(DEFAULT_CAP_HALF_ANGLE_DEG)))
    return half_angle, int(np.clip(round(most * area), 1, most))


def tactile_points(tip_center: Any, force_vector: Any, tip_radius_m: float, n: int = 10, *,
                   cap_half_angle_deg: float = DEFAULT_CAP_HALF_ANGLE_DEG) -> NDArray[np.float64]:
    """Deterministic ``(n, 3)`` points (metres) on the cap of the tip that touches the surface.

    The first is the pole ``tip_center + r · u``, ``u`` the unit direction of ``force_vector`` (the
    force on the surface, newtons); the other ``n - 1`` follow a golden-angle spiral uniform in area
    over the cap of ``cap_half_angle_deg`` (in (0, 90]), the last on its rim.
    """
    center = check_vector("tip_center", tip_center, 3, what="metres")
    force = check_vector("force_vector", force_vector, 3, what="newtons")
    radius = check_positive("tip_radius_m", tip_radius_m)
    count = check_int("n", n, minimum=1)
    half_angle = check_slope_deg("cap_half_angle_deg", cap_half_angle_deg)
    norm = float(np.linalg.norm(force))
    if norm == 0.0:
        raise InvalidArgumentError("`force_vector` must be a non-zero vector; got (0, 0, 0)")
    axis = force / norm
    # A frame around the axis, seeded by the world axis least aligned with it (a well
    # conditioned cross product).
    seed = np.zeros(3)
    seed[int(np.argmin(np.abs(axis)))] = 1.0
    e1 = np.cross(axis, seed)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    i = np.arange(count, dtype=float)
    frac = i / (count - 1) if count > 1 else np.zeros(1)
    # Equal cap-area steps: the area of a cap of polar angle θ is proportional to 1 - cos θ.
    cos_theta = 1.0 - frac * (1.0 - np.cos(np.radians(half_angle)))
    sin_theta = np.sqrt(np.clip(1.0 - cos_theta**2, 0.0, None))
    phi = i * _GOLDEN_ANGLE
    directions = (
        cos_theta[:, None] * axis
        + (sin_theta * np.cos(phi))[:, None] * e1
        + (sin_theta * np.sin(phi))[:, None] * e2)
    return np.asarray(center + radius * directions)


def tip_in_view(points: NDArray[np.float64], tip_center: NDArray[np.float64], tip_radius_m: float,
                *, within_radii: float) -> int:
    """How many of ``points`` ``(n, 3)`` (z up) are the top of a spherical tip at ``tip_center``;
    0 when the tip is not in view. The candidates lie within ``within_radii`` radii of the centre
    and more than half a radius above it (what a camera above sees of a tip); they are the tip
    when their median height stands more than a quarter radius above the surface 2–3 radii away
    (its 90th percentile): a deep press's surface rebounds above the tip's centre but never stands
    above the surface around it, as the tip's top does."""
    radius = tip_radius_m
    near = np.linalg.norm(points - tip_center, axis=1) <= within_radii * radius
    top = near & (points[:, 2] > tip_center[2] + radius / 2)
    if not np.any(top):
        return 0
    r = np.linalg.norm(points[:, :2] - tip_center[:2], axis=1)
    ring = points[(r >= 2 * radius) & (r <= 3 * radius), 2]
    if ring.size and float(np.median(points[top, 2])) <= float(np.quantile(ring, 0.9)) + radius / 4:
        return 0
    return int(top.sum())
