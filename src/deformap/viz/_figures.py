"""The map figure of a run, a :class:`matplotlib.figure.Figure` built without ``pyplot``.

``map.png`` follows the paper's Fig. 6: ground truth | β-field with region contours and the contacts
| variance with the contacts; with a modulus field, a panel of E in kPa (log colour scale) comes
before the variance, which is the variance of the field the regions ran on. Each region is named
(R1, R2, …) at its inmost cell with its mean β (and E) on the map; one legend below the panels says
which mark is the first poke, the later ones and the boundary pokes, and which line is a region
boundary and which the T_h contour. The poke figures are :mod:`deformap.viz._poke`.

Every ``plot_*`` function returns its figure and, given ``path``, also writes it there atomically
(a temporary file in the same folder, renamed onto ``path`` once complete). No backend is selected,
``pyplot`` is never imported and no global state is touched, so the functions are safe in notebooks
and GUI applications, which keep their own backend and display the returned figure their own way.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from deformap.errors import InvalidArgumentError
from deformap.viz._save import save_figure

__all__ = ["plot_map"]

# marker per poke purpose: the first poke, the pokes the variance chose, the boundary pokes
_MARKS = {"first": ("o", "first poke"), "variance": ("^", "later pokes"),
          "boundary": ("s", "boundary pokes")}  # fmt: skip
_HALO = [patheffects.withStroke(linewidth=3.5, foreground="w")]
_REGION_COLOUR, _THRESHOLD_COLOUR = "c", "r"
Extent = tuple[float, float, float, float]


def _extent(xs: NDArray, ys: NDArray) -> Extent:
    dx = (xs[1] - xs[0]) / 2 if xs.size > 1 else 0.0025
    dy = (ys[1] - ys[0]) / 2 if ys.size > 1 else 0.0025
    return (float(xs[0] - dx), float(xs[-1] + dx), float(ys[0] - dy), float(ys[-1] + dy))


def _purposes(n: int, purposes: Sequence[str | None] | None) -> list[str]:
    """Each contact's purpose; without them the first is ``first`` and the rest ``variance``."""
    if purposes is None:
        return ["first"] + ["variance"] * (n - 1) if n else []
    if len(purposes) != n:
        raise InvalidArgumentError(
            f"`purposes` must have one entry per contact ({n}); got {len(purposes)}")
    return [p if p in _MARKS else ("first" if i == 0 else "variance")
            for i, p in enumerate(purposes)]  # fmt: skip


def _contacts(ax: Axes, contacts: NDArray[np.float64], purposes: list[str]) -> None:
    """The pokes, marked by purpose and numbered in order: black with a white halo, readable on
    the dark end of a colour map (a rigid board's β = 0) as on the light one."""
    for purpose, (marker, _) in _MARKS.items():
        mine = [i for i, p in enumerate(purposes) if p == purpose]
        if mine:
            ax.plot(contacts[mine, 0], contacts[mine, 1], marker, mfc="none", mec="k",
                    ms=10 if marker == "o" else 9, mew=2, path_effects=_HALO, linestyle="none")
    for i, (x, y) in enumerate(contacts):
        ax.annotate(str(i + 1), (x, y), xytext=(6, 6), textcoords="offset points", fontsize=8,
                    path_effects=[patheffects.withStroke(linewidth=2.5, foreground="w")])


def _legend(fig: Figure, purposes: list[str], *, regions: bool, threshold: float | None) -> None:
    """One legend below the panels (inside, it would cover a map)."""
    handles = [Line2D([], [], marker=_MARKS[p][0], mfc="none", mec="k", mew=2, ms=9, ls="none",
                      label=_MARKS[p][1]) for p in _MARKS if p in purposes]  # fmt: skip
    if regions:
        handles.append(Line2D([], [], color=_REGION_COLOUR, lw=2, label="region boundary"))
    if threshold is not None:
        handles.append(Line2D([], [], color=_THRESHOLD_COLOUR, lw=1,
                              label=f"variance = T_h ({threshold:.3g})"))
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=9,
                   frameon=False)


def plot_map(
    xs: NDArray[np.float64],
    ys: NDArray[np.float64],
    *,
    beta: NDArray[np.float64],
    variance: NDArray[np.float64],
    contacts: NDArray[np.float64],
    labels: NDArray[np.int64] | None = None,
    levels: NDArray[np.float64] | None = None,
    truth_hardness: NDArray[np.float64] | None = None,
    threshold: float | None = None,
    title: str = "",
    path: str | Path | None = None,
    modulus_pa: NDArray[np.float64] | None = None,
    region_field: str = "beta",
    purposes: Sequence[str | None] | None = None,
    variance_max: float | None = None,
) -> Figure:
    """The map figure: ground truth (when given) | β-field | modulus field (when given) |
    variance and contacts; the regions drawn on the field they were cut from.

    Parameters
    ----------
    xs, ys : (nx,), (ny,) float, metres
        Grid of the maps.
    beta : (ny, nx) float
        β-field mean.
    variance : (ny, nx) float
        Variance of the field the regions ran on (``region_field``'s: β², or (ln E)²).
    contacts : (k, 2) float, metres
        Poked places in order.
    labels, levels : optional
        Region label map and the isopleths drawn as contours of ``region_field``'s mean (β, or
        ln E of ``modulus_pa``); without ``levels``, the edges between the labels are drawn
        (regions labelled by nearest poke). The other field's panel shows the labels' edges.
        Each region is named at its inmost cell with the mean of the β-field over its cells (and
        on the modulus panel the geometric mean of E over them).
    truth_hardness : (ny, nx) float, optional
        Ground-truth hardness in newtons (``inf`` rigid, ``nan`` bare table); omitted without truth.
    threshold : float, optional
        The variance threshold T_h, drawn and labelled as a contour on the variance panel where
        the field crosses it.
    title : str
        The figure's title.
    path : str or Path, optional
        Where to write the figure (110 dpi, format from the suffix); nothing is written without it.
    modulus_pa : (ny, nx) float, optional
        The modulus field's median E in pascals, drawn in kPa on a log colour scale.
    region_field : {"beta", "modulus"}
        The field the regions were cut from (``modulus`` needs ``modulus_pa``).
    purposes : sequence of {"first", "variance", "boundary"} or None, optional
        Each contact's purpose, which picks its mark (circle, triangle, square); without them the
        first contact is the first poke and the others later pokes.
    variance_max : float, optional
        The top of the variance colour scale (from 0), the same for every run drawn with it so
        that runs compare; without it the scale spans 0 to this map's largest variance.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, one panel per map, each with its colour bar, and one legend below them.
    """
    if region_field == "modulus" and modulus_pa is None:
        raise ValueError("`modulus_pa` is required when `region_field` is 'modulus'")
    if variance_max is not None and not variance_max > 0:  # NaN too
        raise InvalidArgumentError(f"`variance_max` must be a number > 0; got {variance_max!r}")
    contacts = np.asarray(contacts, dtype=float).reshape(-1, 2)
    kinds = _purposes(len(contacts), purposes)
    panels = 2 + (truth_hardness is not None) + (modulus_pa is not None)
    fig = Figure(figsize=(5.2 * panels, 4.5), layout="constrained")
    axes = list(np.atleast_1d(fig.subplots(1, panels)))
    ext = _extent(xs, ys)
    if truth_hardness is not None:
        _truth_panel(fig, axes.pop(0), xs, ys, ext, truth_hardness)
    n_regions = "" if labels is None else f", {len(np.unique(labels))} region(s)"
    ax = axes.pop(0)
    im = ax.imshow(beta, origin="lower", extent=ext, cmap="magma", vmin=0.0, vmax=1.0)
    fig.colorbar(im, ax=ax, label="β (deformability) [–]")
    ax.set_title(f"β-field{n_regions if region_field == 'beta' else ''}")
    _field_overlay(ax, xs, ys, beta, labels, levels, contacts, kinds,
                   main=region_field == "beta", name=lambda v: f"β = {v:.2f}")  # fmt: skip
    if modulus_pa is not None:
        ax = axes.pop(0)
        _modulus_panel(fig, ax, ext, modulus_pa)
        ax.set_title(f"modulus field{n_regions if region_field == 'modulus' else ''}")
        _field_overlay(ax, xs, ys, np.log(modulus_pa), labels, levels, contacts, kinds,
                       main=region_field == "modulus",
                       name=lambda v: f"E = {np.exp(v) / 1e3:.3g} kPa")  # fmt: skip
    ax = axes.pop(0)
    drawn = _variance_panel(fig, ax, xs, ys, ext, variance, threshold, variance_max,
                            modulus=region_field == "modulus")  # fmt: skip
    _contacts(ax, contacts, kinds)
    for a in fig.axes:
        if a.get_label() != "<colorbar>":
            a.set_xlabel("x [m]")
            a.set_ylabel("y [m]")
    _legend(fig, kinds, regions=labels is not None and bool(np.ptp(labels) > 0),
            threshold=threshold if drawn else None)
    if title:
        fig.suptitle(title)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _field_overlay(ax: Axes, xs: NDArray, ys: NDArray, values: NDArray, labels: NDArray | None,
                   levels: NDArray | None, contacts: NDArray, kinds: list[str], *, main: bool,
                   name: Callable[[float], str]) -> None:
    """On one field's panel: the regions (its isopleths ``levels`` when the regions were cut from
    it, ``main``), the pokes, and each region named with ``name`` of its mean of ``values``."""
    _regions(ax, xs, ys, values, labels, levels if main else None, main=main)
    _contacts(ax, contacts, kinds)
    if labels is not None:
        _region_names(ax, xs, ys, labels,
                      {k: name(v) for k, v in _region_means(labels, values).items()})


def _truth_panel(fig: Figure, ax: Axes, xs: NDArray, ys: NDArray, ext: Extent,
                 truth_hardness: NDArray) -> None:
    shown = np.where(np.isinf(truth_hardness), np.nan, truth_hardness)
    im = ax.imshow(shown, origin="lower", extent=ext, cmap="viridis_r")
    rigid = np.isinf(truth_hardness)
    if rigid.any():
        ax.contourf(xs, ys, rigid.astype(float), levels=[0.5, 1.5], colors="0.3")
    fig.colorbar(im, ax=ax, label="hardness H [N] (grey: rigid)")
    ax.set_title("ground truth")


def _variance_panel(fig: Figure, ax: Axes, xs: NDArray, ys: NDArray, ext: Extent,
                    variance: NDArray, threshold: float | None, variance_max: float | None, *,
                    modulus: bool) -> bool:
    """The variance from 0 to ``variance_max`` (or its own maximum), the T_h contour labelled;
    whether that contour was drawn."""
    top = float(np.nanmax(variance)) if variance_max is None else variance_max
    im = ax.imshow(variance, origin="lower", extent=ext, cmap="Blues", vmin=0.0,
                   vmax=top if top > 0 else 1.0)  # fmt: skip
    drawn = threshold is not None and float(variance.max()) > threshold > float(variance.min())
    if drawn:
        lines = ax.contour(xs, ys, variance, levels=[threshold], colors=_THRESHOLD_COLOUR,
                           linewidths=1)  # fmt: skip
        ax.clabel(lines, fmt=lambda _: "T_h", fontsize=8, inline=True)
    name = "ln E" if modulus else "β"
    over = variance_max is not None and float(np.nanmax(variance)) > variance_max
    fig.colorbar(im, ax=ax, extend="max" if over else "neither",
                 label=f"var({name})" + (" (fixed scale)" if variance_max is not None else ""))
    ax.set_title(f"{'modulus' if modulus else 'β'}-field variance and contacts")
    return drawn


def _region_means(labels: NDArray, values: NDArray) -> dict[int, float]:
    """The mean of ``values`` over each region's cells (finite values only)."""
    out = {}
    for k in np.unique(labels):
        cells = values[(labels == k) & np.isfinite(values)]
        if k >= 0 and cells.size:
            out[int(k)] = float(cells.mean())
    return out


def _region_names(ax: Axes, xs: NDArray, ys: NDArray, labels: NDArray,
                  texts: dict[int, str]) -> None:
    """``R<k+1>`` and its text at each region's inmost cell (the cell farthest from the region's
    edge: inside the region however it is shaped, where a centroid may fall outside)."""
    for k, text in texts.items():
        inside = np.pad(labels == k, 1)  # the map's border counts as an edge
        depth = distance_transform_edt(inside)[1:-1, 1:-1]
        iy, ix = np.unravel_index(int(np.argmax(depth)), depth.shape)
        ax.text(xs[ix], ys[iy], f"R{k + 1}: {text}", ha="center", va="center", fontsize=8,
                bbox={"boxstyle": "round,pad=0.2", "fc": "w", "ec": "0.5", "alpha": 0.8})


def _regions(ax: Axes, xs: NDArray, ys: NDArray, values: NDArray, labels: NDArray | None,
             levels: NDArray | None, *, main: bool) -> None:
    """The regions on one field's panel: its isopleths ``levels`` when given, else the labels'
    outlines (dashed on the panel of the field they were not cut from)."""
    if levels is not None and len(levels):
        ax.contour(xs, ys, values, levels=np.sort(levels), colors=_REGION_COLOUR, linewidths=2)
    elif labels is not None and np.ptp(labels) > 0:
        # each region's outline (contours of the label values would draw two lines where
        # regions 0 and 2 meet)
        for label in np.unique(labels):
            ax.contour(xs, ys, (labels == label).astype(float), levels=[0.5],
                       colors=_REGION_COLOUR, linewidths=2 if main else 1,
                       linestyles="solid" if main else "dashed")  # fmt: skip


def _modulus_panel(fig: Figure, ax: Axes, ext: Extent, modulus_pa: NDArray) -> None:
    """E in kPa on a log colour scale spanning at least a factor of ten."""
    kpa = np.asarray(modulus_pa, dtype=float) / 1e3
    finite = kpa[np.isfinite(kpa) & (kpa > 0)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (1.0, 10.0)
    mid = np.sqrt(low * high)
    if high / low < 10.0:
        low, high = mid / np.sqrt(10.0), mid * np.sqrt(10.0)
    im = ax.imshow(kpa, origin="lower", extent=ext, cmap="viridis",
                   norm=LogNorm(vmin=low, vmax=high))  # fmt: skip
    bar = fig.colorbar(im, ax=ax, label="Young's modulus E [kPa] (log scale)")
    decades = float(np.log10(high / low))

    def minor(value: float, _: object) -> str:
        # over less than two decades, label the 2s and 5s between the powers of ten
        lead = round(value / 10 ** np.floor(np.log10(value)))
        return f"{value:g}" if decades < 2.0 and lead in (2, 5) else ""

    bar.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    bar.ax.yaxis.set_minor_formatter(FuncFormatter(minor))
