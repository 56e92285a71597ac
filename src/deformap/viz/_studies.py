"""Figures of the studies: β against hardness (Fig. 5a), fit error against cluster size (5b), and
the behaviour study's confusion matrix.

Each takes the study's result as :mod:`deformap.eval` returns it and, given ``path``, writes the
figure there at 110 dpi.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FuncFormatter, MaxNLocator, NullLocator, ScalarFormatter

from deformap.viz._save import save_figure

__all__ = ["plot_behaviour_study", "plot_cluster_size_study", "plot_hardness_study"]

_MARKERS, _LINES = "osv^<>", ("-", "--", "-.", ":")
#: The factor between neighbouring protocols' x on the log hardness axis: about a marker's width,
#: small beside the 1.4× or more between tested foams.
_DODGE = 1.03


def _hardness_axis(rows: list[dict[str, Any]]) -> tuple[list[float], float]:
    finite = sorted({r["hardness_n"] for r in rows if r["hardness_n"] is not None})
    rigid_x = (max(finite) * 1.6) if finite else 1.0
    return finite, rigid_x


def plot_hardness_study(study: dict[str, Any], *, path: str | Path | None = None) -> Figure:
    """β per protocol beside the E read and the true E per foam (β alone when no row has a
    modulus), hardness decreasing to the right as in the paper, rigid at the left; the study's
    conditions (force, thickness, camera, physics) in the title.

    ``study`` is ``{"rows": [{"protocol", "hardness_n" (None: rigid), "beta", "beta_std"}, ...]}``,
    each row optionally with ``modulus_pa``, ``modulus_std_pa``, ``true_modulus_pa``, ``rigid``
    and ``refused`` (not drawn); optionally ``"monotone": {protocol: bool}``, marked in the
    legend, and the conditions ``force_n``, ``thickness_m``, ``camera`` and ``physics``. A study
    with a ``matrix`` (``deformap study hardness --full``) is drawn by
    :func:`_plot_hardness_matrix` instead.
    """
    fig = _plot_hardness_matrix(study) if "matrix" in study else _plot_hardness(study)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _plot_hardness(study: dict[str, Any]) -> Figure:
    rows = [r for r in study["rows"] if not r.get("refused")]
    finite, rigid_x = _hardness_axis(rows)
    with_modulus = any(r.get("modulus_pa") is not None or r.get("rigid") for r in rows)
    fig = Figure(figsize=(13.0 if with_modulus else 7.5, 4.8), layout="constrained")
    axes = fig.subplots(1, 2 if with_modulus else 1, squeeze=False)[0]
    _beta_panel(axes[0], study, rows, rigid_x)
    if with_modulus:
        _modulus_panel(axes[1], [r for r in rows if r["protocol"] == _first_protocol(rows)],
                       rigid_x)  # fmt: skip
    for ax in axes:
        _hardness_ticks(ax, rows, finite, rigid_x)
    axes[-1].set_xlim(axes[0].get_xlim())  # one hardness axis: rigid's tick on both panels
    conditions = _conditions(study)
    name = "β and E against hardness" if with_modulus else "β against hardness"
    fig.suptitle(name + (f" ({conditions})" if conditions else ""), fontsize=11)
    return fig


def _conditions(study: dict[str, Any]) -> str:
    """The press force, foam thickness, camera and world physics the study ran under."""
    force, thickness = study.get("force_n"), study.get("thickness_m")
    parts = ["" if force is None else f"force {force:g} N",
             "" if thickness is None else f"foam {thickness * 100:g} cm thick",
             f"camera {study['camera']}" if study.get("camera") else "",
             f"physics {study['physics']}" if study.get("physics") else ""]
    return ", ".join(p for p in parts if p)


def _hardness_ticks(ax: Axes, rows: list[dict[str, Any]], finite: list[float],
                    rigid_x: float) -> None:
    """The log hardness axis, softer to the right, a tick per tested foam and one for rigid
    beyond a dotted line."""
    ax.set_xscale("log")
    ax.invert_xaxis()
    ax.axvline(np.sqrt(rigid_x * max(finite, default=rigid_x / 1.6)), color="0.7", ls=":")
    ticks = [*finite, rigid_x] if any(r["hardness_n"] is None for r in rows) else finite
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_major_formatter(FuncFormatter(
        lambda v, _: "rigid" if np.isclose(v, rigid_x) else f"{v:g}"))  # fmt: skip
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlabel("hardness H [N] (ISO 2439, log scale; softer →)")


def _beta_panel(ax: Axes, study: dict[str, Any], rows: list[dict[str, Any]],
                rigid_x: float) -> None:
    """β per foam and protocol, each protocol a little apart in x and with its own marker."""
    protocols = list(dict.fromkeys(r["protocol"] for r in rows))
    for i, protocol in enumerate(protocols):
        sub = [r for r in rows if r["protocol"] == protocol]
        # each protocol a little apart in x (a factor about 1.03 per protocol, on the log axis)
        # and with its own marker and line, so protocols reading the same β stay visible
        dodge = _DODGE ** (i - (len(protocols) - 1) / 2)
        foams = sorted((r for r in sub if r["hardness_n"] is not None),
                       key=lambda r: -r["hardness_n"])  # fmt: skip
        mono = study.get("monotone", {}).get(protocol)
        label = protocol + ("" if mono is None else (" ✓ monotone" if mono else " ✗ not monotone"))
        style: dict[str, Any] = {"color": f"C{i % 10}", "marker": _MARKERS[i % len(_MARKERS)],
                                 "capsize": 3, "ls": _LINES[i % len(_LINES)], "mfc": "none",
                                 "mew": 1.5}  # fmt: skip
        if foams:
            ax.errorbar([r["hardness_n"] * dodge for r in foams], [r["beta"] for r in foams],
                        yerr=np.nan_to_num([r["beta_std"] for r in foams]), label=label,
                        **style)  # fmt: skip
        for r in (r for r in sub if r["hardness_n"] is None):  # the rigid board: its own tick
            ax.errorbar([rigid_x * dodge], [r["beta"]], yerr=np.nan_to_num([r["beta_std"]]),
                        **{**style, "ls": "none", "marker": "D", "mfc": style["color"]},
                        label=None if foams else label)  # fmt: skip
    if any(r["hardness_n"] is None for r in rows):
        ax.plot([], [], "D", color="0.3", label="rigid board (filled ◆, its own tick)")
    ax.set_ylabel("estimated β [–]")
    ax.set_ylim(-0.05, 1.05)
    ax.set_title("β from shape matching, per contact protocol", fontsize=10)
    # β rises to the right (softer) and protocols that cannot tell foams apart lie along β = 0,
    # so the upper left (high β on stiff foams) is the corner no curve reaches
    ax.legend(fontsize=8, loc="upper left")


def _modulus_panel(ax: Axes, rows: list[dict[str, Any]], rigid_x: float) -> None:
    """E read from the force–travel record per foam (± its claimed σ) beside the true E; the
    rigid board at its tick, marked when read rigid."""
    foams = sorted((r for r in rows if r["hardness_n"] is not None and r.get("modulus_pa")),
                   key=lambda r: -r["hardness_n"])  # fmt: skip
    if foams:
        ax.errorbar([r["hardness_n"] for r in foams], [r["modulus_pa"] / 1e3 for r in foams],
                    yerr=[(r.get("modulus_std_pa") or 0.0) / 1e3 for r in foams], color="C0",
                    marker="o", mfc="none", mew=1.5, capsize=3,
                    label="E read from the force–travel record (± claimed σ)")  # fmt: skip
    truth = [r for r in foams if r.get("true_modulus_pa")]
    if truth:
        ax.plot([r["hardness_n"] for r in truth], [r["true_modulus_pa"] / 1e3 for r in truth],
                color="0.4", ls="--", marker="x", label="true E (from H, ISO 2439)")  # fmt: skip
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_formatter(FuncFormatter(_minor_label))
    for r in (r for r in rows if r["hardness_n"] is None):
        read = "read rigid" if r.get("rigid") else "not read rigid"
        ax.annotate(read, (rigid_x, 0.5), xycoords=("data", "axes fraction"), ha="center",
                    rotation=90, fontsize=9, color="C0" if r.get("rigid") else "C3")  # fmt: skip
    ax.set_ylabel("Young's modulus E [kPa] (log scale)")
    ax.set_title("E from the force–travel record", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")


def _plot_hardness_matrix(study: dict[str, Any]) -> Figure:
    """E read against the world's true E, one panel per physics: each foam's mean over its places
    with its claimed σ, colour per thickness, marker per camera; the diagonal is a perfect read."""
    rows = [r for r in study["rows"] if r["protocol"] == _first_protocol(study["rows"])]
    physics = list(dict.fromkeys(r["physics"] for r in rows))
    thicknesses = sorted({r["thickness_m"] for r in rows})
    cameras = list(dict.fromkeys(r["camera"] for r in rows))
    markers, colours = "osD^v<>", [f"C{i}" for i in range(10)]
    summary = {(s["camera"], s["thickness_m"], s["physics"]): s for s in study.get("summary", [])}
    overall = {o["physics"]: o for o in study.get("overall", [])}
    fig = Figure(figsize=(6.0 * len(physics), 5.2), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(physics), sharey=True))
    for ax, name in zip(axes, physics, strict=True):
        values: list[float] = []
        for (ci, camera), (ti, thickness) in itertools.product(enumerate(cameras),
                                                                enumerate(thicknesses)):
            sub = [r for r in rows if r["physics"] == name and r["camera"] == camera
                   and r["thickness_m"] == thickness and r.get("modulus_pa") is not None
                   and r.get("true_modulus_pa")]  # fmt: skip
            if not sub:
                continue
            x = np.array([r["true_modulus_pa"] for r in sub]) / 1e3
            y = np.array([r["modulus_pa"] for r in sub]) / 1e3
            err = np.array([r["modulus_std_pa"] or 0.0 for r in sub]) / 1e3
            values.extend([*x, *y])
            entry = summary.get((camera, thickness, name), {})
            ok = entry.get("modulus_monotone") and entry.get("beta_monotone")
            # open markers shrinking per camera: cameras reading alike stay visible, nested
            ax.errorbar(x, y, yerr=err, ls="none", marker=markers[ci % len(markers)],
                        ms=9 - 2 * (ci % 3), mfc="none", mew=1.3,
                        color=colours[ti % len(colours)], capsize=2, alpha=0.9,
                        label=f"{camera}, {thickness * 100:g} cm" + ("" if ok else " ✗"))  # fmt: skip
        if values:
            lo, hi = min(values) / 1.5, max(values) * 1.5
            ax.plot([lo, hi], [lo, hi], color="0.5", ls="--", lw=1, label="E read = true E")
        ax.set_xscale("log")
        ax.set_yscale("log")
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(ScalarFormatter())
            axis.set_minor_formatter(FuncFormatter(_minor_label))
        ax.set_xlabel("true Young's modulus E [kPa] (log)")
        info = overall.get(name, {})
        med, cov = info.get("modulus_median_abs_rel_error"), info.get("modulus_within_2sigma")
        ax.set_title(f"{name}: median |E error| "
                     f"{'–' if med is None else f'{med:.1%}'}, within 2σ "
                     f"{'–' if cov is None else f'{cov:.0%}'}\n"
                     f"presses {info.get('n_presses', 0)}, unread {info.get('n_unread', 0)}, "
                     f"foams refused {info.get('n_refused', 0)}",
                     fontsize=10)  # fmt: skip
        ax.legend(fontsize=7, loc="upper left", ncols=1)
    axes[0].set_ylabel("E read from the force–travel record [kPa] (log; ±claimed σ)")
    # one line over several panels; on one panel (a single physics) it would be cut: two lines
    gap = " " if len(physics) > 1 else "\n"
    fig.suptitle("Young's modulus read against the world's, per camera × thickness"
                 f"{gap}(✗: E or β not monotone, or rigid not read rigid)", fontsize=10)
    mesh_m = study.get("matrix", {}).get("element_size_m")
    if mesh_m is not None:  # the world's mesh is part of what E's error measures
        fig.supxlabel(f"world mesh: {mesh_m * 1e3:g} mm elements in plane", fontsize=8)
    return fig


def _minor_label(value: float, _: object) -> str:
    """Log axes: label the minor ticks at 2, 3 and 5 of each decade only (the others crowd)."""
    mantissa = value / 10 ** np.floor(np.log10(value))
    return f"{value:g}" if any(np.isclose(mantissa, m) for m in (2.0, 3.0, 5.0)) else ""


def _first_protocol(rows: list[dict[str, Any]]) -> str | None:
    names = list(dict.fromkeys(r["protocol"] for r in rows))
    return "force/quadratic" if "force/quadratic" in names else (names[0] if names else None)


def plot_cluster_size_study(study: dict[str, Any], *, path: str | Path | None = None) -> Figure:
    """Shape-matching fit error min ε(β) against cluster size, one line per foam, from
    ``{"rows": [{"cluster_size", "hardness_n" (None: rigid), "fit_error_m"}, ...]}``."""
    rows = study["rows"]
    fig = Figure(figsize=(6.5, 4.2), layout="constrained")
    ax = fig.subplots()
    for hardness in dict.fromkeys(r["hardness_n"] for r in rows):
        sub = sorted((r for r in rows if r["hardness_n"] == hardness),
                     key=lambda r: r["cluster_size"])  # fmt: skip
        ax.plot([r["cluster_size"] for r in sub], [r["fit_error_m"] * 1e3 for r in sub],
                marker="o", label="rigid" if hardness is None else f"{hardness:g} N")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("cluster size k (k×k particles)")
    ax.set_ylabel("fit error min ε(β) [mm]")
    ax.set_title("shape-matching fit error against cluster size")
    ax.legend(fontsize=8)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def plot_behaviour_study(study: dict[str, Any], *, path: str | Path | None = None) -> Figure:
    """The behaviour study's confusion matrix: one row per true class, one column per class read
    (``unknown`` last), each cell's count and its share of the row, coloured by that share; the
    share read right, the elastic presses flagged otherwise and the conditions in the title.

    ``study`` is :func:`deformap.eval.behaviour_summary`'s result (``confusion``, ``n_presses``,
    ``right``, ``elastic_flagged``), optionally with a ``matrix`` (``cameras``,
    ``thicknesses_m``, ``hold_s``, ``force_n``) naming the conditions.
    """
    confusion: dict[str, dict[str, int]] = study["confusion"]
    truths = list(confusion)
    reads = list(next(iter(confusion.values()))) if confusion else []
    counts = np.array([[confusion[t][r] for r in reads] for t in truths], dtype=float)
    totals = counts.sum(axis=1, keepdims=True)
    share = np.divide(counts, totals, out=np.zeros_like(counts), where=totals > 0)
    fig = Figure(figsize=(7.4, 4.6), layout="constrained")
    ax = fig.subplots()
    im = ax.imshow(share, cmap="Blues", vmin=0.0, vmax=1.0)
    fig.colorbar(im, ax=ax, label="share of the true class's presses")
    for i, j in itertools.product(range(len(truths)), range(len(reads))):
        ax.text(j, i, f"{int(counts[i, j])}\n({share[i, j]:.0%})", ha="center", va="center",
                fontsize=9, color="w" if share[i, j] > 0.6 else "k")
    ax.set_xticks(range(len(reads)), reads)
    ax.set_yticks(range(len(truths)),
                  [f"{t} ({int(n)})" for t, n in zip(truths, totals[:, 0], strict=True)])
    ax.set_xlabel("class read from the press")
    ax.set_ylabel("true class (presses)")
    right, flagged = study.get("right"), study.get("elastic_flagged")
    head = f"{study.get('n_presses', int(counts.sum()))} presses"
    if right is not None:
        head += f", {right:.0%} read right"
    if flagged is not None:
        head += f", elastic flagged otherwise {flagged:.0%}"
    matrix = study.get("matrix") or {}
    conditions = ", ".join(p for p in (
        f"cameras {', '.join(matrix['cameras'])}" if matrix.get("cameras") else "",
        "foam " + ", ".join(f"{h * 100:g}" for h in matrix["thicknesses_m"]) + " cm thick"
        if matrix.get("thicknesses_m") else "",
        f"hold {matrix['hold_s']:g} s" if matrix.get("hold_s") is not None else "",
        f"force {matrix['force_n']:g} N" if matrix.get("force_n") is not None else "") if p)
    ax.set_title(f"behaviour read against the world's truth: {head}"
                 + (f"\n{conditions}" if conditions else ""), fontsize=10)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig
