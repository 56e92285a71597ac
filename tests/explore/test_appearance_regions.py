"""The regions under the appearance prior are the pokes' classes: an informative two-material
world gives its two regions, and a look no poke tells apart from another is no region."""

from __future__ import annotations

import numpy as np

from deformap.cloud import PointCloud
from deformap.explore import BetaField, BetaFieldConfig, ExplorationConfig, PokeSet, map_regions
from deformap.explore._appearance import AppearanceImage, build_appearance
from deformap.explore._appearance_prior import AppearancePrior

XS = np.arange(0.0025, 0.3, 0.005)
YS = np.arange(0.0025, 0.2, 0.005)
FOOTPRINT_M = 0.03
RED, BLUE = (0.8, 0.2, 0.2), (0.2, 0.3, 0.8)
CONFIG = ExplorationConfig(field="beta", merge_seams=False, split_by_place=False)
LEFT = [(0.03, 0.05), (0.05, 0.15), (0.08, 0.1)]
RIGHT = [(0.22, 0.05), (0.25, 0.15), (0.27, 0.1)]


def _regions(values):
    """The map's regions under the prior of an image red left of x = 0.15 m and blue beyond
    (four points per map cell with a camera's noise), pokes at ``LEFT + RIGHT``."""
    gx, gy = np.meshgrid(np.arange(0.00125, 0.3, 0.0025), np.arange(0.00125, 0.2, 0.0025))
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    cols = np.where(pts[:, :1] < 0.15, np.array(RED), np.array(BLUE))
    cols = np.clip(cols + 0.01 * np.random.default_rng(0).standard_normal(cols.shape), 0.0, 1.0)
    image = build_appearance(PointCloud(pts, cols), XS, YS, np.zeros((YS.size, XS.size)),
                             FOOTPRINT_M)  # fmt: skip
    assert isinstance(image, AppearanceImage)
    pokes = PokeSet(np.array(LEFT + RIGHT), np.asarray(values, float), np.full(6, 0.01))
    field = BetaField(pokes, XS, YS, BetaFieldConfig(length_scale_m=0.05)).with_prior(
        AppearancePrior(image, XS, YS))
    assert field.models is not None
    return map_regions(field.mean, pokes, field.models.prior.cells_xy, CONFIG, "beta",
                       correlation=field.models.correlation)  # fmt: skip


def test_two_materials_in_their_own_looks_give_two_regions_along_the_looks() -> None:
    found = _regions([0.2, 0.21, 0.19, 0.8, 0.81, 0.79])
    assert found.n_regions == 2
    left = found.labels[:, XS < 0.14]
    right = found.labels[:, XS > 0.16]
    assert np.unique(left).size == 1 and np.unique(right).size == 1
    assert left[0, 0] != right[0, 0]


def test_two_looks_no_poke_tells_apart_are_one_region() -> None:
    found = _regions([0.5, 0.51, 0.49, 0.5, 0.49, 0.51])
    assert found.n_regions == 1
    assert np.unique(found.labels).size == 1
