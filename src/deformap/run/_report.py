"""The one ``report.json`` schema, with one builder per kind of run.

Every report of a mapped surface (:func:`live_report`, :func:`session_report`) holds the core
that :func:`shared_report` builds; values of the map field (``field``) are in its units, β or
ln E [ln Pa]:

- ``pokes`` (one :meth:`deformap.explore.PokeRecord.to_dict` each, with its ``behaviour``: class,
  evidence, relaxation, loss ratio and dents with their σ), ``n_pokes``, ``stop_reason``;
- ``max_variance`` (what the stop compared with ``T_h``, over the stop cells) and
  ``max_variance_map`` (over the whole map);
- ``beta_nugget``, the β-field's nugget τ̂ (:mod:`deformap.explore._nugget`; 0 when off);
- ``field`` (``beta`` or ``modulus``), ``threshold`` (its ``T_h``,
  :func:`deformap.explore.field_settings`), ``field_fallback`` (why a run that asked for the
  modulus field maps on β, else ``None``) and ``unread_places`` (``[x, y]`` [m] of places whose
  modulus could not be read twice, left out of the targets and the stop cells);
- ``regions``: ``levels``, ``class_values``, ``class_betas`` (each class's mean poke β),
  ``class_modulus_median_pa`` (median E [Pa] over each region's cells, ``None`` without a
  modulus), ``poke_labels`` of the pokes ``poke_indices``, ``labels_by``, and with a ground truth
  the scores of :func:`deformap.eval.region_scores` (the ordering scores read the modulus field
  as ``−ln E``, which grows with softness as β does);
- ``modulus_field`` (``None`` while no poke has a modulus): ``xs_m``, ``ys_m``,
  ``log_mean_ln_pa`` and ``log_std`` (posterior mean and standard deviation of ln E, rows along
  y), ``max_variance``, ``pokes`` (``log_modulus_ln_pa``, ``rigid``, ``used``,
  ``excluded_because``) and ``n_used``;
- ``appearance``: whether the map used the camera's colours (``used``), why not (``reason``), the
  look's learned weight (``weight``, the posterior mean; ``weights`` and ``weight_posterior``, its
  grid and posterior), ``look_scale`` and ``n_segments``
  (:class:`deformap.explore.AppearanceOutcome`);
- ``true_regions`` (with a ground truth) and ``timings`` (the loop's, and per poke).

Every report also names ``deformap`` (the version), ``seed`` and the effective ``config``; a live
run adds ``scenario`` and ``timings.world_build_s``, a session its path, ``form``, ``source``,
``skipped`` and ``warnings``. :func:`estimate_report` (one poke, no map) has its own schema.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from deformap import __version__
from deformap._config import config_to_dict
from deformap.environment import TactileContact
from deformap.eval import ordering_scores, region_scores
from deformap.explore import ExplorationResult, PokeResult, field_settings
from deformap.replay import RecordedSession, ReplayResult
from deformap.run._config import RunConfig
from deformap.world import SimulatedWorld

__all__ = [
    "SHARED_KEYS",
    "estimate_report",
    "live_report",
    "modulus_report",
    "session_report",
    "shared_report",
]

SHARED_KEYS = (
    "pokes",
    "n_pokes",
    "stop_reason",
    "field",
    "field_fallback",
    "unread_places",
    "threshold",
    "max_variance",
    "max_variance_map",
    "beta_nugget",
    "regions",
    "modulus_field",
    "appearance",
    "timings",
)
"""The keys :func:`shared_report` always writes (``true_regions`` too, with a ground truth)."""

_ESTIMATE_KEYS = ("contact", "force_n", "betas", "errors", "converged", "iterations",
                  "n_roi_points", "depth_anchored", "stiffness", "layer_thickness_m",
                  "stiffness_error", "behaviour", "timings")  # fmt: skip


def _finite(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else float(value)


def _class_values(result: ExplorationResult) -> dict[str, Any]:
    """The found classes' mean β (from their pokes) and median E over their cells."""
    found = result.regions
    assert found is not None
    field = result.map_field
    betas = {p.record.index: p.record.beta for p in result.pokes}  # a skipped poke has none
    index = np.arange(len(field.pokes)) if field.pokes.index is None else field.pokes.index
    by_index = {int(i): int(k) for i, k in zip(index, found.poke_labels, strict=True)}
    class_betas = []
    for k in range(found.n_regions):
        members = [betas[i] for i, label in by_index.items() if label == k]
        class_betas.append(float(np.mean(members)) if members else None)
    medians: list[float | None] | None = None
    if result.has_modulus:
        median = result.modulus_field.median_pa
        medians = [float(np.median(median[found.labels == k])) if np.any(found.labels == k)
                   else None for k in range(found.n_regions)]  # fmt: skip
    return {"class_betas": class_betas, "class_modulus_median_pa": medians}


def _regions(result: ExplorationResult, truth: Any) -> tuple[dict[str, Any], list[Any] | None]:
    """``regions`` and ``true_regions`` (``None`` without a ground truth) of a mapped surface."""
    found = result.regions
    assert found is not None  # shared_report asks only when there are pokes
    field = result.map_field
    # under region_labels "nearest" the cells take their nearest poke's class, and the levels
    # only separate the classes' values
    regions: dict[str, Any] = {"levels": found.levels.tolist(),
                               "class_values": found.class_betas.tolist(),
                               **_class_values(result),
                               "poke_labels": found.poke_labels.tolist(),
                               # the pokes poke_labels speak of (the map field may leave some out)
                               "poke_indices": [int(i) for i in (field.pokes.index if
                                                field.pokes.index is not None else [])],
                               "labels_by": result.config.region_labels}  # fmt: skip
    if truth is None:
        return regions, None
    labels = truth.ground_truth_labels(result.xs, result.ys)
    hardness_grid = truth.ground_truth_hardness(result.xs, result.ys)
    hardness = {int(label): float(hardness_grid[labels == label][0]) for label in np.unique(labels)}
    # the metrics order by softness: β grows with it, ln E falls
    sign = -1.0 if field.name == "modulus" else 1.0
    scores = region_scores(found.labels, labels, sign * field.mean, hardness)
    # the true label under each of the field's pokes: the grid cell nearest its contact
    xy = field.pokes.xy
    col = np.abs(result.xs[None, :] - xy[:, :1]).argmin(axis=1)
    row = np.abs(result.ys[None, :] - xy[:, 1:]).argmin(axis=1)
    order = ordering_scores(found.labels, sign * found.class_betas, labels, hardness,
                            sign * field.pokes.values, labels[row, col])
    true_regions = [
        {"label": label, "hardness_n": _finite(h)} for label, h in sorted(hardness.items())
    ]
    return {**scores.to_dict(), **order.to_dict(), **regions}, true_regions


def shared_report(result: ExplorationResult, *, truth: Any = None) -> dict[str, Any]:
    """The part of ``report.json`` that a live run and a recorded session share.

    Parameters
    ----------
    result : ExplorationResult
    truth : object with ``ground_truth_labels(xs, ys)`` and ``ground_truth_hardness(xs, ys)``
        A :class:`~deformap.world.SimulatedWorld` or a session's
        :class:`~deformap.replay.GroundTruth`; ``None`` leaves the ground-truth metrics out.
    """
    var = result.map_field.variance
    pokes = [p.record.to_dict() for p in result.pokes]
    per_poke_compute = [p.record.timings.compute_s for p in result.pokes]
    regions, true_regions = _regions(result, truth) if pokes else (None, None)
    report: dict[str, Any] = {
        "pokes": pokes,
        "n_pokes": len(pokes),
        "stop_reason": result.stop_reason,
        "field": result.map_field_name,
        "field_fallback": result.field_fallback,
        "unread_places": [list(xy) for xy in result.unread_places],
        "threshold": field_settings(result.config, result.map_field_name).threshold,
        "max_variance": result.max_variance,
        "max_variance_map": float(var.max()),
        "beta_nugget": float(result.beta_field.pokes.nugget),
        "regions": regions,
        "modulus_field": modulus_report(result),
        "appearance": result.appearance.to_dict(),
    }
    if truth is not None:
        report["true_regions"] = true_regions
    report["timings"] = {
        **result.timings,
        "per_poke_s": [
            (p.record.timings.environment_s or 0.0) + c
            for p, c in zip(result.pokes, per_poke_compute, strict=True)
        ],
        "per_poke_compute_s": per_poke_compute,
    }
    return report


def _rounded(grid: Any) -> list[Any]:
    """A grid as nested lists at 6 significant digits (far below the field's own uncertainty)."""
    return [[float(f"{v:.6g}") for v in row] for row in np.asarray(grid, dtype=float)]


def modulus_report(result: ExplorationResult) -> dict[str, Any] | None:
    """``report.json``'s ``modulus_field`` (module docstring), ``None`` while no poke has a
    modulus."""
    if not result.has_modulus:
        return None
    field = result.modulus_field
    return {
        "units": {"xs_m": "m", "ys_m": "m", "log_mean_ln_pa": "ln Pa (E in Pa)",
                  "log_std": "1 (standard deviation of ln E)"},
        "xs_m": result.xs.tolist(),
        "ys_m": result.ys.tolist(),
        "log_mean_ln_pa": _rounded(field.mean),
        "log_std": _rounded(field.std),
        "max_variance": field.max_variance(result.stop_cells),
        "n_used": len(field.pokes),
        "pokes": [r.to_dict() for r in field.readings],
    }  # fmt: skip


def live_report(
    config: RunConfig, result: ExplorationResult, world: SimulatedWorld, *, world_build_s: float
) -> dict[str, Any]:
    """``report.json`` of a live exploration of a simulated world (scored against its truth)."""
    report = {
        "deformap": __version__,
        "scenario": config.scenario,
        "seed": config.seed,
        "config": config_to_dict(config),
        **shared_report(result, truth=world),
    }
    report["timings"]["world_build_s"] = world_build_s
    return report


def session_report(
    config: RunConfig, session: RecordedSession, replay: ReplayResult
) -> dict[str, Any]:
    """``report.json`` of a recorded session mapped offline (scored if it holds a ground truth)."""
    return {
        "deformap": __version__,
        "session": str(session.path),
        "form": session.form,
        "source": {k: v for k, v in session.source.items() if k != "config"},
        "seed": config.seed,
        "config": config_to_dict(config),
        **shared_report(replay.result, truth=session.ground_truth),
        "skipped": replay.skipped,
        "warnings": [*replay.warnings,
                     *([replay.result.field_fallback] if replay.result.field_fallback else [])],
    }


def estimate_report(
    before: Path, after: Path, contact: TactileContact, poke: PokeResult
) -> dict[str, Any]:
    """``estimate.json``: β of one poke with its uncertainty and E(β) curve; with a force–travel
    record its ``stiffness`` (``None`` without one), the ``layer_thickness_m`` it was read with
    and ``stiffness_error`` (why a record gave none); ``behaviour``, what the press reveals beyond
    its stiffness."""
    r = poke.record.to_dict()
    return {
        "before": str(before),
        "after": str(after),
        "beta": r["beta"],
        "beta_std": r["beta_std"],
        "contact_point": contact.contact_point.tolist(),
        **{k: r.get(k) for k in _ESTIMATE_KEYS},
    }
