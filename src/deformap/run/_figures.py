"""The figures of a run folder: ``map.png`` and ``poke-NN.png``, ``beta-curve.png`` and
``poke.png`` of one estimated poke, and the 3D recording ``run.rrd``.

Each file is written atomically (:func:`~deformap.run.atomic_path`). :mod:`deformap.viz` is
imported when a figure is drawn, not with this module: it loads matplotlib (and rerun), which a run
without figures never needs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from deformap.explore import ExplorationResult, PokeResult
from deformap.run._folder import atomic_path

__all__ = ["write_estimate_figures", "write_map_figures", "write_rerun"]


def write_map_figures(
    folder: Path,
    result: ExplorationResult,
    *,
    truth: Any = None,
    threshold: float | None = None,
    title: str = "",
) -> list[Path]:
    """``map.png`` (when there is a poke) and one ``poke-NN.png`` per poke processed here.

    Parameters
    ----------
    folder : Path
    result : ExplorationResult
    truth : object with ``ground_truth_hardness(xs, ys)``, optional
        As in :func:`~deformap.run.shared_report`; without it the map has no ground-truth panel.
    threshold : float, optional
        T_h, drawn on the variance panel.
    title : str

    Returns
    -------
    list of Path
        The files written. A poke resumed from a journal has no arrays and no figure.
    """
    from deformap.viz import plot_map, plot_poke

    mapper = result.mapper
    written = []
    if result.pokes:
        beta, var = mapper.field()
        regions = mapper.regions()
        contacts = np.array([p.xy for p in result.pokes])
        truth_hardness = None if truth is None else truth.ground_truth_hardness(mapper.xs, mapper.ys)
        levels = regions.levels if mapper.config.region_labels == "isopleth" else None
        with atomic_path(folder / "map.png") as tmp:
            plot_map(tmp, mapper.xs, mapper.ys, beta=beta, variance=var, contacts=contacts,
                     labels=regions.labels, levels=levels, truth_hardness=truth_hardness,
                     threshold=threshold, title=title)  # fmt: skip
        written.append(folder / "map.png")
    for poke in result.pokes:
        if poke.roi_xs is None:  # resumed from the journal: no arrays to draw
            continue
        r = poke.record
        path = folder / f"poke-{r['index'] + 1:02d}.png"
        title = f"poke {r['index'] + 1} at ({r['contact_xy'][0]:.3f}, {r['contact_xy'][1]:.3f}) m"
        with atomic_path(path) as tmp:
            _plot_poke(plot_poke, tmp, poke, title)
        written.append(path)
    return written


def _plot_poke(plot_poke: Any, path: Path, poke: PokeResult, title: str) -> None:
    r = poke.record
    arrays = (poke.roi_xs, poke.roi_ys, poke.rest_z, poke.deformed_z, poke.roi_points, poke.tactile)
    roi_xs, roi_ys, rest_z, deformed_z, roi_points, tactile = (np.asarray(a) for a in arrays)
    plot_poke(path, roi_xs=roi_xs, roi_ys=roi_ys, rest_z=rest_z, deformed_z=deformed_z,
              roi_points=roi_points, tactile=tactile, betas=np.asarray(r["betas"]),
              errors=np.asarray(r["errors"]), beta=r["beta"], beta_std=r["beta_std"],
              title=title)  # fmt: skip


def write_estimate_figures(folder: Path, poke: PokeResult) -> list[Path]:
    """``beta-curve.png`` (the shape-matching error E(β)) and ``poke.png`` of one poke."""
    from matplotlib.figure import Figure

    from deformap.viz import plot_beta_curve, plot_poke

    r = poke.record
    fig = Figure(figsize=(5.0, 3.6), constrained_layout=True)
    ax = fig.add_subplot()
    plot_beta_curve(ax, np.asarray(r["betas"]), np.asarray(r["errors"]), r["beta"], r["beta_std"])
    ax.set_title("shape-matching error E(β)")
    with atomic_path(folder / "beta-curve.png") as tmp:
        fig.savefig(tmp, dpi=110)
    with atomic_path(folder / "poke.png") as tmp:
        _plot_poke(plot_poke, tmp, poke, "one poke")
    return [folder / "beta-curve.png", folder / "poke.png"]


def write_rerun(path: Path, result: ExplorationResult) -> Path:
    """The run as a rerun recording (extra ``rerun``), starting from the surface's points."""
    from deformap.viz import record_run

    surface = result.mapper.surface
    if surface is None:  # pragma: no cover - explore() fits the surface before any poke
        raise RuntimeError("the exploration has no surface model")
    with atomic_path(path) as tmp:
        record_run(tmp, result, initial_points=surface.points)
    return path
