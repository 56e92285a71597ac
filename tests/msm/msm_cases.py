"""Shared cases of the shape-matching tests: small ROIs and Hertz dents (imported by the tests)."""

from __future__ import annotations

import numpy as np

from deformap.testing import elastic_dent, hardness_to_modulus


def roi_axes(n: int, spacing: float, center=(0.30, 0.20)):
    xs = center[0] + (np.arange(n) - (n - 1) / 2) * spacing
    ys = center[1] + (np.arange(n) - (n - 1) / 2) * spacing
    return xs, ys


def dent_case(hardness_n, *, n=13, spacing=0.01, force_n=0.5, tip_radius_m=0.01, height=0.05):
    """Flat foam ROI, its Hertz dent (``hardness_n=None``: rigid) as points, and the contact."""
    xs, ys = roi_axes(n, spacing)
    z = np.full((n, n), height)
    e = None if hardness_n is None else hardness_to_modulus(hardness_n)
    zd, contact = elastic_dent(xs, ys, z, (0.30, 0.20), force_n=force_n,
                               tip_radius_m=tip_radius_m, modulus_pa=e)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.column_stack([gx.ravel(), gy.ravel(), zd.ravel()])
    return xs, ys, z, pts, contact

