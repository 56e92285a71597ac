"""The map figure of a run (``map.png``, the paper's Fig. 6), built without ``pyplot``.

Panels: ground truth | camera view | β-field | modulus field | behaviour | variance, each when
given. Stiffness
has one colour direction in every panel (:mod:`deformap.viz._style`); regions are named R1, R2, …
as ``pokes.csv`` numbers them, pokes from 1. ``plot_*`` functions return the figure and, given
``path``, write it atomically; no backend is selected and no global state is touched.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from deformap.errors import InvalidArgumentError
from deformap.viz._overlay import (
    MARKS,
    REGION_COLOUR,
    Extent,
    Overlay,
    draw_pokes,
    extent,
    label_place,
    poke_purposes,
)
from deformap.viz._save import save_figure
from deformap.viz._style import BETA_CMAP, RIGID_COLOUR, STIFFNESS_CMAP, modulus_norm
from deformap.world import hardness_to_youngs_modulus

__all__ = ["BEHAVIOUR_COLOURS", "plot_map"]

_THRESHOLD_COLOUR = "tab:orange"
#: The behaviour panel's colours, one per class (categorical, apart from every stiffness colour
#: map's ends): elastic blue, viscoelastic orange, plastic red, unknown pale grey, mixed purple.
BEHAVIOUR_COLOURS = {"elastic": "#1f77b4", "viscoelastic": "#ff7f0e", "plastic": "#d62728",
                     "unknown": "#d9d9d9", "mixed": "#9467bd"}


def _legend(fig: Figure, purposes: list[str], *, regions: bool, threshold: float | None,
            note: str | None) -> None:
    """One legend below the panels (inside, it would cover a map); ``note`` (no T_h contour) as
    an entry without a mark."""
    handles = [Line2D([], [], marker=MARKS[p][0], mfc="none", mec="k", mew=2, ms=9, ls="none",
                      label=MARKS[p][1]) for p in MARKS if p in purposes]  # fmt: skip
    if regions:
        handles.append(Line2D([], [], color=REGION_COLOUR, lw=2, label="region boundary"))
    if threshold is not None:
        handles.append(Line2D([], [], color=_THRESHOLD_COLOUR, lw=1.5,
                              label=f"variance = T_h ({threshold:.4g})"))
    if note is not None:
        handles.append(Line2D([], [], ls="none", label=note))
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
    class_betas: Sequence[float | None] | None = None,
    class_modulus_pa: Sequence[float | None] | None = None,
    rigid_classes: Collection[int] = (),
    appearance_rgb: NDArray[np.float64] | None = None,
    appearance_segments: NDArray[np.int64] | None = None,
    behaviour_class: NDArray[np.int64] | None = None,
    behaviour_names: Sequence[str] = (),
) -> Figure:
    """The map figure: ground truth | camera view with its segments | β-field | modulus field |
    variance and contacts (optional panels when given); regions drawn on the field cut from.

    Parameters
    ----------
    xs, ys : (nx,), (ny,) float, metres
        Grid of the maps.
    beta, variance : (ny, nx) float
        β-field mean; variance of ``region_field``'s field (β², or (ln E)²).
    contacts : (k, 2) float, metres
        Poked places in order.
    labels, levels : optional
        Region label map (label ``k`` is R(k+1)) and the isopleths of ``region_field``'s mean;
        without ``levels`` the labels' edges are drawn.
    truth_hardness : (ny, nx) float, optional
        Ground-truth hardness [N] (``inf`` rigid, ``nan`` bare), drawn as E on the modulus scale.
    threshold : float, optional
        T_h, drawn as a contour on the variance panel, or named in the legend when not crossed.
    title : str
        The figure's title.
    path : str or Path, optional
        Where to write the figure (110 dpi, format from the suffix).
    modulus_pa : (ny, nx) float, optional
        The modulus field's median E [Pa], drawn in kPa on a log scale.
    region_field : {"beta", "modulus"}
        The field the regions were cut from (``modulus`` needs ``modulus_pa``).
    purposes : sequence of {"first", "variance", "appearance", "boundary"} or None, optional
        Each contact's purpose (its mark); default: first, then variance.
    variance_max : float, optional
        Top of the variance colour scale, fixed so that runs compare; default: this map's maximum.
    class_betas, class_modulus_pa : sequence of float or None, optional
        Each region's β and E [Pa] as ``report.json`` gives them; default: the median over its cells.
    rigid_classes : collection of int
        Regions labelled "rigid".
    appearance_rgb, appearance_segments : (ny, nx, 3) float, (ny, nx) int, optional
        The appearance prior's view (sRGB in [0, 1]) and its segments (``-1`` masked).
    behaviour_class : (ny, nx) int, optional
        Each cell's behaviour class, an index into ``behaviour_names`` (names of
        :data:`BEHAVIOUR_COLOURS`; ``-1`` none), drawn in categorical colours with the regions.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if region_field == "modulus" and modulus_pa is None:
        raise ValueError("`modulus_pa` is required when `region_field` is 'modulus'")
    if variance_max is not None and not variance_max > 0:  # NaN too
        raise InvalidArgumentError(f"`variance_max` must be a number > 0; got {variance_max!r}")
    contacts = np.asarray(contacts, dtype=float).reshape(-1, 2)
    kinds = poke_purposes(len(contacts), purposes)
    if behaviour_class is not None:
        behaviour_class = np.asarray(behaviour_class)
        unnamed = [n for n in behaviour_names if n not in BEHAVIOUR_COLOURS]
        if behaviour_class.shape != np.shape(beta) or unnamed or (
                behaviour_class.size and int(behaviour_class.max()) >= len(behaviour_names)):
            raise InvalidArgumentError(
                f"`behaviour_class` must be a grid of the map's shape {np.shape(beta)} indexing "
                f"`behaviour_names` (of {sorted(BEHAVIOUR_COLOURS)}); got shape "
                f"{behaviour_class.shape} and names {list(behaviour_names)}")
    panels = (2 + (truth_hardness is not None) + (modulus_pa is not None)
              + (appearance_rgb is not None) + (behaviour_class is not None))  # fmt: skip
    fig = Figure(figsize=(5.2 * panels, 4.6), layout="constrained")
    axes = list(np.atleast_1d(fig.subplots(1, panels)))
    ext = extent(xs, ys)
    truth_kpa = None if truth_hardness is None else _truth_modulus_kpa(truth_hardness)
    kpa = None if modulus_pa is None else np.asarray(modulus_pa, dtype=float) / 1e3
    norm = modulus_norm(*(m for m in (kpa, truth_kpa) if m is not None))
    if truth_kpa is not None:
        _truth_panel(fig, axes.pop(0), xs, ys, ext, truth_kpa, norm)
    if appearance_rgb is not None:
        ax = axes.pop(0)
        _appearance_panel(ax, ext, appearance_rgb, appearance_segments)
        draw_pokes(ax, contacts, kinds)
    n_regions = "" if labels is None else f", {len(np.unique(labels))} region(s)"
    overlay = Overlay(xs, ys, labels, levels, contacts, kinds, set(rigid_classes))
    ax = axes.pop(0)
    im = ax.imshow(beta, origin="lower", extent=ext, cmap=BETA_CMAP, vmin=0.0, vmax=1.0)
    fig.colorbar(im, ax=ax, label="β (deformability) [–]; 1 soft, 0 stiff")
    ax.set_title(f"β-field{n_regions if region_field == 'beta' else ''}")
    overlay.draw(ax, beta, class_betas, main=region_field == "beta",
                 name=lambda v: f"β = {v:.2f}")  # fmt: skip
    if kpa is not None:
        ax = axes.pop(0)
        _modulus_image(fig, ax, ext, kpa, norm, "Young's modulus E [kPa] (log scale)")
        ax.set_title(f"modulus field{n_regions if region_field == 'modulus' else ''}")
        moduli = None if class_modulus_pa is None else [
            None if v is None else float(np.log(v)) for v in class_modulus_pa]  # fmt: skip
        overlay.draw(ax, np.log(kpa * 1e3), moduli, main=region_field == "modulus",
                     name=lambda v: f"E = {np.exp(v) / 1e3:.3g} kPa")  # fmt: skip
    if behaviour_class is not None:
        _behaviour_panel(fig, axes.pop(0), ext, behaviour_class, list(behaviour_names), overlay)
    ax = axes.pop(0)
    note = _variance_panel(fig, ax, xs, ys, ext, variance, threshold, variance_max,
                           modulus=region_field == "modulus")  # fmt: skip
    draw_pokes(ax, contacts, kinds)
    for a in fig.axes:
        if a.get_label() != "<colorbar>":
            a.set_xlabel("x [m]")
            a.set_ylabel("y [m]")
    _legend(fig, kinds, regions=labels is not None and bool(np.ptp(labels) > 0),
            threshold=threshold if note is None else None, note=note)
    if title:
        fig.suptitle(title)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _behaviour_panel(fig: Figure, ax: Axes, ext: Extent, classes: NDArray, names: list[str],
                     overlay: Overlay) -> None:
    """Each cell's behaviour class in its colour (the classes present on the map, named on a
    categorical colour bar), the regions' outlines (black, apart from every class colour) and
    names, and the pokes."""
    present = sorted({int(k) for k in np.unique(classes) if k >= 0})
    if not present:
        ax.set_title("behaviour: no region")
        return
    image = np.full(classes.shape, np.nan)
    for slot, k in enumerate(present):
        image[classes == k] = slot
    cmap = ListedColormap([BEHAVIOUR_COLOURS[names[k]] for k in present])
    norm = BoundaryNorm(np.arange(len(present) + 1) - 0.5, len(present))
    im = ax.imshow(image, origin="lower", extent=ext, cmap=cmap, norm=norm,
                   interpolation="nearest")  # fmt: skip
    bar = fig.colorbar(im, ax=ax, ticks=np.arange(len(present)))
    bar.ax.set_yticklabels([names[k] for k in present])
    bar.ax.tick_params(length=0)
    ax.set_title("behaviour by region (presses)")
    labels = overlay.labels
    if labels is not None and np.ptp(labels) > 0:  # black: the red boundary would vanish here
        for label in np.unique(labels):
            ax.contour(overlay.xs, overlay.ys, (labels == label).astype(float), levels=[0.5],
                       colors="k", linewidths=1.5)  # fmt: skip
    draw_pokes(ax, overlay.contacts, overlay.kinds)
    if labels is None:
        return
    for k in (int(k) for k in np.unique(labels) if k >= 0):
        cells = classes[labels == k]
        if not cells.size or cells[0] < 0:
            continue
        text = f"R{k + 1}: {names[int(cells[0])]}"
        x, y = label_place(overlay.xs, overlay.ys, labels == k, overlay.contacts, len(text))
        ax.text(x, y, text, ha="center", va="center", fontsize=8,
                bbox={"boxstyle": "round,pad=0.2", "fc": "w", "ec": "0.5", "alpha": 0.85})


def _appearance_panel(ax: Axes, ext: Extent, rgb: NDArray, segments: NDArray | None) -> None:
    """The camera's view on the map grid, the segments' edges in white."""
    ax.imshow(np.clip(rgb, 0.0, 1.0), origin="lower", extent=ext, interpolation="nearest")
    if segments is not None:
        edge = np.zeros(segments.shape, dtype=bool)
        edge[:, 1:] |= segments[:, 1:] != segments[:, :-1]
        edge[1:, :] |= segments[1:, :] != segments[:-1, :]
        overlay = np.zeros((*segments.shape, 4))
        overlay[edge] = (1.0, 1.0, 1.0, 0.9)
        ax.imshow(overlay, origin="lower", extent=ext, interpolation="nearest")
        ax.set_title(f"camera view, {int(segments.max()) + 1} segment(s)")
    else:
        ax.set_title("camera view")


def _truth_modulus_kpa(truth_hardness: NDArray) -> NDArray[np.float64]:
    """Young's modulus [kPa] of each cell's ground-truth hardness; ``inf`` (rigid) and ``nan``
    (bare table) kept."""
    hardness = np.asarray(truth_hardness, dtype=float)
    out = hardness.copy()
    foam = np.isfinite(hardness) & (hardness > 0)
    out[foam] = [hardness_to_youngs_modulus(float(h)) / 1e3 for h in hardness[foam]]
    return out


def _modulus_image(fig: Figure, ax: Axes, ext: Extent, kpa: NDArray, norm: LogNorm,
                   label: str) -> None:
    """E in kPa on the shared log scale, its colour bar's ticks as plain numbers (the 2s and 5s
    between the powers of ten labelled too when the scale spans under two decades)."""
    im = ax.imshow(np.where(np.isfinite(kpa), kpa, np.nan), origin="lower", extent=ext,
                   cmap=STIFFNESS_CMAP, norm=norm)  # fmt: skip
    bar = fig.colorbar(im, ax=ax, label=label)
    decades = float(np.log10(float(norm.vmax or 10.0) / float(norm.vmin or 1.0)))

    def minor(value: float, _: object) -> str:
        lead = round(value / 10 ** np.floor(np.log10(value)))
        return f"{value:g}" if decades < 2.0 and lead in (2, 5) else ""

    bar.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    bar.ax.yaxis.set_minor_formatter(FuncFormatter(minor))


def _truth_panel(fig: Figure, ax: Axes, xs: NDArray, ys: NDArray, ext: Extent,
                 truth_kpa: NDArray, norm: LogNorm) -> None:
    """The ground truth as E on the map's scale; rigid cells grey and named."""
    _modulus_image(fig, ax, ext, truth_kpa, norm,
                   "true E [kPa] (log scale; grey: rigid)")  # fmt: skip
    rigid = np.isinf(truth_kpa)
    if rigid.any():
        ax.contourf(xs, ys, rigid.astype(float), levels=[0.5, 1.5],
                    cmap=ListedColormap([RIGID_COLOUR]))  # fmt: skip
        depth = distance_transform_edt(np.pad(rigid, 1))[1:-1, 1:-1]
        iy, ix = np.unravel_index(int(np.argmax(depth)), depth.shape)
        ax.text(xs[ix], ys[iy], "rigid", ha="center", va="center", fontsize=9, color="w")
    ax.set_title("ground truth")


def _variance_panel(fig: Figure, ax: Axes, xs: NDArray, ys: NDArray, ext: Extent,
                    variance: NDArray, threshold: float | None, variance_max: float | None, *,
                    modulus: bool) -> str | None:
    """The variance from 0 to ``variance_max`` (or its own maximum), the T_h contour labelled;
    without a contour, the note that says why (``None`` when drawn or without T_h)."""
    top = float(np.nanmax(variance)) if variance_max is None else variance_max
    im = ax.imshow(variance, origin="lower", extent=ext, cmap="Blues", vmin=0.0,
                   vmax=top if top > 0 else 1.0)  # fmt: skip
    note = None
    if threshold is not None:
        high, low = float(np.nanmax(variance)), float(np.nanmin(variance))
        if high > threshold > low:
            lines = ax.contour(xs, ys, variance, levels=[threshold], colors=_THRESHOLD_COLOUR,
                               linewidths=1.5)  # fmt: skip
            ax.clabel(lines, fmt=lambda _: "T_h", fontsize=8, inline=True)
        else:
            side = "below" if high <= threshold else "above"
            note = f"variance {side} T_h ({threshold:.4g}) everywhere: no T_h contour"
    name = "ln E" if modulus else "β"
    over = variance_max is not None and float(np.nanmax(variance)) > variance_max
    fig.colorbar(im, ax=ax, extend="max" if over else "neither",
                 label=f"var({name})" + (" (fixed scale)" if variance_max is not None else ""))
    ax.set_title(f"{'modulus' if modulus else 'β'}-field variance and contacts")
    return note


