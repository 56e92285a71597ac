"""What every panel of the map figure draws over its image: the pokes marked by purpose and
numbered from 1, the regions' outlines or isopleths, and each region's name placed clear of the
pokes (:class:`Overlay`); the panels' extent from the grid's cell centres (:func:`extent`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from deformap.errors import InvalidArgumentError

__all__ = ["MARKS", "REGION_COLOUR", "Extent", "Overlay", "draw_pokes", "extent", "label_place",
           "poke_purposes"]

REGION_COLOUR = "r"
Extent = tuple[float, float, float, float]

# marker per poke purpose: the first poke, the pokes the variance chose, the pokes testing a look
# (appearance prior), the boundary pokes
MARKS = {"first": ("o", "first poke"), "variance": ("^", "later pokes"),
          "appearance": ("D", "pokes testing a look"),
          "boundary": ("s", "boundary pokes")}  # fmt: skip
_HALO = [patheffects.withStroke(linewidth=3.5, foreground="w")]
_PANEL_PX = 400.0
"""About how many pixels a map panel's axes span across (5.2 in at 110 dpi, less its colour bar):
the scale by which a region's label is kept clear of the pokes' marks."""
def extent(xs: NDArray, ys: NDArray) -> Extent:
    dx = (xs[1] - xs[0]) / 2 if xs.size > 1 else 0.0025
    dy = (ys[1] - ys[0]) / 2 if ys.size > 1 else 0.0025
    return (float(xs[0] - dx), float(xs[-1] + dx), float(ys[0] - dy), float(ys[-1] + dy))


def poke_purposes(n: int, purposes: Sequence[str | None] | None) -> list[str]:
    """Each contact's purpose; without them the first is ``first`` and the rest ``variance``."""
    if purposes is None:
        return ["first"] + ["variance"] * (n - 1) if n else []
    if len(purposes) != n:
        raise InvalidArgumentError(
            f"`purposes` must have one entry per contact ({n}); got {len(purposes)}")
    return [p if p in MARKS else ("first" if i == 0 else "variance")
            for i, p in enumerate(purposes)]  # fmt: skip


def draw_pokes(ax: Axes, contacts: NDArray[np.float64], purposes: list[str]) -> None:
    """The pokes, marked by purpose and numbered from 1: black with a white halo, readable on
    the dark end of a colour map as on the light one."""
    for purpose, (marker, _) in MARKS.items():
        mine = [i for i, p in enumerate(purposes) if p == purpose]
        if mine:
            ax.plot(contacts[mine, 0], contacts[mine, 1], marker, mfc="none", mec="k",
                    ms=10 if marker == "o" else 9, mew=2, path_effects=_HALO, linestyle="none")
    for i, (x, y) in enumerate(contacts):
        ax.annotate(str(i + 1), (x, y), xytext=(6, 6), textcoords="offset points", fontsize=8,
                    path_effects=[patheffects.withStroke(linewidth=2.5, foreground="w")])


class Overlay:
    """What every field panel draws over its image: the regions, the pokes and the regions'
    names with their values."""

    def __init__(self, xs: NDArray, ys: NDArray, labels: NDArray | None, levels: NDArray | None,
                 contacts: NDArray, kinds: list[str], rigid: set[int]) -> None:
        self.xs, self.ys, self.labels, self.levels = xs, ys, labels, levels
        self.contacts, self.kinds, self.rigid = contacts, kinds, rigid

    def draw(self, ax: Axes, values: NDArray, given: Sequence[float | None] | None, *,
             main: bool, name: Callable[[float], str]) -> None:
        """The regions (the isopleths of ``values`` when cut from this field, ``main``), the
        pokes, and each region's name with ``given[k]`` (else the median of ``values`` over its
        cells) or "rigid"."""
        _regions(ax, self.xs, self.ys, values, self.labels, self.levels if main else None,
                 main=main)  # fmt: skip
        draw_pokes(ax, self.contacts, self.kinds)
        if self.labels is None:
            return
        texts = {}
        for k in (int(k) for k in np.unique(self.labels) if k >= 0):
            value = given[k] if given is not None and k < len(given) else None
            if value is None:
                cells = values[(self.labels == k) & np.isfinite(values)]
                value = float(np.median(cells)) if cells.size else None
            if k in self.rigid:
                texts[k] = f"R{k + 1}: rigid"
            elif value is not None:
                texts[k] = f"R{k + 1}: {name(value)}"
        for k, text in texts.items():
            x, y = label_place(self.xs, self.ys, self.labels == k, self.contacts, len(text))
            ax.text(x, y, text, ha="center", va="center", fontsize=8,
                    bbox={"boxstyle": "round,pad=0.2", "fc": "w", "ec": "0.5", "alpha": 0.85})


def label_place(xs: NDArray, ys: NDArray, region: NDArray, contacts: NDArray,
                 n_chars: int) -> tuple[float, float]:
    """Where a region's label of ``n_chars`` characters goes: the cell deepest inside the region
    (farthest from its edge, the map's border counting as one: inside however the region is
    shaped, where a centroid may fall outside) among those where the label's box clears every
    poke's mark and number; the deepest cell when none does."""
    depth = distance_transform_edt(np.pad(region, 1))[1:-1, 1:-1]
    px = (xs[-1] - xs[0]) / _PANEL_PX if xs.size > 1 else 1e-3  # metres per pixel
    # at 110 dpi a poke takes its mark (10 px about it) and its number (up to 20 px right of it
    # and 23 px above); the label's box is 8-point characters about 6.5 px wide, 20 px high;
    # 4 px apart
    half_w, half_h = n_chars * 3.25 + 4.0 + 4.0, 10.0 + 4.0
    gx, gy = np.meshgrid(xs, ys)
    clear = region.copy()
    for cx, cy in contacts:
        dx, dy = (gx - cx) / px, (gy - cy) / px
        clear &= ~((dx > -10.0 - half_w) & (dx < 20.0 + half_w)
                   & (dy > -10.0 - half_h) & (dy < 23.0 + half_h))
    score = np.where(clear, depth, -1.0) if clear.any() else depth
    iy, ix = np.unravel_index(int(np.argmax(score)), score.shape)
    return float(xs[ix]), float(ys[iy])


def _regions(ax: Axes, xs: NDArray, ys: NDArray, values: NDArray, labels: NDArray | None,
             levels: NDArray | None, *, main: bool) -> None:
    """The regions on one field's panel: its isopleths ``levels`` when given, else the labels'
    outlines (dashed on the panel of the field they were not cut from)."""
    if levels is not None and len(levels):
        ax.contour(xs, ys, values, levels=np.sort(levels), colors=REGION_COLOUR, linewidths=2)
    elif labels is not None and np.ptp(labels) > 0:
        # each region's outline (contours of the label values would draw two lines where
        # regions 0 and 2 meet)
        for label in np.unique(labels):
            ax.contour(xs, ys, (labels == label).astype(float), levels=[0.5],
                       colors=REGION_COLOUR, linewidths=2 if main else 1,
                       linestyles="solid" if main else "dashed")  # fmt: skip
