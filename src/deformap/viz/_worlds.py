"""The many-worlds benchmark's figure: region accuracy against pokes, one panel per layout family.

Each combination (strategy/field/cut) is a line, the mean accuracy over the family's worlds after
each poke, with a band of its 95 % confidence interval (mean ± 1.96 standard errors, a normal
approximation: the worlds are independent draws) and the good-map level as a dashed line.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from numpy.typing import NDArray

from deformap.viz._save import save_figure

__all__ = ["plot_world_curves"]

_Z95 = 1.959964  # two-sided 95 % quantile of the standard normal


#: Line styles of the fields and cuts, in the order first met (solid, dashed, dotted, ...).
_STYLES: tuple[str | tuple[int, tuple[int, ...]], ...] = (
    "-", "--", ":", "-.", (0, (5, 1)), (0, (3, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (8, 3, 2, 3)))


def _line_styles(names: list[str]) -> tuple[dict[str, str], dict[str, object]]:
    """A colour per strategy and a line style per field and cut of each ``strategy/field/cut``
    name (a name of another shape is a strategy of its own), so that a reader finds a strategy by
    its colour and a cut by its line whatever the number of combinations; past ten strategies
    or eight field/cut pairs the colours or styles repeat."""
    strategies: dict[str, int] = {}
    ways: dict[str, int] = {}
    colours: dict[str, str] = {}
    styles: dict[str, object] = {}
    for name in names:
        strategy, _, way = name.partition("/")
        colours[name] = f"C{strategies.setdefault(strategy, len(strategies)) % 10}"
        styles[name] = _STYLES[ways.setdefault(way, len(ways)) % len(_STYLES)]
    return colours, styles


def plot_world_curves(curves: dict[str, dict[str, NDArray[np.float64]]], *,
                      good_accuracy: float = 0.9, path: str | Path | None = None) -> Figure:
    """Accuracy against pokes with confidence bands, one panel per family (``"all"`` first).

    Parameters
    ----------
    curves : dict
        ``{family: {combination: (n_worlds, max_pokes) accuracies}}``
        (:func:`deformap.eval.accuracy_curves`).
    good_accuracy : float
        Drawn as a dashed line.
    path : str or Path, optional
        Where to write the figure (110 dpi); nothing is written without it.
    """
    families = sorted(curves, key=lambda f: (f != "all", f))
    cols = min(3, max(1, len(families)))
    rows = math.ceil(len(families) / cols)
    fig = Figure(figsize=(4.6 * cols, 3.4 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True)
    names = sorted({name for family in curves.values() for name in family})
    colours, styles = _line_styles(names)
    band_alpha = 0.15 if len(names) <= 6 else 0.06  # many bands over each other read as one
    for ax, family in zip(axes.ravel(), families, strict=False):
        n_worlds = 0
        for name in names:
            acc = curves[family].get(name)
            if acc is None or not acc.size:
                continue
            n_worlds = max(n_worlds, len(acc))
            pokes = np.arange(1, acc.shape[1] + 1)
            mean = np.nanmean(acc, axis=0)
            counts = np.sum(np.isfinite(acc), axis=0)
            se = np.nanstd(acc, axis=0, ddof=1) / np.sqrt(counts) if len(acc) > 1 else 0 * mean
            ax.plot(pokes, mean, color=colours[name], ls=styles[name], lw=1.4, label=name)
            ax.fill_between(pokes, mean - _Z95 * se, np.minimum(1.0, mean + _Z95 * se),
                            color=colours[name], alpha=band_alpha, lw=0)
        ax.axhline(good_accuracy, color="k", ls="--", lw=0.8,
                   label=f"accuracy {good_accuracy:g} (a good map)")
        ax.set_title(f"{family} ({n_worlds} world{'s' if n_worlds != 1 else ''})", fontsize=10)
        ax.set_ylim(0.0, 1.02)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(families):]:
        ax.set_visible(False)
    # the lowest panel drawn in each column carries the poke axis (shared x hides the others')
    for col in range(cols):
        shown = [r for r in range(rows) if r * cols + col < len(families)]
        if shown:
            ax = axes[shown[-1], col]
            ax.xaxis.set_tick_params(labelbottom=True)
            ax.set_xlabel("pokes")
    for ax in axes[:, 0]:
        ax.set_ylabel("region accuracy")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncols=min(5, len(labels)),
                   fontsize=8, frameon=False)
    fig.suptitle("region accuracy against pokes: mean and 95 % band over worlds", fontsize=11)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig
