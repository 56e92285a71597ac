"""The figures of one poke: ``poke-NN.png`` (the paper's Fig. 4) and the error curve ε(β).

Every length is drawn in millimetres; legends sit outside the axes, where they cover no data.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from deformap.viz._overlay import extent
from deformap.viz._save import save_figure

__all__ = ["plot_beta_curve", "plot_error_curve", "plot_poke"]

#: The narrowest height span of the colour scale of the surface before the poke (metres): a depth
#: camera's random error is about 1.6 mm · z² at range z (Khoshelham & Elberink 2012, Sensors 12(2),
#: Fig. 9), so narrower relief is the surface GP's smoothing of noise.
MIN_COLOUR_SPAN_M = 1e-3

_BELOW: dict[str, Any] = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.2), "fontsize": 8,
                          "frameon": False}  # fmt: skip


def plot_beta_curve(ax: Axes, betas: NDArray, errors: NDArray, beta_hat: float, std: float) -> None:
    """Draw the shape-matching error ε(β) [mm] with the estimate and its band on ``ax``."""
    order = np.argsort(betas)
    ax.plot(np.asarray(betas)[order], np.asarray(errors)[order] * 1e3, "-", color="k")
    ax.axvline(beta_hat, color="r", label=f"β̂ = {beta_hat:.3f} ± {std:.3f}")
    ax.axvspan(max(0.0, beta_hat - std), min(1.0, beta_hat + std), color="r", alpha=0.15)
    ax.set_xlabel("β [–]")
    ax.set_ylabel("shape-matching error ε(β) [mm]")
    ax.legend(fontsize=8)


def plot_error_curve(betas: NDArray, errors: NDArray, beta: float, beta_std: float, *,
                     title: str = "shape-matching error ε(β)", path: str | Path | None = None
                     ) -> Figure:  # fmt: skip
    """:func:`plot_beta_curve` in a figure of its own: the βs tried ``(m,)`` in any order, their
    error ε(β) ``(m,)`` in metres, the estimate β̂ and its standard deviation; written to ``path``
    at 110 dpi when given."""
    fig = Figure(figsize=(5.0, 3.6), layout="constrained")
    ax = fig.subplots()
    plot_beta_curve(ax, betas, errors, beta, beta_std)
    ax.set_title(title)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _span(values: NDArray, minimum: float) -> tuple[float, float]:
    """``(low, high)`` of the finite ``values``, widened about its middle to ``minimum``."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)
    if high - low < minimum:
        mid = 0.5 * (low + high)
        low, high = mid - minimum / 2, mid + minimum / 2
    return low, high


def plot_poke(*, roi_xs: NDArray, roi_ys: NDArray, rest_z: NDArray, deformed_z: NDArray,
              roi_points: NDArray, tactile: NDArray, betas: NDArray, errors: NDArray, beta: float,
              beta_std: float, simulated_z: NDArray | None = None, title: str = "",
              path: str | Path | None = None,
              force_travel: tuple[NDArray, NDArray] | None = None,
              force_fit: NDArray | None = None, reading: str = "") -> Figure:  # fmt: skip
    """One poke's figure: above, the ROI before on a colour scale of its own (so that its relief
    shows), then on one scale the cloud while pressing, the observed dent and the simulated one at
    β̂; below, a section through them, ε(β), and force against travel.

    Parameters
    ----------
    roi_xs, roi_ys, rest_z, deformed_z : (nx,), (ny,), (ny, nx), (ny, nx) float, metres
        The grid of the region of interest, the heights before (surface GP) and while pressing
        (touch GP).
    roi_points, tactile : (n, 3), (t, 3) float, metres
        The cloud in the ROI while pressing (the robot removed) and the tactile points.
    betas, errors, beta, beta_std : (m,), (m,) float, float, float
        The βs tried, their error ε(β) in metres, the estimate β̂ and its standard deviation.
    simulated_z : (ny, nx) float, metres, optional
        The shape-matching surface at β̂ on the ROI grid ("not simulated" without it).
    path : str or Path, optional
        Where to write the figure (100 dpi); nothing is written without it.
    force_travel, force_fit : ((n,), (n,)) and (2, m) float, metres and newtons, optional
        The press's record (travel since first contact, force) and the contact model fitted to it.
    reading : str
        What the record read ("E = 9.7 ± 0.7 kPa", "rigid", or why none), in the panel's legend.
    """
    fig = Figure(figsize=(17, 8.8), layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=(1.0, 0.95))  # type: ignore[misc]
    before, cloud, observed, simulated = top.subplots(1, 4)
    section, curve, press = bottom.subplots(1, 3)
    mm = 1e3
    ext = tuple(v * mm for v in extent(roi_xs, roi_ys))
    low, high = _span(rest_z, MIN_COLOUR_SPAN_M)
    im = before.imshow(rest_z * mm, origin="lower", extent=ext, vmin=low * mm, vmax=high * mm,
                       cmap="viridis")  # fmt: skip
    top.colorbar(im, ax=before, label="z [mm] (own scale)")
    before.set_title("ROI before (surface GP)")
    # one scale for the dent's three views, from the deepest surface to the rest surface's top
    dents = [deformed_z] + ([] if simulated_z is None else [simulated_z])
    low = min(float(np.nanmin(d)) for d in dents)
    high = max(float(np.nanmax(rest_z)), low + MIN_COLOUR_SPAN_M)
    scale = {"vmin": low * mm, "vmax": high * mm, "cmap": "viridis"}
    sc = cloud.scatter(roi_points[:, 0] * mm, roi_points[:, 1] * mm, c=roi_points[:, 2] * mm,
                       s=4, **scale)  # fmt: skip
    cloud.plot(tactile[:, 0] * mm, tactile[:, 1] * mm, "r.", ms=6, label="tactile points")
    cloud.set(xlim=ext[:2], ylim=ext[2:], aspect="equal")
    cloud.legend(**_BELOW)
    cloud.set_title("cloud pressed, robot removed")
    top.colorbar(sc, ax=cloud, label="z [mm]", extend="both")
    im = observed.imshow(deformed_z * mm, origin="lower", extent=ext, **scale)
    observed.set_title("observed dent (touch GP)")
    top.colorbar(im, ax=observed, label="z [mm]")
    if simulated_z is None:
        simulated.text(0.5, 0.5, "not simulated", ha="center", va="center",
                       transform=simulated.transAxes)  # fmt: skip
        simulated.set(xlim=ext[:2], ylim=ext[2:])
    else:
        im = simulated.imshow(simulated_z * mm, origin="lower", extent=ext, **scale)
        top.colorbar(im, ax=simulated, label="z [mm]")
    simulated.set_title(f"shape matching at β̂ = {beta:.3f}")
    for ax in (before, cloud, observed, simulated):
        ax.set(xlabel="x [mm]", ylabel="y [mm]")
    _section(section, roi_xs, roi_ys, rest_z, deformed_z, simulated_z, roi_points)
    plot_beta_curve(curve, betas, errors, beta, beta_std)
    curve.set_title("shape-matching error ε(β)")
    _force_travel(press, force_travel, force_fit, reading)
    if title:  # on the upper subfigure, whose layout keeps it clear of the panels' titles
        top.suptitle(title, fontsize=13)
    if path is not None:
        save_figure(fig, path, dpi=100)
    return fig


def _section(ax: Axes, xs: NDArray, ys: NDArray, rest_z: NDArray, deformed_z: NDArray,
             simulated_z: NDArray | None, points: NDArray) -> None:
    """The row of the ROI through its middle (the contact): before, observed, simulated, and the
    cloud's points within one cell of it; millimetres on both axes."""
    mid = rest_z.shape[0] // 2
    mm = 1e3
    ax.plot(xs * mm, rest_z[mid] * mm, "k--", label="before (surface GP)")
    ax.plot(xs * mm, deformed_z[mid] * mm, "b-", lw=2, label="observed dent (touch GP)")
    if simulated_z is not None:
        ax.plot(xs * mm, simulated_z[mid] * mm, "r-", label="shape matching at β̂")
    cell = (ys[1] - ys[0]) if ys.size > 1 else np.inf
    near = np.abs(points[:, 1] - ys[mid]) < cell
    ax.plot(points[near, 0] * mm, points[near, 2] * mm, ".", color="0.6", ms=3,
            label="cloud points on the section")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_title(f"section through the contact (y = {ys[mid] * mm:.0f} mm)")
    # below the axes: inside, it would cover the dent, which is at the section's middle
    ax.legend(ncols=2, **_BELOW)


def _force_travel(ax: Axes, record: tuple[NDArray, NDArray] | None, fit: NDArray | None,
                  reading: str) -> None:
    """The press's force against the tip's travel, the fitted contact model over it, and what
    it read in the legend."""
    ax.set_title("force–travel record")
    ax.set_xlabel("travel since first contact [mm]")
    ax.set_ylabel("force [N]")
    if record is None:
        ax.text(0.5, 0.5, "no force–travel record" + (f"\n{reading}" if reading else ""),
                ha="center", va="center", transform=ax.transAxes)  # fmt: skip
        return
    travel, force = (np.asarray(v, dtype=float) for v in record)
    ax.plot(travel * 1e3, force, "o", ms=4, mfc="none", color="k", label="record")
    if fit is not None:
        ax.plot(np.asarray(fit[0]) * 1e3, fit[1], "r-", lw=1.5,
                label="contact model fitted" + (f": {reading}" if reading else ""))
    elif reading:
        ax.plot([], [], ls="none", label=reading)
    ax.grid(alpha=0.3)
    ax.legend(**_BELOW)
