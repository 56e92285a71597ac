"""Figures of the studies: β against hardness (Fig. 5a) and fit error against cluster size (5b)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

__all__ = ["plot_cluster_size_study", "plot_hardness_study"]


def _hardness_axis(rows: list[dict[str, Any]]) -> tuple[list[float], float]:
    finite = sorted({r["hardness_n"] for r in rows if r["hardness_n"] is not None})
    rigid_x = (max(finite) * 1.6) if finite else 1.0
    return finite, rigid_x


def plot_hardness_study(path: str | Path, study: dict[str, Any]) -> Path:
    """β per foam and protocol, hardness decreasing to the right as in the paper; rigid at left."""
    rows = study["rows"]
    _, rigid_x = _hardness_axis(rows)
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
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
    ax.annotate("rigid", (rigid_x, 0.02), ha="center", fontsize=9)
    ax.set_xlabel("hardness H [N] (ISO 2439, log scale; softer →)")
    ax.set_ylabel("estimated β")
    ax.set_ylim(-0.03, 1.03)
    ax.set_title("β against hardness (same force, same places)")
    ax.legend(fontsize=8)
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def plot_cluster_size_study(path: str | Path, study: dict[str, Any]) -> Path:
    """Fit error min E(β) against cluster size, one line per foam."""
    rows = study["rows"]
    fig, ax = plt.subplots(figsize=(6.5, 4.2), constrained_layout=True)
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
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
