"""The `textured` family's looks: materials whose colours lie a few percent apart in sRGB (a
colour difference ΔE*ab of a few units, above the just-noticeable one) are a layout the prior uses,
not an image it falls back on."""

from __future__ import annotations

import numpy as np
from skimage.color import rgb2lab

from deformap.cloud import PointCloud
from deformap.explore._appearance import JND_DELTA_E, AppearanceImage, build_appearance

XS = np.arange(0.0025, 0.3, 0.005)
YS = np.arange(0.0025, 0.2, 0.005)
FOOTPRINT_M = 0.03
# one base colour, the second look 0.04 bluer in sRGB: the textured family's "within a few percent"
OCHRE, BLUER = (0.60, 0.50, 0.30), (0.60, 0.50, 0.34)


def _image(left: tuple[float, ...], right: tuple[float, ...]) -> AppearanceImage | str:
    """Four points per map cell on a flat table, ``left`` of x = 0.15 m and ``right`` beyond, with
    a camera's colour noise (0.01 in sRGB)."""
    gx, gy = np.meshgrid(np.arange(0.00125, 0.3, 0.0025), np.arange(0.00125, 0.2, 0.0025))
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    cols = np.where(pts[:, :1] < 0.15, np.array(left), np.array(right))
    cols = np.clip(cols + 0.01 * np.random.default_rng(0).standard_normal(cols.shape), 0.0, 1.0)
    return build_appearance(PointCloud(pts, cols), XS, YS, np.zeros((YS.size, XS.size)),
                            FOOTPRINT_M)  # fmt: skip


def test_two_looks_a_few_delta_e_apart_are_a_layout_not_a_fall_back() -> None:
    delta_e = float(np.linalg.norm(rgb2lab(np.array([OCHRE])) - rgb2lab(np.array([BLUER]))))
    # the case the per-channel spread hid: above the JND, below 2√3 · JND (that spread is ΔE / (2√3)
    # for two equal looks)
    assert JND_DELTA_E < delta_e < 2 * np.sqrt(3) * JND_DELTA_E
    image = _image(OCHRE, BLUER)
    assert isinstance(image, AppearanceImage), image
    left, right = image.segments[:, XS < 0.14], image.segments[:, XS > 0.16]
    assert not set(np.unique(left)) & set(np.unique(right))


def test_one_look_with_the_same_noise_still_falls_back() -> None:
    why = _image(OCHRE, OCHRE)
    assert isinstance(why, str) and "no layout" in why
