"""A benchmark world scored again from the pokes it stored: other cuts or region rules, no press."""

from __future__ import annotations

from dataclasses import replace
from typing import Any, cast

import numpy as np

from deformap.errors import InvalidArgumentError
from deformap.eval._metrics import region_scores
from deformap.eval._world_draw import WorldTask, material_truth
from deformap.eval._world_result import WorldResult
from deformap.explore import (
    BetaField,
    ExplorationConfig,
    MapGrid,
    ModulusField,
    PokeSet,
    RegionLabels,
    map_regions,
)
from deformap.explore._nugget import with_nugget

__all__ = ["rescore_world"]


def rescore_world(task: WorldTask, result: WorldResult) -> WorldResult:
    """``result`` of :func:`deformap.eval.run_world` with its rows scored under ``task``'s cuts
    and exploration settings instead, on the pokes it stored (no press is made again).

    Only the settings that act after the pokes, on the map field and its regions (the cut,
    ``merge_seams``, ``split_by_place``), are measured this way, and the map field is refitted
    from the stored pokes alone: the pokes are the run's, so a
    setting that moves them would be scored on pokes it did not choose (the caller's to refuse).

    After ``k`` pokes the map field is the one of the stored pokes numbered below ``k`` (a poke
    without a value, a modulus field's poke whose record gave none, leaves a gap, as it did in
    the run), so scoring the run's own cuts again gives its rows to the bit (a test checks it).
    Where a modulus run's map field was β after ``k`` pokes (it fell back: the row's
    ``map_field``), that row is scored on the β pokes it stored (``fallback_pokes``). The columns
    that do not depend on the cut (``purpose``, ``threshold``, ``modulus_error``, times, ...) are
    the run's.

    Raises
    ------
    InvalidArgumentError
        ``result`` did not finish, or a run that fell back to β has no β pokes stored.
    """
    if result.status != "ok":
        raise InvalidArgumentError(f"`result` of world {task.index} must be a finished world; "
                                   f"got status {result.status!r}")
    draw = task.draw()  # the truth is the layout's, whatever paints it: nothing is pressed
    explore = task.exploration_for(draw)
    grid = MapGrid.build(draw.scenario.workspace, explore)
    labels, hardness, _ = material_truth(draw.scenario, grid.xs, grid.ys)
    head: dict[tuple[str, str, str, str, int], dict[str, Any]] = {}
    for row in result.rows:
        head.setdefault((row["appearance"], row["prior"], row["strategy"], row["field"],
                         int(row["poke"])), row)
    arms = task.arms()
    rows: list[dict[str, Any]] = []
    for (appearance, prior, strategy, field_name, poke), old in sorted(
            head.items(), key=lambda kv: (arms.index(kv[0][:2]), task.strategies.index(kv[0][2]),
                                          task.fields.index(kv[0][3]), kv[0][4])):
        mapped = old.get("map_field", field_name)  # the field the run mapped on at this poke
        stored = result.pokes if mapped == field_name else result.fallback_pokes
        key = WorldResult.run_key(appearance, prior, strategy, field_name)
        if key not in stored:
            raise InvalidArgumentError(f"world {task.index} stores no {mapped} pokes of "
                                       f"{key!r}, whose map field was {mapped!r} at poke {poke}")
        config = replace(explore, strategy=cast(Any, strategy), field=cast(Any, mapped),
                         appearance=cast(Any, prior))
        mean, pokes = _map_field(stored[key], poke, config, grid)
        sign = -1.0 if mapped == "modulus" else 1.0
        for cut in task.cuts:  # a finished world has a poke with a value at every k
            found = map_regions(mean, pokes, grid.cells_xy,
                                replace(config, region_labels=cast(RegionLabels, cut)),
                                mapped)
            scores = region_scores(found.labels, labels, sign * mean, hardness)
            rows.append({**old, "cut": cut, "accuracy": scores.accuracy,
                         "mean_iou": scores.mean_iou, "found": scores.found,
                         "true": scores.true, "kendall_tau": scores.kendall_tau})  # fmt: skip
    return replace(result, rows=tuple(rows))


def _map_field(data: dict[str, list[Any]], poke: int, config: ExplorationConfig, grid: MapGrid
               ) -> tuple[Any, PokeSet]:
    """The map field's mean after ``poke`` pokes, from the stored pokes numbered below it, and
    those pokes (the β-field's with the map's nugget after them, as the run had it)."""
    index = np.asarray(data["index"], dtype=np.int64)
    keep = index < poke
    kept = [h for h, k in zip(data["thickness"], keep, strict=True) if k]
    thickness = None if any(h is None for h in kept) else np.asarray(kept, float)
    pokes = PokeSet(np.column_stack([data["x"], data["y"]])[keep],
                    np.asarray(data["value"], float)[keep],
                    np.asarray(data["noise"], float)[keep], index[keep],
                    thickness=thickness)  # fmt: skip
    if config.field == "modulus":
        return ModulusField(pokes, grid.xs, grid.ys, config.modulus_field).mean, pokes
    pokes = with_nugget(pokes, config)
    return BetaField(pokes, grid.xs, grid.ys, config.beta_field).mean, pokes
