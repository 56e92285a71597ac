"""The figures of a run folder: ``map.png`` and ``poke-NN.png``, ``beta-curve.png`` and
``poke.png`` of one estimated poke, and the 3D recording ``run.rrd``.

Each file is written atomically (by :mod:`deformap.viz`). :mod:`deformap.viz` is
imported when a figure is drawn, not with this module: it loads matplotlib (and rerun), which a run
without figures never needs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from deformap.explore import ExplorationResult, PokeResult
from deformap.run._report import BEHAVIOUR_NAMES, _class_values, behaviour_grids

__all__ = ["poke_figure_path", "rigid_regions", "write_estimate_figures", "write_map_figures",
           "write_poke_figure", "write_rerun"]


def write_map_figures(
    folder: Path,
    result: ExplorationResult,
    *,
    truth: Any = None,
    threshold: float | None = None,
    title: str = "",
    poke_figures: bool = True,
    variance_max: float | None = None,
) -> list[Path]:
    """``map.png`` (when there is a poke; with a behaviour panel when some poke read a known
    behaviour) and, with ``poke_figures``, one ``poke-NN.png`` per poke processed here
    (:func:`write_poke_figure`).

    Parameters
    ----------
    folder : Path
    result : ExplorationResult
    truth : object with ``ground_truth_hardness(xs, ys)``, optional
        As in :func:`~deformap.run.shared_report`; without it the map has no ground-truth panel.
    threshold : float, optional
        T_h of the map field actually used (``field_settings(result.config,
        result.map_field_name).threshold``), drawn on the variance
        panel.
    title : str
    poke_figures : bool
        False when the caller drew each poke's figure as the poke was made.
    variance_max : float, optional
        A fixed top of the variance colour scale, so that runs compare; without it each map's
        own largest variance.

    Returns
    -------
    list of Path
        The files written. A poke resumed from a journal has no arrays and no figure here.
    """
    from deformap.viz import plot_map

    written = []
    regions = result.regions
    if regions is not None:
        contacts = np.array([p.xy for p in result.pokes])
        truth_hardness = None if truth is None else truth.ground_truth_hardness(result.xs, result.ys)
        # isopleths unless a class split by behaviour made the regions no level set
        bands = np.searchsorted(regions.levels, result.map_field.mean, side="right")
        levels = (regions.levels if result.config.region_labels == "isopleth"
                  and np.array_equal(bands, regions.labels) else None)  # fmt: skip
        modulus = result.modulus_field.median_pa if result.has_modulus else None
        values = _class_values(result)  # what report.json says of each region
        image = result.appearance.image
        # the behaviour panel only when some poke read a behaviour
        known = any(p.record.behaviour is not None and p.record.behaviour.behaviour != "unknown"
                    for p in result.pokes)
        behaviour = behaviour_grids(result)["behaviour_class"] if known else None
        plot_map(result.xs, result.ys, beta=result.beta_field.mean,
                 variance=result.map_field.variance, contacts=contacts, labels=regions.labels,
                 levels=levels, truth_hardness=truth_hardness, threshold=threshold, title=title,
                 path=folder / "map.png", modulus_pa=modulus,
                 region_field=result.map_field_name,
                 purposes=[p.record.purpose for p in result.pokes],
                 variance_max=variance_max, class_betas=values["class_betas"],
                 class_modulus_pa=values["class_modulus_median_pa"],
                 rigid_classes=rigid_regions(result),
                 appearance_rgb=None if image is None else image.rgb(),
                 appearance_segments=None if image is None else image.segments,
                 behaviour_class=behaviour, behaviour_names=BEHAVIOUR_NAMES)  # fmt: skip
        written.append(folder / "map.png")
    if poke_figures:
        written += [write_poke_figure(folder, poke) for poke in result.pokes
                    if poke.dent is not None]  # a poke resumed from a journal has no arrays
    return written


def rigid_regions(result: ExplorationResult) -> set[int]:
    """The regions (labels) whose pokes all read rigid from their force–travel records."""
    regions = result.regions
    if regions is None:
        return set()
    index = result.map_field.pokes.index
    indices = range(len(regions.poke_labels)) if index is None else index
    rigid = {p.record.index: p.record.stiffness is not None and p.record.stiffness.rigid
             for p in result.pokes}  # fmt: skip
    by_label: dict[int, list[bool]] = {}
    for i, k in zip(indices, regions.poke_labels, strict=True):
        by_label.setdefault(int(k), []).append(rigid.get(int(i), False))
    return {k for k, flags in by_label.items() if flags and all(flags)}


def poke_figure_path(folder: Path, index: int) -> Path:
    """Where the figure of poke ``index`` (0-based) goes: ``poke-NN.png``, NN from 01."""
    return folder / f"poke-{index + 1:02d}.png"


def write_poke_figure(folder: Path, poke: PokeResult) -> Path:
    """``poke-NN.png`` of one processed poke (it must carry its dent's arrays)."""
    r = poke.record
    path = poke_figure_path(folder, r.index)
    _plot_poke(path, poke, f"poke {r.index + 1} at ({r.contact_xy[0]:.3f}, "
                           f"{r.contact_xy[1]:.3f}) m")  # fmt: skip
    return path


def _plot_poke(path: Path, poke: PokeResult, title: str) -> None:
    from deformap.viz import plot_poke

    r, dent = poke.record, poke.dent
    assert dent is not None  # the callers skip pokes without a dent
    # the shape-matching body at β̂ that the estimate kept (its particles start on the ROI grid)
    surface = None if poke.estimate is None else poke.estimate.surface
    simulated = None if surface is None else np.asarray(surface)[..., 2]
    if simulated is not None and simulated.shape != dent.rest_z.shape:
        simulated = None
    record = dent.force_travel
    plot_poke(roi_xs=dent.roi_xs, roi_ys=dent.roi_ys, rest_z=dent.rest_z,
              deformed_z=dent.deformed_z, roi_points=dent.roi_points, tactile=dent.tactile,
              betas=np.asarray(r.betas), errors=np.asarray(r.errors), beta=r.beta,
              beta_std=r.beta_std, simulated_z=simulated, title=title, path=path,
              force_travel=None if record is None else (record.travel_m, record.force_n),
              force_fit=dent.force_fit, reading=_reading(poke))  # fmt: skip


def _reading(poke: PokeResult) -> str:
    """What the poke's force–travel record read, as the console prints it."""
    r = poke.record
    s = r.stiffness
    if s is None:
        return "" if r.stiffness_error is None else "not read (see report.json)"
    if s.rigid:
        bound = s.stiffness_lower_n_per_m
        return "rigid" + ("" if bound is None else f" (k ≥ {bound:.0f} N/m)")
    if s.modulus_pa is None or s.modulus_std_pa is None:
        return ""
    return f"E = {s.modulus_pa / 1e3:.1f} ± {s.modulus_std_pa / 1e3:.1f} kPa"


def write_estimate_figures(folder: Path, poke: PokeResult) -> list[Path]:
    """``beta-curve.png`` (the shape-matching error ε(β)) and ``poke.png`` of one poke."""
    from deformap.viz import plot_error_curve

    r = poke.record
    plot_error_curve(np.asarray(r.betas), np.asarray(r.errors), r.beta, r.beta_std,
                     path=folder / "beta-curve.png")  # fmt: skip
    _plot_poke(folder / "poke.png", poke, "one poke")
    return [folder / "beta-curve.png", folder / "poke.png"]


def write_rerun(path: Path, result: ExplorationResult, *, truth: Any = None) -> Path:
    """The run as a rerun recording (extra ``rerun``), starting from the surface's points.

    With ``truth`` (a simulated world: ``ground_truth_hardness(xs, ys)`` and its probe in
    ``config.probe``) the recording holds the ground truth and, per poke, the robot's hull: the
    probe's ``robot_points`` at the poke's tip centre, pressing straight down as the simulated
    world does.
    """
    from deformap.viz import record_run

    surface = result.surface
    if surface is None:  # pragma: no cover - explore() fits the surface before any poke
        raise RuntimeError("the exploration has no surface model")
    truth_hardness = None if truth is None else truth.ground_truth_hardness(result.xs, result.ys)
    probe = getattr(getattr(truth, "config", None), "probe", None)
    hulls = None if probe is None else [
        probe.robot_points(np.asarray(p.record.contact.tip_center), np.array([0.0, 0.0, 1.0]))
        for p in result.pokes]  # fmt: skip
    return Path(record_run(path, result, initial_points=surface.points,
                           truth_hardness=truth_hardness, robot_points=hulls))
