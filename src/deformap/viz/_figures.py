"""Figures of a run, each a :class:`matplotlib.figure.Figure` built without ``pyplot``.

``map.png`` follows the paper's Fig. 6: ground truth | β-field with region contours and the contacts
| variance with the contacts (first contact a circle, later ones triangles); with a modulus field, a
panel of E in kPa (log colour scale) comes before the variance, which is the variance of the field
the regions ran on. ``poke-NN.png``
follows its Fig. 4: the ROI before, after (cloud and reconstructed surface), the fitted dent, and
the error curve E(β).

Every ``plot_*`` function returns its figure and, given ``path``, also writes it there atomically
(a temporary file in the same folder, renamed onto ``path`` once complete). No backend is selected,
``pyplot`` is never imported and no global state is touched, so the functions are safe in notebooks
and GUI applications, which keep their own backend and display the returned figure their own way.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter
from numpy.typing import NDArray

from deformap.viz._save import save_figure

__all__ = ["plot_beta_curve", "plot_error_curve", "plot_map", "plot_poke"]


def _extent(xs: NDArray, ys: NDArray) -> list[float]:
    dx = (xs[1] - xs[0]) / 2 if xs.size > 1 else 0.0025
    dy = (ys[1] - ys[0]) / 2 if ys.size > 1 else 0.0025
    return [xs[0] - dx, xs[-1] + dx, ys[0] - dy, ys[-1] + dy]


def _contacts(ax: Axes, contacts: NDArray[np.float64]) -> None:
    if contacts.size == 0:
        return
    # black marks with a white halo: readable on the dark end of a colour map (a rigid board's
    # β = 0) as on the light one
    halo = [patheffects.withStroke(linewidth=3.5, foreground="w")]
    ax.plot(contacts[0, 0], contacts[0, 1], "o", mfc="none", mec="k", ms=10, mew=2,
            path_effects=halo)
    if len(contacts) > 1:
        ax.plot(contacts[1:, 0], contacts[1:, 1], "^", mfc="none", mec="k", ms=9, mew=2,
                path_effects=halo, linestyle="none")
    for i, (x, y) in enumerate(contacts):
        ax.annotate(str(i + 1), (x, y), xytext=(6, 6), textcoords="offset points", fontsize=8,
                    path_effects=[patheffects.withStroke(linewidth=2.5, foreground="w")])


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
    truth_hardness : (ny, nx) float, optional
        Ground-truth hardness in newtons (``inf`` rigid, ``nan`` bare table); omitted without truth.
    threshold : float, optional
        The variance threshold, drawn as a contour on the variance panel where the field crosses it.
    title : str
        The figure's title.
    path : str or Path, optional
        Where to write the figure (110 dpi, format from the suffix); nothing is written without it.
    modulus_pa : (ny, nx) float, optional
        The modulus field's median E in pascals, drawn in kPa on a log colour scale.
    region_field : {"beta", "modulus"}
        The field the regions were cut from (``modulus`` needs ``modulus_pa``).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, one panel per map, each with its colour bar.
    """
    if region_field == "modulus" and modulus_pa is None:
        raise ValueError("`modulus_pa` is required when `region_field` is 'modulus'")
    panels = 2 + (truth_hardness is not None) + (modulus_pa is not None)
    fig = Figure(figsize=(5.2 * panels, 4.0), layout="constrained")
    axes = fig.subplots(1, panels)
    ext = _extent(xs, ys)
    axes = list(np.atleast_1d(axes))
    if truth_hardness is not None:
        ax = axes.pop(0)
        shown = np.where(np.isinf(truth_hardness), np.nan, truth_hardness)
        im = ax.imshow(shown, origin="lower", extent=ext, cmap="viridis_r")
        rigid = np.isinf(truth_hardness)
        if rigid.any():
            ax.contourf(xs, ys, rigid.astype(float), levels=[0.5, 1.5], colors="0.3")
        fig.colorbar(im, ax=ax, label="hardness H [N] (grey: rigid)")
        ax.set_title("ground truth")
    n_regions = "" if labels is None else f", {len(np.unique(labels))} region(s)"
    ax = axes.pop(0)
    im = ax.imshow(beta, origin="lower", extent=ext, cmap="magma", vmin=0.0, vmax=1.0)
    _regions(ax, xs, ys, beta, labels, levels if region_field == "beta" else None,
             main=region_field == "beta")  # fmt: skip
    fig.colorbar(im, ax=ax, label="β (deformability)")
    ax.set_title(f"β-field{n_regions if region_field == 'beta' else ''}")
    _contacts(ax, contacts)
    if modulus_pa is not None:
        ax = axes.pop(0)
        _modulus_panel(fig, ax, ext, modulus_pa)
        log_e = np.log(modulus_pa)
        _regions(ax, xs, ys, log_e, labels, levels if region_field == "modulus" else None,
                 main=region_field == "modulus")  # fmt: skip
        ax.set_title(f"modulus field{n_regions if region_field == 'modulus' else ''}")
        _contacts(ax, contacts)
    ax = axes.pop(0)
    im = ax.imshow(variance, origin="lower", extent=ext, cmap="Blues")
    if threshold is not None and variance.max() > threshold > variance.min():
        ax.contour(xs, ys, variance, levels=[threshold], colors="r", linewidths=1)
    name = "ln E" if region_field == "modulus" else "β"
    fig.colorbar(im, ax=ax, label=f"var({name})")
    ax.set_title(f"{'modulus' if region_field == 'modulus' else 'β'}-field variance and contacts")
    _contacts(ax, contacts)
    for a in fig.axes:
        if a.get_label() != "<colorbar>":
            a.set_xlabel("x [m]")
            a.set_ylabel("y [m]")
    if title:
        fig.suptitle(title)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _regions(ax: Axes, xs: NDArray, ys: NDArray, values: NDArray, labels: NDArray | None,
             levels: NDArray | None, *, main: bool) -> None:
    """The regions on one field's panel: its isopleths ``levels`` when given, else the labels'
    outlines (dashed on the panel of the field they were not cut from)."""
    if levels is not None and len(levels):
        ax.contour(xs, ys, values, levels=np.sort(levels), colors="c", linewidths=2)
    elif labels is not None and np.ptp(labels) > 0:
        # each region's outline (contours of the label values would draw two lines where
        # regions 0 and 2 meet)
        for label in np.unique(labels):
            ax.contour(xs, ys, (labels == label).astype(float), levels=[0.5], colors="c",
                       linewidths=2 if main else 1,
                       linestyles="solid" if main else "dashed")  # fmt: skip


def _modulus_panel(fig: Figure, ax: Axes, ext: list[float], modulus_pa: NDArray) -> None:
    """E in kPa on a log colour scale spanning at least a factor of ten."""
    kpa = np.asarray(modulus_pa, dtype=float) / 1e3
    finite = kpa[np.isfinite(kpa) & (kpa > 0)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (1.0, 10.0)
    mid = np.sqrt(low * high)
    if high / low < 10.0:
        low, high = mid / np.sqrt(10.0), mid * np.sqrt(10.0)
    im = ax.imshow(kpa, origin="lower", extent=(ext[0], ext[1], ext[2], ext[3]), cmap="viridis",
                   norm=LogNorm(vmin=low, vmax=high))  # fmt: skip
    bar = fig.colorbar(im, ax=ax, label="Young's modulus E [kPa] (log scale)")
    decades = float(np.log10(high / low))

    def minor(value: float, _: object) -> str:
        # over less than two decades, label the 2s and 5s between the powers of ten
        lead = round(value / 10 ** np.floor(np.log10(value)))
        return f"{value:g}" if decades < 2.0 and lead in (2, 5) else ""

    bar.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    bar.ax.yaxis.set_minor_formatter(FuncFormatter(minor))


def plot_beta_curve(ax: Axes, betas: NDArray, errors: NDArray, beta_hat: float, std: float) -> None:
    """Draw E(β) with the estimate and its uncertainty band on ``ax``."""
    order = np.argsort(betas)
    ax.plot(np.asarray(betas)[order], np.asarray(errors)[order] * 1e3, "-", color="k")
    ax.axvline(beta_hat, color="r", label=f"β̂ = {beta_hat:.3f} ± {std:.3f}")
    ax.axvspan(max(0.0, beta_hat - std), min(1.0, beta_hat + std), color="r", alpha=0.15)
    ax.set_xlabel("β")
    ax.set_ylabel("E(β) [mm]")
    ax.legend(fontsize=8)


def plot_error_curve(
    betas: NDArray[np.float64],
    errors: NDArray[np.float64],
    beta: float,
    beta_std: float,
    *,
    title: str = "shape-matching error E(β)",
    path: str | Path | None = None,
) -> Figure:
    """A figure of its own holding :func:`plot_beta_curve`: E(β), β̂ and its uncertainty band.

    Parameters
    ----------
    betas, errors : (m,) float
        The βs tried and their error E(β) in metres (drawn in millimetres), in any order.
    beta, beta_std : float
        The estimate β̂ and its standard deviation.
    title : str
        The axes' title.
    path : str or Path, optional
        Where to write the figure (110 dpi, format from the suffix); nothing is written without it.
    """
    fig = Figure(figsize=(5.0, 3.6), layout="constrained")
    ax = fig.subplots()
    plot_beta_curve(ax, betas, errors, beta, beta_std)
    ax.set_title(title)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def plot_poke(
    *,
    roi_xs: NDArray[np.float64],
    roi_ys: NDArray[np.float64],
    rest_z: NDArray[np.float64],
    deformed_z: NDArray[np.float64],
    roi_points: NDArray[np.float64],
    tactile: NDArray[np.float64],
    betas: NDArray[np.float64],
    errors: NDArray[np.float64],
    beta: float,
    beta_std: float,
    simulated_z: NDArray[np.float64] | None = None,
    title: str = "",
    path: str | Path | None = None,
) -> Figure:
    """One poke's figure: the ROI before, the cloud while pressing, a section, E(β).

    Parameters
    ----------
    roi_xs, roi_ys : (nx,), (ny,) float, metres
        Grid of the region of interest around the contact.
    rest_z, deformed_z : (ny, nx) float, metres
        Heights before (surface GP) and while pressing (touch GP).
    roi_points : (n, 3) float, metres
        The cloud in the ROI while pressing, the robot removed.
    tactile : (t, 3) float, metres
        The tactile points added on the probe's tip.
    betas, errors : (m,) float
        The βs tried and their error E(β) in metres.
    beta, beta_std : float
        The estimate β̂ and its standard deviation.
    simulated_z : (ny, nx) float, metres, optional
        The shape-matching surface at β̂, drawn on the section when given.
    title : str
        The figure's title.
    path : str or Path, optional
        Where to write the figure (100 dpi, format from the suffix); nothing is written without it.
    """
    fig = Figure(figsize=(19, 4.0), layout="constrained")
    axes = fig.subplots(1, 4)
    ext = _extent(roi_xs, roi_ys)
    lo = float(min(rest_z.min(), deformed_z.min()))
    hi = float(max(rest_z.max(), deformed_z.max()))
    ax = axes[0]
    im = ax.imshow(rest_z * 1e3, origin="lower", extent=ext, vmin=lo * 1e3, vmax=hi * 1e3)
    ax.set_title("ROI before (surface GP)")
    ax.set(xlabel="x [m]", ylabel="y [m]")
    fig.colorbar(im, ax=ax, label="z [mm]")
    ax = axes[1]
    sc = ax.scatter(
        roi_points[:, 0],
        roi_points[:, 1],
        c=roi_points[:, 2] * 1e3,
        s=4,
        vmin=lo * 1e3,
        vmax=hi * 1e3,
    )
    ax.plot(tactile[:, 0], tactile[:, 1], "r.", ms=6, label="tactile points")
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_aspect("equal")
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title("cloud while pressing (robot removed)")
    ax.set(xlabel="x [m]", ylabel="y [m]")
    fig.colorbar(sc, ax=ax, label="z [mm]")
    ax = axes[2]
    mid = rest_z.shape[0] // 2
    ax.plot(roi_xs * 1e2, rest_z[mid] * 1e3, "k--", label="before")
    ax.plot(roi_xs * 1e2, deformed_z[mid] * 1e3, "b-", lw=2, label="observed dent (touch GP)")
    if simulated_z is not None:
        ax.plot(roi_xs * 1e2, simulated_z[mid] * 1e3, "r-", label="shape matching at β̂")
    near = np.abs(roi_points[:, 1] - roi_ys[mid]) < (roi_ys[1] - roi_ys[0])
    ax.plot(
        roi_points[near, 0] * 1e2,
        roi_points[near, 2] * 1e3,
        ".",
        color="0.6",
        ms=3,
        label="cloud points on the section",
    )
    ax.set_xlabel("x [cm]")
    ax.set_ylabel("z [mm]")
    ax.set_title("section through the contact")
    # below the axes: inside, it would cover the dent, which is at the section's middle
    ax.legend(fontsize=8, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    plot_beta_curve(axes[3], betas, errors, beta, beta_std)
    axes[3].set_title("shape-matching error E(β)")
    if title:
        fig.suptitle(title)
    if path is not None:
        save_figure(fig, path, dpi=100)
    return fig
