"""Many worlds: one seeded random world, every strategy × field mapped on it, scored after each poke.

:func:`run_world` builds the world of a :class:`~deformap.eval.WorldTask` once per appearance
family (:func:`deformap.eval.draw_world`: the same layout, painted) and maps it under each of the
family's arms (:meth:`~deformap.eval.WorldTask.arms`: ``ExplorationConfig.appearance`` off and
``auto``, or ``auto`` alone) with every strategy × field, each from the same start (one first
observation and one ``Mapper.initialise`` per arm, whose state every combination of the arm starts
from, copied: the same cloud and the same stream give every combination the same surface model),
poking to ``max_pokes``: once the map field's variance is under ``T_h`` the remaining pokes go
where a region boundary is least certain (``ExplorationConfig.boundary_pokes``), so every
combination makes ``max_pokes`` pokes and the curves compare like with like; ``threshold`` in a row
says whether the variance rule was met. Every cut (``region_labels``) asked for is scored on the
same pokes: where the next poke goes does not depend on the cut (the targets read the classes of
the pokes before any cut), so mapping once per cut would repeat the same pokes. After every poke it
records (one row each per cut):

- ``accuracy``, ``mean_iou``, ``found``, ``true``, ``kendall_tau``
  (:func:`deformap.eval.region_scores`) of the map field's regions against the world's truth by
  *material* (blocks of one material, a checker's diagonal squares, are one true region);
- ``modulus_error``: the median over the foam cells of ``|Ê − E| / E``, Ê the modulus field's
  median (``None`` while no poke has a modulus);
- ``beta_spread``: the β-field has no ground truth in the simulated world (β is the estimator's
  shape-matching parameter, not a property of the foam), so its error against the truth is read
  as how far it is from being constant on each material: the standard deviation of its mean over
  each foam material's cells, averaged over the materials (0 for a field that is constant on
  each material; the order of those constants is ``kendall_tau``'s);
- ``poke_s``: the poke's wall time (target, press, dent and estimate, fields), ``elapsed_s`` the
  combination's so far.

A row names its ``appearance`` family and ``prior`` (the arm's ``ExplorationConfig.appearance``).
The two arms of a painted family press the same world, and a press's noise is a function of its
place and force, so the blind map and the prior differ only by what the prior does. Every number
of a row is a function of the task, whatever process computes it; only the times differ between
runs.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Sequence
from dataclasses import replace
from functools import partial
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud
from deformap.eval._metrics import region_scores
from deformap.eval._world_draw import WorldDraw, WorldTask, material_truth
from deformap.eval._world_result import PokeData, WorldResult, poke_data
from deformap.explore import (
    ExplorationConfig,
    MapGrid,
    Mapper,
    PokeSet,
    RegionLabels,
    Target,
    beta_noise_floor,
    map_regions,
    poke_step,
)
from deformap.world import SimulatedWorld, WorldConfig, camera_preset

__all__ = ["run_world"]

_Truth = tuple[NDArray[np.int64], dict[int, float], NDArray[np.float64]]


def _scores(mapper: Mapper, truth: _Truth,
            cuts: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Each cut's scores of the mapper's current map (the pokes do not depend on the cut: the
    targets read the cut-free classes of ``poke_classes``)."""
    labels, hardness, modulus = truth
    field = mapper.map_field
    sign = -1.0 if field.name == "modulus" else 1.0  # the metrics order by softness
    foam = np.isfinite(modulus)
    modulus_error = None
    if len(mapper.modulus_field.pokes) and foam.any():
        rel = np.abs(mapper.modulus_field.median_pa[foam] / modulus[foam] - 1.0)
        modulus_error = float(np.median(rel))
    beta = mapper.beta_field.mean
    spreads = [float(np.std(beta[(labels == k) & foam])) for k in np.unique(labels[foam])]
    shared = {"modulus_error": modulus_error,
              "beta_spread": float(np.mean(spreads)) if spreads else None}
    # the map the mapper draws: under the appearance prior, `nearest` labels each cell by its
    # most correlated poke (Mapper.regions)
    correlation = None if field.models is None else field.models.correlation
    out = {}
    for cut in cuts:
        found = map_regions(field.mean, field.pokes, mapper.grid.cells_xy,
                            replace(mapper.config, region_labels=cast(RegionLabels, cut)),
                            field.name, correlation=correlation)  # fmt: skip
        scores = region_scores(found.labels, labels, sign * field.mean, hardness)
        out[cut] = {"accuracy": scores.accuracy, "mean_iou": scores.mean_iou,
                    "found": scores.found, "true": scores.true,
                    "kendall_tau": scores.kendall_tau, **shared}  # fmt: skip
    return out


def _map_one(world: SimulatedWorld, draw: WorldDraw, config: ExplorationConfig,
             start: dict[str, Any], truth: _Truth, seed: int,
             cuts: Sequence[str]
             ) -> tuple[list[dict[str, Any]], dict[str, list[Any]], dict[str, list[Any]] | None]:
    """Map the world with one configuration to ``max_pokes``; one row per poke and cut, the
    field's pokes at the end (``poke_data``), and the β pokes of a run whose map field fell
    back to β at some poke (else ``None``)."""
    mapper = Mapper(world.workspace, config)
    # what the first observation gave, copied: one combination's mapping cannot change another's
    vars(mapper).update(copy.deepcopy(start))
    streams = np.random.default_rng(np.random.SeedSequence([seed, draw.index, 1])).spawn(
        config.max_pokes + 1)
    rows: list[dict[str, Any]] = []
    t_start = time.perf_counter()
    for index in range(config.max_pokes):
        t0 = time.perf_counter()
        if index == 0:
            target: Target | None = Target(np.array(world.workspace.center, float), "first")
        else:
            target = mapper.next_target(streams[index + 1])
        if target is None:  # nothing left to poke: the map stays as it is
            break
        t_target = time.perf_counter() - t0
        poke = poke_step(mapper, index, partial(world.press, target.xy, config.force_n),
                         finish=world.release, target=target, target_s=t_target)  # fmt: skip
        t1 = time.perf_counter()
        head = {"poke": index + 1, "purpose": poke.record.purpose,
                "map_field": mapper.map_field_name,
                "threshold": bool(mapper.max_variance() <= mapper.threshold)}
        for cut, scores in _scores(mapper, truth, cuts).items():
            rows.append({"cut": cut, **head, **scores,
                         "poke_s": t1 - t0, "elapsed_s": t1 - t_start})  # fmt: skip
    records = {p.record.index: p.record for p in mapper.pokes}
    beta = PokeSet.of(list(records.values()), beta_noise_floor(config))

    def data(pokes: PokeSet) -> PokeData:
        thickness = [records[int(i)].layer_thickness_m for i in np.asarray(pokes.index)]
        return poke_data(pokes, thickness)

    # the field's own pokes; a modulus run whose map field was β at some poke (it fell back, for
    # good or until a poke had a modulus) stores the β pokes too, which :func:`rescore_world`
    # scores those pokes' rows on
    stored = mapper.modulus_field.pokes if config.field == "modulus" else beta
    fell_back = any(r["map_field"] != config.field for r in rows)
    return rows, data(stored), (data(beta) if fell_back else None)


def _build_world(task: WorldTask, appearance: str
                 ) -> tuple[WorldDraw, SimulatedWorld, ExplorationConfig]:
    """The world of ``task`` painted by ``appearance``, built, and the exploration settings it is
    mapped with."""
    draw = task.draw(appearance)
    base = WorldConfig.coarse() if task.coarse else WorldConfig()
    config = replace(base, physics=draw.physics,
                     camera=replace(camera_preset(draw.camera), width=base.camera.width,
                                    height=base.camera.height) if task.coarse
                     else camera_preset(draw.camera))  # fmt: skip
    world_seq = np.random.SeedSequence([task.seed, task.index, 0]).spawn(2)[0]
    world = SimulatedWorld(draw.scenario, config=config, rng=np.random.default_rng(world_seq))
    return draw, world, task.exploration_for(draw)


def _start(world: SimulatedWorld, config: ExplorationConfig, cloud: PointCloud,
           rng: np.random.Generator) -> dict[str, Any]:
    """What ``Mapper.initialise`` sets from the first observation under ``config`` (the surface
    model and whatever else it derives from the cloud), for every combination to start from
    without fitting it again."""
    mapper = Mapper(world.workspace, config)
    before = dict(vars(mapper))
    mapper.initialise(cloud, rng)
    return {k: v for k, v in vars(mapper).items() if k not in before or before[k] is not v}


def run_world(task: WorldTask) -> WorldResult:
    """Build the world of ``task`` and map it under every arm with every strategy × field
    (module docstring).

    Returns
    -------
    WorldResult
        One row per arm × strategy × field × cut × poke, each mapping's map-field pokes (and the
        β pokes of a modulus run that fell back to β) under :meth:`WorldResult.run_key`, and the
        world's wall time, building included.
    """
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    pokes, fallback = {}, {}
    summary: dict[str, Any] = {}
    explore_seq = np.random.SeedSequence([task.seed, task.index, 0]).spawn(2)[1]
    for appearance in task.appearances:
        draw, world, explore = _build_world(task, appearance)
        summary = summary or draw.summary()  # the same layout in every family
        cloud = world.observe()
        grid = MapGrid.build(world.workspace, explore)
        truth = material_truth(world.scenario, grid.xs, grid.ys)
        for prior in (p for a, p in task.arms() if a == appearance):
            armed = replace(explore, appearance=cast(Any, prior))
            start = _start(world, armed, cloud, np.random.default_rng(explore_seq))
            for strategy, field in ((s, f) for s in task.strategies for f in task.fields):
                cfg = replace(armed, strategy=cast(Any, strategy), field=cast(Any, field))
                key = WorldResult.run_key(appearance, prior, strategy, field)
                mapped, pokes[key], beta = _map_one(world, draw, cfg, start, truth, task.seed,
                                                    task.cuts)
                if beta is not None:
                    fallback[key] = beta
                rows.extend({"world": task.index, "family": draw.family,
                             "appearance": appearance, "prior": prior, "strategy": strategy,
                             "field": field, **row} for row in mapped)  # fmt: skip
    return WorldResult(world=summary, rows=tuple(rows), pokes=pokes,
                       fallback_pokes=fallback, seconds=time.perf_counter() - t0)
