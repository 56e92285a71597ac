"""The appearance image of a camera that leaves rows of the map unseen: the gaps are no edges, so
a strip of mixed colour along a boundary, too thin for a dent, is merged, not kept as a look."""

from __future__ import annotations

import numpy as np

from deformap.cloud import PointCloud
from deformap.explore._appearance import AppearanceImage, build_appearance

XS = np.arange(0.0025, 0.3, 0.005)
YS = np.arange(0.0025, 0.2, 0.005)
FOOTPRINT_M = 0.03
RED, BLUE, MIXED = (0.8, 0.2, 0.2), (0.2, 0.3, 0.8), (0.5, 0.25, 0.5)


def _colour(x: float) -> tuple[float, float, float]:
    if 0.14 <= x < 0.16:  # four cells, 2 cm: narrower than a dent
        return MIXED
    return RED if x < 0.14 else BLUE


def _image(gaps: bool) -> AppearanceImage:
    """Four points per map cell; with ``gaps``, every third row of cells gets none."""
    gx, gy = np.meshgrid(np.arange(0.00125, 0.3, 0.0025), np.arange(0.00125, 0.2, 0.0025))
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    if gaps:
        pts = pts[np.rint((pts[:, 1] - YS[0]) / 0.005).astype(int) % 3 != 1]
    rng = np.random.default_rng(0)
    cols = np.array([_colour(x) for x in pts[:, 0]]) + 0.01 * rng.standard_normal((len(pts), 3))
    image = build_appearance(PointCloud(pts, np.clip(cols, 0, 1)), XS, YS,
                             np.zeros((YS.size, XS.size)), FOOTPRINT_M)  # fmt: skip
    assert isinstance(image, AppearanceImage), image
    return image


def test_a_thin_strip_between_two_looks_is_merged_whether_or_not_rows_are_unseen() -> None:
    for gaps in (False, True):
        image = _image(gaps)
        seg = image.segments
        assert (seg[1::3] < 0).all() == gaps and (seg[::3] >= 0).mean() > 0.8
        strip = np.unique(seg[:, (XS >= 0.14) & (XS < 0.16)])
        outside = np.unique(seg[:, (XS < 0.13) | (XS > 0.17)])
        strip = strip[strip >= 0]
        # every segment on the strip reaches into a block: no look of its own
        assert set(strip.tolist()) <= set(outside.tolist()), (gaps, strip, outside)
        assert np.isnan(image.lab[seg < 0]).all()


def test_rows_of_unseen_cells_do_not_make_every_segment_thin() -> None:
    from deformap.explore._appearance import _merge_thin

    # two wide looks, a strip two cells wide between them, every third row unseen
    segments = np.zeros((30, 40), dtype=np.int64)
    segments[:, 19:21] = 1
    segments[:, 21:] = 2
    channels = np.zeros((30, 40, 1))
    channels[:, 19:21] = 0.4
    channels[:, 21:] = 1.0
    segments[1::3] = -1
    merged = _merge_thin(segments, channels, min_depth_cells=3.0)
    assert (merged[1::3] == -1).all()
    assert int(merged.max()) == 1  # the strip joined the look nearest its own
    assert (merged[::3, 19:21] == merged[0, 0]).all() and (merged[::3, 21:] == 1).all()
