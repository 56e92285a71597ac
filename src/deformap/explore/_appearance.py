"""The appearance image: what the first observation's colours say about the layout, on the map grid.

Built once from the cloud before the first poke (:func:`build_appearance`):

1. Each map cell takes the mean sRGB of the cloud's points in it that lie on the fitted surface
   (within :data:`SURFACE_TOLERANCE_M`); a cell without such points is masked.
2. Channels per cell: the mean colour in CIELAB (a Euclidean step is a colour difference), the
   local standard deviation of L* over a window a dent wide (texture), and the surface's height.
3. A Felzenszwalb & Huttenlocher (2004) over-segmentation of the channels, each divided by its
   robust noise. Segments are candidate regions the prior (:mod:`._appearance_prior`) weighs by
   the pokes; those smaller than a dent's footprint are merged or masked, and one too thin for a
   dent (no cell half a footprint from its edge) is merged into its most alike neighbour; a
   masked cell counts there as its nearest seen cell's segment, so the rows a camera leaves
   unseen are no edges and a strip of mixed colour along a boundary is no look of its own.
4. Each segment's feature: its cells' mean channels, standardised per group (colour, texture,
   height) by the spread of the segment means, never below the group's noise nor, for colour
   and texture, the just-noticeable difference, so a flat channel is not inflated. The looks
   differ when, in some group, the root-mean-square distance between the looks of two cells
   drawn at random (a colour difference ΔE*ab for colour) exceeds that floor.

Where the image cannot carry a layout (no colour, too little seen, saturated or black, colours
all alike, no segment a dent wide, one segment, looks that differ by no more than a
just-noticeable difference or the noise), :func:`build_appearance` returns the reason instead and
the map is the blind one.

References
----------
Felzenszwalb, P. F., Huttenlocher, D. P. (2004). Efficient graph-based image segmentation.
IJCV 59(2), 167–181.
Mahy, M., Van Eycken, L., Oosterlinck, A. (1994). Evaluation of uniform color spaces developed
after the adoption of CIELAB and CIELUV. Color Research & Application 19(2), 105–121.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage as ndi

from deformap.cloud import PointCloud

__all__ = ["SURFACE_TOLERANCE_M", "AppearanceImage", "build_appearance"]

#: A point further than this from the fitted surface [m] is not the surface's look (the robot, a
#: block's side face): well above the depth camera's noise and below a tip.
SURFACE_TOLERANCE_M = 0.01
#: Smallest share of the map's cells that must carry colour, so the prior speaks for seen cells.
MIN_SEEN_FRACTION = 0.5
#: CIELAB L* at or above which a cell is saturated, at or below which it is black.
SATURATED_L, BLACK_L = 99.0, 1.0
#: Largest share of saturated (or black) cells: beyond half, the colours show the exposure.
MAX_CLIPPED_FRACTION = 0.5
#: A CIELAB difference below this (ΔE*ab = 1) is no difference at all.
SAME_DELTA_E = 1.0
#: The just-noticeable CIELAB difference (ΔE*ab ≈ 2.3, Mahy et al. 1994): colour and texture
#: spreads are never standardised below it, so shading and vignetting stay one look.
JND_DELTA_E = 2.3
#: Felzenszwalb's scale in units of the image's noise: a boundary needs a step several noise
#: standard deviations high along a segment, not one noisy cell.
SEGMENT_SCALE = 300.0
#: Felzenszwalb's Gaussian pre-smoothing [cells]: below a cell, so an edge stays within a cell.
SEGMENT_SIGMA = 0.8
#: Most rounds of merging thin segments (each round at least halves a run of adjacent strips).
MERGE_ROUNDS = 8
#: Smallest noise a channel is divided by: CIELAB units, the texture's, and metres of height (a
#: step under a millimetre is no edge a depth camera resolves).
_NOISE_FLOORS = (SAME_DELTA_E / 2, SAME_DELTA_E / 2, 1e-3)


@dataclass(frozen=True, eq=False)
class AppearanceImage:
    """The first observation's look on the map grid and its segments: ``lab (ny, nx, 3)`` the
    mean CIELAB colour per cell and ``texture (ny, nx)`` the local std of L* (NaN where masked);
    ``segments (ny, nx)`` each cell's segment ``0 .. n_segments - 1`` (``-1`` masked);
    ``features (n_segments, 5)`` the standardised mean L*, a*, b*, spread of L*, mean height."""

    lab: NDArray[np.float64]
    texture: NDArray[np.float64]
    segments: NDArray[np.int64]
    features: NDArray[np.float64]

    @property
    def n_segments(self) -> int:
        return int(self.features.shape[0])

    def rgb(self) -> NDArray[np.float64]:
        """``(ny, nx, 3)`` sRGB in [0, 1] of the cells' mean colour (masked cells black)."""
        from skimage.color import lab2rgb

        return np.asarray(lab2rgb(np.nan_to_num(self.lab, nan=0.0)), dtype=float)


def _cell_colours(cloud: PointCloud, xs: NDArray[np.float64], ys: NDArray[np.float64],
                  height: NDArray[np.float64]
                  ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:  # fmt: skip
    """``(ny, nx, 3)`` mean sRGB of the points on the surface in each cell, and the cells with
    any such point."""
    assert cloud.colors is not None
    spacing = float(xs[1] - xs[0]) if xs.size > 1 else float(ys[1] - ys[0])
    pts = cloud.points
    ix = np.rint((pts[:, 0] - xs[0]) / spacing).astype(np.int64)
    iy = np.rint((pts[:, 1] - ys[0]) / spacing).astype(np.int64)
    inside = (ix >= 0) & (ix < xs.size) & (iy >= 0) & (iy < ys.size)
    flat = iy[inside] * xs.size + ix[inside]
    on_surface = np.abs(pts[inside, 2] - height.ravel()[flat]) <= SURFACE_TOLERANCE_M
    flat, colours = flat[on_surface], cloud.colors[inside][on_surface]
    count = np.bincount(flat, minlength=height.size)
    sums = np.stack([np.bincount(flat, colours[:, k], minlength=height.size) for k in range(3)],
                    axis=-1)  # fmt: skip
    rgb = sums / np.maximum(count, 1)[:, None]
    return rgb.reshape((*height.shape, 3)), (count > 0).reshape(height.shape)


def _noise(channel: NDArray[np.float64], mask: NDArray[np.bool_]) -> float:
    """Robust std of a channel's cell-to-cell scatter (the camera's noise and the finest
    texture): the MAD of horizontally neighbouring seen cells' differences, over √2, on the
    cells as measured (a smoothed or filled cell shares its neighbours' values, which would
    understate the scatter and split one look into many, or chain two looks into one)."""
    both = mask[:, 1:] & mask[:, :-1]
    diff = np.diff(channel, axis=1)[both]
    if diff.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(diff - np.median(diff))) / np.sqrt(2.0))


def _local_std(values: NDArray[np.float64], mask: NDArray[np.bool_], window: int
               ) -> NDArray[np.float64]:  # fmt: skip
    """Standard deviation of ``values`` over the seen cells of a ``window``-cell square."""
    weight = mask.astype(float)
    v = np.where(mask, values, 0.0)
    n = np.maximum(ndi.uniform_filter(weight, window), 1e-12)
    mean = ndi.uniform_filter(v * weight, window) / n
    mean_sq = ndi.uniform_filter(v * v * weight, window) / n
    return np.sqrt(np.maximum(mean_sq - mean**2, 0.0))


def _fill_unseen(image: NDArray[np.float64], mask: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Each unseen cell takes its nearest seen cell's channels."""
    if mask.all():
        return image
    idx = ndi.distance_transform_edt(~mask, return_distances=False, return_indices=True)
    return np.asarray(image[idx[0], idx[1]])


def _segment(channels: NDArray[np.float64], mask: NDArray[np.bool_], min_cells: int
             ) -> NDArray[np.int64]:  # fmt: skip
    """Felzenszwalb segments of the noise-scaled ``channels (ny, nx, k)``, ``-1`` where masked
    or where a segment keeps fewer than ``min_cells`` seen cells; labels ``0 ..`` in order."""
    from skimage.segmentation import felzenszwalb

    with warnings.catch_warnings():  # five channels are meant as channels, not as a 3D image
        warnings.simplefilter("ignore", RuntimeWarning)
        raw = felzenszwalb(_fill_unseen(channels, mask), scale=SEGMENT_SCALE, sigma=SEGMENT_SIGMA,
                           min_size=min_cells, channel_axis=-1)  # fmt: skip
    raw = np.where(mask, raw, -1)
    labels, counts = np.unique(raw[raw >= 0], return_counts=True)
    keep = labels[counts >= min_cells]
    lookup = np.full(int(raw.max()) + 2, -1, dtype=np.int64)
    lookup[keep] = np.arange(keep.size)
    return np.where(raw >= 0, lookup[raw], -1).astype(np.int64)


def _merge_thin(segments: NDArray[np.int64], channels: NDArray[np.float64],
                min_depth_cells: float) -> NDArray[np.int64]:
    """Each segment with no cell ``min_depth_cells`` from its edge merged into the adjacent
    segment of nearest mean channels; labels ``0 ..`` in order again, ``-1`` kept."""
    n = int(segments.max()) + 1
    # depth on the segments a dent meets: a masked cell (a gap between the camera's rows, the
    # robot's shadow) takes its nearest seen cell's segment, so a gap is no edge
    seen = segments >= 0
    filled = segments
    if not seen.all():
        nearest = ndi.distance_transform_edt(~seen, return_distances=False, return_indices=True)
        filled = segments[nearest[0], nearest[1]]
    edge = np.zeros(segments.shape, dtype=bool)
    for axis in (0, 1):
        differs = np.diff(filled, axis=axis) != 0
        lo = [slice(None)] * 2
        hi = [slice(None)] * 2
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        edge[tuple(lo)] |= differs
        edge[tuple(hi)] |= differs
    depth = ndi.distance_transform_edt(np.pad(~edge, 1, constant_values=False))[1:-1, 1:-1]
    index = np.arange(n)
    deepest = np.asarray(ndi.maximum(depth, filled, index), dtype=float)
    means = np.stack([ndi.mean(channels[..., k], segments, index)
                      for k in range(channels.shape[-1])], axis=-1)  # fmt: skip
    thin = deepest < min_depth_cells
    if not thin.any() or thin.all():
        return segments
    pairs: set[tuple[int, int]] = set()
    for a, b in ((filled[:, :-1], filled[:, 1:]), (filled[:-1, :], filled[1:, :])):
        touch = (a != b) & (a >= 0) & (b >= 0)
        pairs.update(zip(a[touch].tolist(), b[touch].tolist(), strict=True))
    target = index.copy()
    for s in np.flatnonzero(thin):
        near = {b for a, b in pairs if a == s} | {a for a, b in pairs if b == s}
        wide = [k for k in near if not thin[k]]
        # a strip among strips joins a strip (the next round sees what they made together)
        choice = wide or [k for k in near if target[k] == k]
        if choice:
            target[s] = min(choice, key=lambda k: float(np.sum((means[k] - means[s]) ** 2)))
    merged = np.where(segments >= 0, target[np.maximum(segments, 0)], -1)
    _, relabelled = np.unique(merged, return_inverse=True)
    return np.asarray(relabelled.reshape(segments.shape) - int((merged < 0).any()), dtype=np.int64)


def _features(channels: NDArray[np.float64], noise: NDArray[np.float64],
              segments: NDArray[np.int64], n: int) -> tuple[NDArray[np.float64], bool]:
    """``(n, 5)`` standardised segment means (module docstring, step 4), and whether any
    channel group's spread exceeds its floor; ``noise (5,)`` each channel's noise."""
    flat = segments.ravel()
    seen = flat >= 0
    values = channels.reshape(-1, channels.shape[-1])[seen]
    count = np.bincount(flat[seen], minlength=n).astype(float)
    means = np.stack([np.bincount(flat[seen], values[:, k], minlength=n) for k in
                      range(values.shape[1])], axis=-1) / count[:, None]  # fmt: skip
    # the texture of a segment is the spread of L* within it: the local channel, which the
    # segmentation reads, also rises along every edge
    mean_sq = np.bincount(flat[seen], values[:, 0] ** 2, minlength=n) / count
    means[:, 3] = np.sqrt(np.maximum(mean_sq - means[:, 0] ** 2, 0.0))
    weights = count / count.sum()
    centred = means - weights @ means
    out = np.empty_like(means)
    differ = False
    for group in (slice(0, 3), slice(3, 4), slice(4, 5)):  # colour, texture, height
        spread = np.sqrt(float(weights @ np.sum(centred[:, group] ** 2, axis=1))
                         / (group.stop - group.start))  # fmt: skip
        floor = float(np.max(noise[group]))
        if group.start < 4:  # colour and texture: what the eye would tell apart
            floor = max(floor, JND_DELTA_E)
        # the looks differ when two places drawn at random differ by more than the floor, as a
        # distance over the group's channels (ΔE*ab for colour; RMS over pairs of cells): the
        # per-channel spread above is ΔE / (2√3) for two equal looks, so it hid looks up to
        # 2√3 · JND ≈ 8 apart
        differ |= float(np.sqrt(2.0 * weights @ np.sum(centred[:, group] ** 2, axis=1))) > floor
        out[:, group] = centred[:, group] / max(spread, floor)
    return out, differ


def _unusable(lab: NDArray[np.float64], mask: NDArray[np.bool_]) -> str | None:
    """Why the colours of the seen cells cannot carry a layout, or ``None``."""
    if mask.mean() < MIN_SEEN_FRACTION:
        return (f"colour covers {100 * mask.mean():.0f} % of the map's cells, under "
                f"{100 * MIN_SEEN_FRACTION:.0f} %")
    lightness = lab[..., 0][mask]
    for what, clipped in (("saturated", lightness >= SATURATED_L), ("black", lightness <= BLACK_L)):
        if clipped.mean() > MAX_CLIPPED_FRACTION:
            return f"the colour image is {what} in {100 * clipped.mean():.0f} % of the seen cells"
    seen = lab[mask]
    if float(np.max(np.ptp(seen, axis=0))) < SAME_DELTA_E:
        return "the colours are all alike (within ΔE*ab = 1): they show no layout"
    return None


def build_appearance(cloud: PointCloud, xs: NDArray[np.float64], ys: NDArray[np.float64],
                     height: NDArray[np.float64], footprint_m: float
                     ) -> AppearanceImage | str:  # fmt: skip
    """The appearance image of ``cloud`` (sRGB ``colors`` in [0, 1]) on the evenly spaced grid
    ``xs (nx,)``, ``ys (ny,)`` [m] with the surface's ``height (ny, nx)`` [m], or the one-line
    reason there is none; ``footprint_m`` [m] is the texture window and the smallest segment's
    diameter."""
    if cloud.colors is None:
        return "the cloud has no colour"
    from skimage.color import rgb2lab

    rgb, mask = _cell_colours(cloud, xs, ys, height)
    lab = np.asarray(rgb2lab(rgb), dtype=float)
    why = _unusable(lab, mask)
    if why is not None:
        return why
    spacing = float(xs[1] - xs[0]) if xs.size > 1 else float(ys[1] - ys[0])
    window = max(3, round(footprint_m / spacing) | 1)
    texture = _local_std(lab[..., 0], mask, window)
    channels = np.dstack([lab, texture, height])
    lab_noise = float(np.mean([_noise(lab[..., k], mask) for k in range(3)]))
    noise = np.maximum([lab_noise] * 3 + [_noise(texture, mask), _noise(height, mask)],
                       [_NOISE_FLOORS[0]] * 3 + list(_NOISE_FLOORS[1:]))  # fmt: skip
    min_cells = max(1, int(np.ceil(np.pi * (footprint_m / 2) ** 2 / spacing**2)))
    segments = _segment(channels / noise, mask, min_cells)
    for _ in range(MERGE_ROUNDS):
        if segments.max() < 0:
            break
        merged = _merge_thin(segments, channels / noise, footprint_m / (2 * spacing))
        if merged.max() == segments.max():
            break
        segments = merged
    n = int(segments.max()) + 1
    if n == 0:
        return (f"no segment of the image is as large as a dent's footprint "
                f"({footprint_m * 100:.1f} cm across)")
    if n == 1:
        return "the image is one segment: it shows no layout"
    seen = segments >= 0
    features, differ = _features(channels, noise, segments, n)
    if not differ:
        return ("the segments' looks differ by less than the eye or the camera's noise tells "
                "apart: it shows no layout")
    return AppearanceImage(lab=np.where(seen[..., None], lab, np.nan),
                           texture=np.where(seen, texture, np.nan), segments=segments,
                           features=features)  # fmt: skip
