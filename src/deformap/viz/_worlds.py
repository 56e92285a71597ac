"""The many-worlds benchmark's figure: region accuracy against pokes, one panel per family.

Each panel draws the mean accuracy over the family's worlds after each poke of the best few
combinations (strategy/field/cut) and the paper's, with a 95 % band (mean ± 1.96 standard errors,
the worlds being independent draws) over enough worlds; blind curves, when given, dotted.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from numpy.typing import NDArray

from deformap.viz._save import save_figure

__all__ = ["plot_world_curves"]

_Z95 = 1.959964  # two-sided 95 % quantile of the standard normal
PAPER_COMBINATION = "paper/beta/isopleth"
"""The paper's way: its variance-led poke choice, the β-field, regions cut at isopleths."""

Curves = dict[str, dict[str, NDArray[np.float64]]]


def _chosen(curves: Curves, best: int, paper: str) -> tuple[list[str], str | None]:
    """The ``best`` combinations by mean accuracy, and the paper's (else its strategy's best)."""
    pooled = curves.get("all") or {
        name: np.concatenate([f[name] for f in curves.values() if name in f])
        for name in {n for f in curves.values() for n in f}}  # fmt: skip
    scores = {name: float(np.nanmean(acc)) if np.isfinite(acc).any() else -np.inf
              for name, acc in pooled.items() if acc.size}  # fmt: skip
    ranked = sorted(scores, key=lambda n: (-scores[n], n))
    strategy = paper.partition("/")[0]
    theirs = paper if paper in scores else next(
        (n for n in ranked if n.partition("/")[0] == strategy), None)  # fmt: skip
    return ranked[:best], theirs


def plot_world_curves(curves: Curves, *, good_accuracy: float = 0.9,
                      path: str | Path | None = None, best: int = 3, min_band_worlds: int = 10,
                      paper: str = PAPER_COMBINATION, blind: Curves | None = None) -> Figure:
    """Accuracy against pokes of the best few combinations and the paper's, one panel per family
    (``"all"`` first).

    Parameters
    ----------
    curves : dict
        ``{family: {combination: (n_worlds, max_pokes) accuracies}}``
        (:func:`deformap.eval.accuracy_curves`).
    good_accuracy : float
        Drawn as a dashed line.
    path : str or Path, optional
        Where to write the figure (110 dpi).
    best : int
        How many combinations to draw besides the paper's: a handful keeps the lines apart.
    min_band_worlds : int
        The fewest worlds for a 95 % band: over fewer the normal approximation is too rough.
    paper : str
        The paper's combination, drawn black (else its strategy's best).
    blind : dict, optional
        The same curves mapped blind (``exploration.appearance`` off), drawn dotted.
    """
    families = sorted(curves, key=lambda f: (f != "all", f))
    top, theirs = _chosen(curves, best, paper)
    shown = top + ([theirs] if theirs is not None and theirs not in top else [])
    n = max(1, len(families))
    cols = 2 if n == 4 else min(3, n)
    rows = math.ceil(n / cols)
    fig = Figure(figsize=(4.6 * cols, 3.4 * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False, sharey=True).ravel()
    for ax, family in zip(axes, families, strict=False):
        worlds = 0
        for i, name in enumerate(shown):
            acc = curves[family].get(name)
            if acc is not None and acc.size:
                worlds = max(worlds, len(acc))
                _curve(ax, acc, name, i, paper=None if name != theirs else name == paper,
                       band=min_band_worlds, arm="prior" if blind is not None else None)
            off = (blind or {}).get(family, {}).get(name)
            if off is not None and off.size:
                _curve(ax, off, name, i, paper=None if name != theirs else name == paper,
                       band=0, arm="blind")
        ax.axhline(good_accuracy, color="0.3", ls="--", lw=0.8,
                   label=f"accuracy {good_accuracy:g} (a good map)")  # fmt: skip
        note = "" if worlds >= min_band_worlds else ", too few for a band"
        ax.set_title(f"{family} ({worlds} world{'s' if worlds != 1 else ''}{note})", fontsize=10)
        ax.set(ylim=(0.0, 1.02), xlabel="pokes")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(alpha=0.3)
    for ax in axes[0::cols]:
        ax.set_ylabel("region accuracy")
    handles, labels = axes[0].get_legend_handles_labels()
    spare = axes[len(families):]
    for ax in spare:  # a slot the families leave: the legend goes there, not below
        ax.set_axis_off()
    if handles and len(spare):
        spare[0].legend(handles, labels, loc="center", fontsize=8, frameon=False)
    elif handles:
        fig.legend(handles, labels, loc="outside lower center", ncols=min(3, len(labels)),
                   fontsize=8, frameon=False)
    n_all = len({name for family in curves.values() for name in family})
    arms = "" if blind is None else "with the appearance prior solid, blind dotted; "
    fig.suptitle(f"region accuracy against pokes, mean over worlds: the best {len(top)} of "
                 f"{n_all} combinations by mean accuracy, and the paper's\n({arms}95 % band "
                 f"where {min_band_worlds} worlds or more)", fontsize=10)  # fmt: skip
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _curve(ax: Axes, acc: NDArray[np.float64], name: str, rank: int, *, paper: bool | None,
           band: int, arm: str | None = None) -> None:
    """One combination's mean accuracy after each poke, with its band over ``band`` worlds or more;
    the paper's (``paper`` not None) black and dash-dotted, ``arm="blind"`` dotted."""
    pokes = np.arange(1, acc.shape[1] + 1)
    mean = np.nanmean(acc, axis=0)
    colour, style = ("k", "-.") if paper is not None else (f"C{rank % 10}", "-")
    label = {None: f"{rank + 1}. {name}", True: f"{name} (the paper's)",
             False: f"{name} (the paper's strategy)"}[paper]  # fmt: skip
    if arm is not None:
        label = f"{label}, {arm}"
    # dotted and wider on top of the prior's, so that a blind curve equal to it still shows
    ax.plot(pokes, mean, color=colour, ls=":" if arm == "blind" else style,
            lw=2.6 if arm == "blind" else 1.6, label=label)
    counts = np.sum(np.isfinite(acc), axis=0)
    if band and counts.min() >= max(band, 2):
        se = np.nanstd(acc, axis=0, ddof=1) / np.sqrt(counts)
        ax.fill_between(pokes, mean - _Z95 * se, np.minimum(1.0, mean + _Z95 * se),
                        color=colour, alpha=0.15, lw=0)  # fmt: skip
