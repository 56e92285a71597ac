"""Maps a user can take away as numbers: ``map.npz`` (the grids) and ``pokes.csv`` (one row a poke).

``map.npz`` (``numpy.load(path)``, no pickle), each array ``(ny, nx)`` on the map's grid: ``xs_m
(nx,)`` and ``ys_m (ny,)``, the cells' centres in the world frame (``frame``, ``units``);
``beta_mean``, ``beta_std``; the modulus field's ``modulus_median_pa`` (exp of the mean of ln E),
``log_modulus_mean``, ``log_modulus_std`` (NaN when no poke gave a modulus); ``region_labels``
(label ``k`` is region ``R(k+1)``, -1 without a region map) and the ``field`` they were cut from;
the behaviour by region (:func:`deformap.run._report.behaviour_grids`): ``behaviour_class`` (an
index into ``behaviour_names``, -1 without a region map) and the medians ``relaxation``,
``relaxation_tau_s`` [s], ``loss_ratio``, ``residual_dent_m``, ``released_dent_m`` [m] over each
region's pokes that give them (NaN elsewhere).
The appearance prior's input: ``appearance_lab (ny, nx, 3)``, each cell's mean colour in CIELAB
(L* 0–100, a*, b*; NaN where no colour was seen or the prior was not used) and
``appearance_segments (ny, nx)`` int, each cell's segment ``0 ..`` (``-1`` where masked or the
prior was not used).

``pokes.csv``: the columns :data:`POKES_CSV_COLUMNS`, ``poke`` numbered from 1 (``report.json``'s
``index`` + 1), the contact where the tip touched, ``tip_center_z_m`` at the commanded force, the
force–travel reading (empty without one), ``region`` (``region_labels`` + 1; empty where the
map field left the poke out) and what the press reveals beyond its stiffness (``behaviour`` and
the quantities of :class:`deformap.stiffness.PressBehaviour` with their σ; empty where the press
could not give them), then ``contact_model`` (the contact model of largest weight in σ's mixture)
and ``models_fitting`` (the models the record is consistent with, ``;``-joined; see
:class:`deformap.stiffness.ContactModelFit`). :func:`write_run_results` writes every mapping
workflow's results: ``report.json``, these two files and the figures, each atomically.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from deformap._files import atomic_path, write_text_atomically
from deformap.explore import ExplorationResult, PokeResult, field_settings
from deformap.run._figures import write_map_figures, write_poke_figure
from deformap.run._folder import write_json
from deformap.run._hooks import NO_HOOKS, RunHooks
from deformap.run._report import BEHAVIOUR_NAMES, BEHAVIOUR_QUANTITIES, behaviour_grids

__all__ = ["POKES_CSV_COLUMNS", "poke_writer", "write_run_results"]

POKES_CSV_COLUMNS = (
    "poke", "purpose", "target_x_m", "target_y_m", "contact_x_m", "contact_y_m", "tip_center_z_m",
    "force_n", "beta", "beta_std", "stiffness_n_per_m", "stiffness_std_n_per_m", "modulus_pa",
    "modulus_std_pa", "rigid", "region", "behaviour", "relaxation", "relaxation_std", "tau_s",
    "tau_std_s", "loss_ratio", "loss_ratio_std", "residual_dent_m", "residual_dent_std_m",
    "released_dent_m", "released_dent_std_m", "modulus_instantaneous_pa", "modulus_relaxed_pa",
    "contact_model", "models_fitting",
)  # fmt: skip


def _write_map_npz(path: Path, result: ExplorationResult) -> None:
    """``map.npz`` of ``result`` (module docstring)."""
    shape = (result.ys.size, result.xs.size)
    nan = np.full(shape, np.nan)
    modulus = result.modulus_field
    arrays: dict[str, Any] = {
        "xs_m": result.xs, "ys_m": result.ys,
        "frame": np.array("world"),
        "units": np.array("xs_m, ys_m: m; beta: 1; modulus_median_pa: Pa; log_modulus: ln Pa; "
                          "relaxation, loss_ratio: 1; relaxation_tau_s: s; residual_dent_m, "
                          "released_dent_m: m"),
        "beta_mean": result.beta_field.mean, "beta_std": np.sqrt(result.beta_field.variance),
        "modulus_median_pa": modulus.median_pa if result.has_modulus else nan,
        "log_modulus_mean": modulus.mean if result.has_modulus else nan,
        "log_modulus_std": modulus.std if result.has_modulus else nan,
        "region_labels": (result.regions.labels if result.regions is not None
                          else np.full(shape, -1, dtype=np.int64)),
        "field": np.array(result.map_field_name),
        "behaviour_names": np.array(BEHAVIOUR_NAMES),
        "behaviour_class": np.full(shape, -1, dtype=np.int64),
        **{key: nan for key in BEHAVIOUR_QUANTITIES},
        **behaviour_grids(result),
    }  # fmt: skip
    # the appearance prior's image and segments (NaN / -1 everywhere without one)
    image = result.appearance.image
    arrays["appearance_lab"] = (np.full((*shape, 3), np.nan) if image is None
                                else np.asarray(image.lab, dtype=float))  # fmt: skip
    arrays["appearance_segments"] = (np.full(shape, -1, dtype=np.int64) if image is None
                                     else np.asarray(image.segments, dtype=np.int64))  # fmt: skip
    arrays["units"] = np.array(f"{arrays['units']}; appearance_lab: CIELAB")
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def _cell(value: Any) -> Any:
    return "" if value is None else value


def _model_cells(s: Any) -> tuple[str, str]:
    """``contact_model`` (the model of largest weight) and ``models_fitting`` (``;``-joined) of a
    poke's stiffness estimate, or ``None``."""
    if s is None or not s.model_fits:
        return "", ""
    top = max(s.model_fits, key=lambda f: f.weight)
    return top.name, ";".join(f.name for f in s.model_fits if f.fits)


def _write_pokes_csv(path: Path, result: ExplorationResult) -> None:
    """``pokes.csv`` of ``result`` (module docstring)."""
    region_of: dict[int, int] = {}
    if result.regions is not None:
        index = result.map_field.pokes.index
        assert index is not None  # PokeSet fills it
        region_of = {int(i): int(k)
                     for i, k in zip(index, result.regions.poke_labels, strict=True)}
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(POKES_CSV_COLUMNS)
    for poke in result.pokes:
        r = poke.record
        s = r.stiffness
        b = r.behaviour
        writer.writerow([
            r.index + 1, _cell(r.purpose), *(float(v) for v in r.target_xy),
            *(float(v) for v in r.contact_xy), r.contact.tip_center[2], r.force_n, r.beta,
            r.beta_std, _cell(s and s.stiffness_n_per_m), _cell(s and s.stiffness_std_n_per_m),
            _cell(s and s.modulus_pa), _cell(s and s.modulus_std_pa),
            "" if s is None else s.rigid,
            "" if r.index not in region_of else region_of[r.index] + 1,
            *(("",) * 13 if b is None else (
                b.behaviour, _cell(b.relaxation), _cell(b.relaxation_sigma), _cell(b.tau_s),
                _cell(b.tau_sigma_s), _cell(b.loss_ratio), _cell(b.loss_ratio_sigma),
                _cell(b.residual_dent_m), _cell(b.residual_dent_sigma_m),
                _cell(b.released_dent_m), _cell(b.released_dent_sigma_m),
                _cell(b.modulus_instantaneous_pa), _cell(b.modulus_relaxed_pa))),
            *_model_cells(s),
        ])  # fmt: skip
    write_text_atomically(path, text.getvalue())


def write_run_results(folder: Path, result: ExplorationResult, report: dict[str, Any], *,
                      figures: bool, title: str, truth: Any = None, poke_figures: bool = True,
                      hooks: RunHooks = NO_HOOKS, variance_max: float | None = None) -> None:
    """``report.json``, ``map.npz``, ``pokes.csv`` and, with ``figures``, ``map.png`` (T_h of the
    field the map ran on; its variance scale fixed at ``variance_max`` when given) and the
    ``poke-NN.png`` (unless the caller drew them as the pokes came: ``poke_figures=False``)."""
    write_json(folder / "report.json", report)
    _write_map_npz(folder / "map.npz", result)
    _write_pokes_csv(folder / "pokes.csv", result)
    if figures:
        hooks.stage("drawing figures")
        write_map_figures(folder, result, truth=truth,
                          threshold=field_settings(result.config,
                                                   result.map_field_name).threshold, title=title,
                          poke_figures=poke_figures, variance_max=variance_max)  # fmt: skip


def poke_writer(folder: Path, *, figures: bool, hooks: RunHooks) -> Callable[[PokeResult], None]:
    """The live loop's ``on_poke``: ``poke-NN.png`` drawn as each poke is made (so a killed run
    keeps its pokes' figures), then the progress hook."""

    def on_poke(poke: PokeResult) -> None:
        if figures:
            write_poke_figure(folder, poke)
        hooks.poke(poke.record)

    return on_poke
