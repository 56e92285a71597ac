"""Figures of the studies: β against hardness (Fig. 5a) and fit error against cluster size (5b).

Each function takes the study's result (as :func:`deformap.eval.hardness_study` and
:func:`deformap.eval.cluster_size_study` return it), returns a :class:`matplotlib.figure.Figure`
built without ``pyplot``, and, given ``path``, writes it there atomically at 110 dpi.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from deformap.viz._save import save_figure

__all__ = ["plot_cluster_size_study", "plot_hardness_study"]


def _hardness_axis(rows: list[dict[str, Any]]) -> tuple[list[float], float]:
    finite = sorted({r["hardness_n"] for r in rows if r["hardness_n"] is not None})
    rigid_x = (max(finite) * 1.6) if finite else 1.0
    return finite, rigid_x


def plot_hardness_study(study: dict[str, Any], *, path: str | Path | None = None) -> Figure:
    """β per foam and protocol, hardness decreasing to the right as in the paper; rigid at left.

    Parameters
    ----------
    study : dict
        ``{"rows": [{"protocol", "hardness_n" (None: rigid), "beta", "beta_std"}, ...]}`` and
        optionally ``"monotone": {protocol: bool}``, marked in the legend.
    path : str or Path, optional
        Where to write the figure; nothing is written without it.
    """
    rows = study["rows"]
    _, rigid_x = _hardness_axis(rows)
    fig = Figure(figsize=(7, 4.5), layout="constrained")
    ax = fig.subplots()
    for protocol in dict.fromkeys(r["protocol"] for r in rows):
        sub = [r for r in rows if r["protocol"] == protocol]
        x = np.array([rigid_x if r["hardness_n"] is None else r["hardness_n"] for r in sub])
        y = np.array([r["beta"] for r in sub])
        err = np.nan_to_num(np.array([r["beta_std"] for r in sub]))
        order = np.argsort(-x)
        mono = study.get("monotone", {}).get(protocol)
        label = protocol + ("" if mono is None else (" ✓ monotone" if mono else " ✗ not monotone"))
        ax.errorbar(x[order], y[order], yerr=err[order], marker="o", capsize=3, label=label)
    ax.set_xscale("log")
    ax.invert_xaxis()
    ax.axvline(rigid_x / 1.25, color="0.7", ls=":")
    # at the top: the rigid board's β, near 0, would sit under the word
    ax.annotate("rigid", (rigid_x, 0.98), ha="center", va="top", fontsize=9)
    ax.set_xlabel("hardness H [N] (ISO 2439, log scale; softer →)")
    ax.set_ylabel("estimated β")
    ax.set_ylim(-0.03, 1.03)
    ax.set_title("β against hardness (same force, same places)")
    # β rises to the right (softer), so the lower right is free; upper left holds "rigid"
    ax.legend(fontsize=8, loc="lower right")
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def plot_cluster_size_study(study: dict[str, Any], *, path: str | Path | None = None) -> Figure:
    """Fit error min E(β) against cluster size, one line per foam.

    Parameters
    ----------
    study : dict
        ``{"rows": [{"cluster_size", "hardness_n" (None: rigid), "fit_error_m"}, ...]}``.
    path : str or Path, optional
        Where to write the figure; nothing is written without it.
    """
    rows = study["rows"]
    fig = Figure(figsize=(6.5, 4.2), layout="constrained")
    ax = fig.subplots()
    for hardness in dict.fromkeys(r["hardness_n"] for r in rows):
        sub = sorted(
            (r for r in rows if r["hardness_n"] == hardness), key=lambda r: r["cluster_size"]
        )
        label = "rigid" if hardness is None else f"{hardness:g} N"
        ax.plot(
            [r["cluster_size"] for r in sub],
            [r["fit_error_m"] * 1e3 for r in sub],
            marker="o",
            label=label,
        )
    ax.set_xlabel("cluster size k (k×k particles)")
    ax.set_ylabel("fit error min E(β) [mm]")
    ax.set_title("shape-matching fit error against cluster size")
    ax.legend(fontsize=8)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig
