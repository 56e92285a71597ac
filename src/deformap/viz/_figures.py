"""Figures of a run, with matplotlib (Agg backend, files only).

``map.png`` follows the paper's Fig. 6: ground truth | β-field with region contours and the contacts
| variance with the contacts (first contact a circle, later ones triangles). ``poke-NN.png``
follows its Fig. 4: the ROI before, after (cloud and reconstructed surface), the fitted dent, and
the error curve E(β).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

__all__ = ["plot_beta_curve", "plot_map", "plot_poke"]


def _extent(xs: NDArray, ys: NDArray) -> list[float]:
    dx = (xs[1] - xs[0]) / 2 if xs.size > 1 else 0.0025
    dy = (ys[1] - ys[0]) / 2 if ys.size > 1 else 0.0025
    return [xs[0] - dx, xs[-1] + dx, ys[0] - dy, ys[-1] + dy]


def _contacts(ax: Any, contacts: NDArray[np.float64]) -> None:
    if contacts.size == 0:
        return
    ax.plot(contacts[0, 0], contacts[0, 1], "o", mfc="none", mec="k", ms=10, mew=2)
    if len(contacts) > 1:
        ax.plot(contacts[1:, 0], contacts[1:, 1], "^", mfc="none", mec="k", ms=9, mew=2)
    for i, (x, y) in enumerate(contacts):
        ax.annotate(str(i + 1), (x, y), xytext=(6, 6), textcoords="offset points", fontsize=8)


def plot_map(
    path: str | Path,
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
) -> Path:
    """Write the three-panel map figure and return its path.

    Parameters
    ----------
    xs, ys : (nx,), (ny,) float, metres
        Grid of the maps.
    beta, variance : (ny, nx) float
        β-field mean and variance.
    contacts : (k, 2) float, metres
        Poked places in order.
    labels, levels : optional
        Region label map and the isopleths drawn as contours of ``beta``; without ``levels``, the
        edges between the labels are drawn (regions labelled by nearest poke).
    truth_hardness : (ny, nx) float, optional
        Ground-truth hardness in newtons (``inf`` rigid, ``nan`` bare table); omitted without truth.
    """
    panels = 3 if truth_hardness is not None else 2
    fig, axes = plt.subplots(1, panels, figsize=(5.2 * panels, 4.0), constrained_layout=True)
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
    ax = axes[0]
    im = ax.imshow(beta, origin="lower", extent=ext, cmap="magma", vmin=0.0, vmax=1.0)
    if levels is not None and len(levels):
        ax.contour(xs, ys, beta, levels=np.sort(levels), colors="c", linewidths=2)
    elif labels is not None and np.ptp(labels) > 0:
        # each region's outline (contours of the label values would draw two lines where
        # regions 0 and 2 meet)
        for label in np.unique(labels):
            ax.contour(xs, ys, (labels == label).astype(float), levels=[0.5], colors="c",
                       linewidths=2)
    fig.colorbar(im, ax=ax, label="β (deformability)")
    n_regions = "" if labels is None else f", {len(np.unique(labels))} region(s)"
    ax.set_title(f"β-field{n_regions}")
    _contacts(ax, contacts)
    ax = axes[1]
    im = ax.imshow(variance, origin="lower", extent=ext, cmap="Blues")
    if threshold is not None and variance.max() > threshold > variance.min():
        ax.contour(xs, ys, variance, levels=[threshold], colors="r", linewidths=1)
    fig.colorbar(im, ax=ax, label="var(β)")
    ax.set_title("β-field variance and contacts")
    _contacts(ax, contacts)
    for a in fig.axes:
        if a.get_label() != "<colorbar>":
            a.set_xlabel("x [m]")
            a.set_ylabel("y [m]")
    if title:
        fig.suptitle(title)
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def plot_beta_curve(ax: Any, betas: NDArray, errors: NDArray, beta_hat: float, std: float) -> None:
    """Draw E(β) with the estimate and its uncertainty band on ``ax``."""
    order = np.argsort(betas)
    ax.plot(np.asarray(betas)[order], np.asarray(errors)[order] * 1e3, "-", color="k")
    ax.axvline(beta_hat, color="r", label=f"β̂ = {beta_hat:.3f} ± {std:.3f}")
    ax.axvspan(max(0.0, beta_hat - std), min(1.0, beta_hat + std), color="r", alpha=0.15)
    ax.set_xlabel("β")
    ax.set_ylabel("E(β) [mm]")
    ax.legend(fontsize=8)


def plot_poke(
    path: str | Path,
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
) -> Path:
    """Write one poke's figure: before, after, the fitted dent (and simulated one), E(β)."""
    fig, axes = plt.subplots(1, 4, figsize=(19, 4.0), constrained_layout=True)
    ext = _extent(roi_xs, roi_ys)
    lo = float(min(rest_z.min(), deformed_z.min()))
    hi = float(max(rest_z.max(), deformed_z.max()))
    ax = axes[0]
    im = ax.imshow(rest_z * 1e3, origin="lower", extent=ext, vmin=lo * 1e3, vmax=hi * 1e3)
    ax.set_title("ROI before (surface GP)")
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
    ax.legend(fontsize=8)
    plot_beta_curve(axes[3], betas, errors, beta, beta_std)
    axes[3].set_title("shape-matching error E(β)")
    if title:
        fig.suptitle(title)
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
