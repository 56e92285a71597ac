"""Many worlds: one seeded random world, every strategy × field mapped on it, scored after each poke.

A benchmark world (:func:`draw_world`) is drawn from ``(seed, index)`` alone: its layout family is
the ``index``-th of the families asked for, in turn (so any run of ``n`` worlds spans them
evenly), and the rest is drawn from ``numpy.random.SeedSequence([seed, index])``: the layout and
its materials (:func:`deformap.world.random_scenario`, hardness over 30–250 N, the hardness study's
range, issue 13; one material rigid with probability 1/4), and the axes of the stiffness issue:
the world's physics (any of :data:`deformap.world.PHYSICS`), camera (every preset of
:data:`deformap.world.CAMERA_PRESETS`), block thickness (:data:`THICKNESSES_M`, the hardness
study's matrix) and press force (:data:`FORCES_N`).

:func:`run_world` builds that world once and maps it with every strategy × field from the same
surface model (one first observation and one fit: the same cloud and the same stream give every
combination the same model), poking to ``max_pokes``: once the map field's variance is under
``T_h`` the remaining pokes go where a region boundary is least certain
(``ExplorationConfig.boundary_pokes``), so every combination makes ``max_pokes`` pokes and the
curves compare like with like; ``threshold`` in a row says whether the variance rule was met.
Every cut (``region_labels``) asked for is scored on the same pokes: where the next poke goes
does not depend on the cut (the targets read the classes of
:func:`deformap.explore._classes.poke_classes`, before any cut), so mapping once per cut would
repeat the same pokes. After every poke it records (one row each per cut):

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

Every number of a row is a function of ``(seed, index)`` and the settings, whatever process
computes it; only the times differ between runs.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, cast, get_args, get_type_hints

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError
from deformap.eval._metrics import region_scores
from deformap.explore import (
    BetaField,
    ExplorationConfig,
    MapGrid,
    Mapper,
    ModulusField,
    PokeSet,
    RegionLabels,
    Target,
    beta_noise_floor,
    map_regions,
    poke_step,
)
from deformap.explore._nugget import with_nugget
from deformap.world import (
    CAMERA_PRESETS,
    LAYOUT_FAMILIES,
    PHYSICS,
    Physics,
    Scenario,
    SimulatedWorld,
    WorldConfig,
    camera_preset,
    random_scenario,
)

__all__ = [
    "FORCES_N",
    "HARDNESS_RANGE_N",
    "POKES_FORMAT",
    "THICKNESSES_M",
    "TIME_COLUMNS",
    "WorldDraw",
    "choices",
    "draw_world",
    "rescore_world",
    "row_values",
    "run_world",
]

#: Hardness of the benchmark's foams: the hardness study's 30–250 N (issue 13), super soft to firm.
HARDNESS_RANGE_N = (30.0, 250.0)
#: Block thicknesses: the hardness study's matrix (``study hardness --full``).
THICKNESSES_M = (0.03, 0.05, 0.10)
#: Press forces: the exploration's 0.6 N and a third below and above it. 0.4 N still dents a
#: 250 N foam by more than the camera's noise at 5 cm; 0.8 N stays within the range the world
#: presses a 30 N foam 3 cm thick without bottoming out (issue 13's forces).
FORCES_N = (0.4, 0.6, 0.8)
#: Probability that one material of a benchmark world is a rigid board (the generator's default).
P_RIGID = 0.25
#: Version of the stored pokes (a world's ``pokes`` and ``pokes_format``): 1, the columns ``x``,
#: ``y``, ``value``, ``noise``, ``index`` (worlds stored before the key was, without
#: ``thickness``, read as 1); 2, with ``thickness`` too; 3, with ``fallback_pokes`` too (the β
#: pokes of a modulus run that fell back, so that its rows are rescored, not carried). A reader
#: refuses a version it does not know rather than guess what a newer one's columns mean.
POKES_FORMAT = 3
#: Columns of a row that hold wall times (the only ones two runs of one world may differ in).
TIME_COLUMNS = ("poke_s", "elapsed_s")


def choices(field: str) -> tuple[str, ...]:
    """The values ``ExplorationConfig.<field>`` accepts (its ``Literal``): ``strategy``,
    ``field`` or ``region_labels``; new names added there are accepted here unchanged."""
    return tuple(get_args(get_type_hints(ExplorationConfig)[field]))


@dataclass(frozen=True, kw_only=True)
class WorldDraw:
    """One benchmark world: its layout and the axes it is measured under."""

    index: int
    family: str
    physics: Physics
    camera: str
    thickness_m: float
    force_n: float
    scenario: Scenario

    def summary(self) -> dict[str, Any]:
        """Plain data naming the world (its blocks' hardness and whether any is rigid)."""
        return {"index": self.index, "family": self.family, "physics": self.physics,
                "camera": self.camera, "thickness_m": self.thickness_m, "force_n": self.force_n,
                "blocks": len(self.scenario.blocks),
                "hardness_n": sorted({b.hardness for b in self.scenario.blocks
                                      if not b.rigid}),
                "rigid": any(b.rigid for b in self.scenario.blocks)}  # fmt: skip


def draw_world(seed: int, index: int, families: Sequence[str] = LAYOUT_FAMILIES,
               physics: Sequence[str] = PHYSICS) -> WorldDraw:
    """The ``index``-th world of a benchmark seeded ``seed`` (module docstring); ``physics``
    the world physics to draw from (all by default)."""
    if not families:
        raise InvalidArgumentError("`families` must name at least one layout family; got none")
    if not physics or any(p not in PHYSICS for p in physics):
        raise InvalidArgumentError(f"`physics` must be names from {list(PHYSICS)}; got "
                                   f"{list(physics)}")
    rng = np.random.default_rng(np.random.SeedSequence([seed, index]))
    family = families[index % len(families)]
    drawn = cast(Physics, str(rng.choice(list(physics))))
    camera = str(rng.choice(sorted(CAMERA_PRESETS)))
    thickness = float(rng.choice(THICKNESSES_M))
    force = float(rng.choice(FORCES_N))
    scenario = random_scenario(rng, family=family, hardness_range_n=HARDNESS_RANGE_N,
                               p_rigid=P_RIGID, thickness_m=thickness)  # fmt: skip
    return WorldDraw(index=index, family=family, physics=drawn, camera=camera,
                     thickness_m=thickness, force_n=force, scenario=scenario)


def _material_truth(scenario: Scenario, xs: NDArray, ys: NDArray
                    ) -> tuple[NDArray[np.int64], dict[int, float], NDArray[np.float64]]:
    """Labels by material (blocks of one hardness are one), their hardness, and E on the grid
    (the world's ground truth, read from its layout: no FEM needed)."""
    hardness = scenario.per_block(xs, ys, [b.hardness for b in scenario.blocks])
    values, labels = np.unique(hardness, return_inverse=True)
    return (labels.reshape(hardness.shape).astype(np.int64),
            {k: float(v) for k, v in enumerate(values)},
            scenario.per_block(xs, ys, [b.modulus_pa for b in scenario.blocks]))


def _scores(mapper: Mapper, truth: tuple[NDArray, dict[int, float], NDArray],
            cuts: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Each cut's scores of the mapper's current map (the pokes do not depend on the cut: the
    targets read the cut-free classes of :func:`deformap.explore._classes.poke_classes`)."""
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
    out = {}
    for cut in cuts:
        found = map_regions(field.mean, field.pokes, mapper.grid.cells_xy,
                            replace(mapper.config, region_labels=cast(RegionLabels, cut)),
                            field.name)  # fmt: skip
        scores = region_scores(found.labels, labels, sign * field.mean, hardness)
        out[cut] = {"accuracy": scores.accuracy, "mean_iou": scores.mean_iou,
                    "found": scores.found, "true": scores.true,
                    "kendall_tau": scores.kendall_tau, **shared}  # fmt: skip
    return out


def _map_one(world: SimulatedWorld, draw: WorldDraw, config: ExplorationConfig, surface: Any,
             truth: tuple[NDArray, dict[int, float], NDArray], seed: int,
             cuts: Sequence[str]
             ) -> tuple[list[dict[str, Any]], dict[str, list[Any]], dict[str, list[Any]] | None]:
    """Map the world with one configuration to ``max_pokes``; one row per poke and cut, the
    field's pokes at the end (:func:`poke_data`), and the β pokes of a run whose map field fell
    back to β at some poke (else ``None``)."""
    mapper = Mapper(world.workspace, config)
    mapper.surface = surface  # the combinations share the first observation's model
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

    def data(pokes: PokeSet) -> dict[str, list[Any]]:
        thickness = [records[int(i)].layer_thickness_m for i in np.asarray(pokes.index)]
        return poke_data(pokes, thickness)

    # the field's own pokes; a modulus run whose map field was β at some poke (it fell back, for
    # good or until a poke had a modulus) stores the β pokes too, which :func:`rescore_world`
    # scores those pokes' rows on
    stored = mapper.modulus_field.pokes if config.field == "modulus" else beta
    fell_back = any(r["map_field"] != config.field for r in rows)
    return rows, data(stored), (data(beta) if fell_back else None)


def poke_data(pokes: PokeSet, thickness: Sequence[float | None]) -> dict[str, list[Any]]:
    """A map field's pokes as plain data: ``x``, ``y`` [m], ``value`` (β, or ln E [ln Pa]),
    ``noise`` (its uncertainty with the field's floor; the β-field's before the map's nugget,
    which depends on the pokes so far and is estimated again when they are rescored) and
    ``index`` (the poke's number in its run, from 0) and ``thickness`` (the layer's at each poke
    [m], ``None`` where a poke had none: ``PokeRecord.layer_thickness_m``), in the field's order.
    Floats keep every bit through JSON (``repr``)."""
    return {"x": [float(v) for v in pokes.xy[:, 0]], "y": [float(v) for v in pokes.xy[:, 1]],
            "value": [float(v) for v in pokes.values], "noise": [float(v) for v in pokes.noise],
            "index": [int(v) for v in np.asarray(pokes.index)],
            "thickness": [None if t is None else float(t) for t in thickness]}


def _draw(task: dict[str, Any]) -> tuple[WorldDraw, ExplorationConfig]:
    """The world ``task`` draws (:func:`run_world`) and the exploration settings it is mapped
    with."""
    draw = draw_world(int(task["seed"]), int(task["index"]), tuple(task["families"]),
                      tuple(task.get("physics", PHYSICS)))
    k = int(task["max_pokes"])
    explore = ExplorationConfig(max_pokes=k, boundary_pokes=k, force_n=draw.force_n)
    rules: dict[str, Any] = {r: bool(task[r]) for r in ("merge_seams", "split_by_place")
                             if r in task}  # the rules on the regions, when given
    explore = replace(explore, **rules)
    return draw, explore


def _build_world(task: dict[str, Any]) -> tuple[WorldDraw, SimulatedWorld, ExplorationConfig]:
    """The world of ``task`` (:func:`run_world`), built, and the exploration settings it is
    mapped with."""
    seed, index = int(task["seed"]), int(task["index"])
    draw, explore = _draw(task)
    base = WorldConfig.coarse() if task["coarse"] else WorldConfig()
    config = replace(base, physics=draw.physics,
                     camera=replace(camera_preset(draw.camera), width=base.camera.width,
                                    height=base.camera.height) if task["coarse"]
                     else camera_preset(draw.camera))  # fmt: skip
    world_seq = np.random.SeedSequence([seed, index, 0]).spawn(2)[0]
    world = SimulatedWorld(draw.scenario, config=config, rng=np.random.default_rng(world_seq))
    return draw, world, explore


def run_world(task: dict[str, Any]) -> dict[str, Any]:
    """Build one benchmark world and map it with every strategy × field; plain data in and out.

    Parameters
    ----------
    task : dict
        ``seed``, ``index``, ``families``, ``physics`` (optional: the world physics drawn
        from, default all), ``strategies``, ``fields``, ``cuts`` (the
        ``region_labels`` scored, each on the same pokes), ``max_pokes``, ``coarse`` (the
        test mesh and camera of :meth:`WorldConfig.coarse`, else the default world),
        ``merge_seams``, ``split_by_place``, ``unread_place`` and ``boundary_score``
        (optional: ``ExplorationConfig``'s, default the exploration's).

    Returns
    -------
    dict with ``world`` (:meth:`WorldDraw.summary`), ``rows`` (one per strategy × field × cut ×
    poke, each naming them), ``pokes`` (each ``"strategy/field"``'s field's pokes,
    :func:`poke_data`: what :func:`rescore_world` scores other cuts on), ``fallback_pokes`` (the
    β pokes of each modulus ``"strategy/field"`` whose map field was β at some poke: a row's
    ``map_field`` says which), ``pokes_format`` (:data:`POKES_FORMAT`) and ``seconds`` (the
    world's wall time, building included).
    """
    t0 = time.perf_counter()
    draw, world, explore = _build_world(task)
    seed, index = int(task["seed"]), int(task["index"])
    cuts = tuple(task["cuts"])
    explore_seq = np.random.SeedSequence([seed, index, 0]).spawn(2)[1]
    first = Mapper(world.workspace, explore)
    surface = first.initialise(world.observe(), np.random.default_rng(explore_seq))
    truth = _material_truth(world.scenario, first.grid.xs, first.grid.ys)
    rows = []
    pokes, fallback = {}, {}
    for strategy in task["strategies"]:
        for field in task["fields"]:
            cfg = replace(explore, strategy=strategy, field=field)
            combo = f"{strategy}/{field}"
            mapped, pokes[combo], beta = _map_one(world, draw, cfg, surface, truth, seed, cuts)
            if beta is not None:
                fallback[combo] = beta
            for row in mapped:
                rows.append({"world": index, "family": draw.family, "strategy": strategy,
                             "field": field, **row})  # fmt: skip
    return {"world": draw.summary(), "rows": rows, "pokes": pokes, "fallback_pokes": fallback,
            "pokes_format": POKES_FORMAT, "seconds": time.perf_counter() - t0, "status": "ok",
            "error": None}


def row_values(row: dict[str, Any]) -> dict[str, Any]:
    """A row without its wall times (what two runs of one world must agree on)."""
    return {k: v for k, v in row.items() if k not in TIME_COLUMNS}


def fell_back_cuts(result: dict[str, Any]) -> dict[tuple[str, str], set[str]]:
    """The combinations ``(strategy, field)`` of a :func:`run_world` result that cannot be
    rescored: their run fell back from the modulus field to β on the way (a row's ``map_field`` is
    not its ``field``) and the result holds no β pokes of theirs (``fallback_pokes``: a world
    stored before :data:`POKES_FORMAT` 3), each with the cuts its rows were scored under."""
    stored = result.get("fallback_pokes") or {}
    fell = {(r["strategy"], r["field"]) for r in result.get("rows", [])
            if r.get("map_field", r["field"]) != r["field"]
            and f"{r['strategy']}/{r['field']}" not in stored}
    return {combo: {r["cut"] for r in result["rows"] if (r["strategy"], r["field"]) == combo}
            for combo in fell}


def rescore_world(task: dict[str, Any], result: dict[str, Any], cuts: Sequence[str],
                  **settings: Any) -> dict[str, Any]:
    """``result`` of :func:`run_world` for ``task`` with its rows scored under ``cuts`` instead,
    on the pokes it stored (no press is made again: the pokes do not depend on the cut).
    ``settings`` are the rules that act after the pokes, on the regions: ``merge_seams`` and
    ``split_by_place`` only.

    After ``k`` pokes the map field is the one of the stored pokes numbered below ``k`` (a poke
    without a value, a modulus field's poke whose record gave none, leaves a gap, as it did in the
    run), so scoring the run's own cuts again, on a world written by the same version, gives its
    rows to the bit (a test checks it). Where a modulus run's map field was β after ``k`` pokes
    (it fell back: the row's ``map_field``), that row is scored on the β pokes it stored
    (``fallback_pokes``). A world stored before those were (:data:`POKES_FORMAT` 1 and 2) carries
    such a combination's rows as they were, for the cuts it was scored under (another cut is
    refused: :func:`fell_back_cuts`). The columns that do not depend on the cut
    (``purpose``, ``threshold``, ``modulus_error``, times, ...) are the run's. A world stored
    before the pokes' layer thickness was (no ``thickness`` key) has the world's own rest height at
    each poke stand in for the surface model's
    (:func:`deformap.explore._places.merge_seam_classes` needs it).

    Raises
    ------
    InvalidArgumentError
        ``result`` did not finish, or holds no pokes (a run before they were stored); a setting
        other than those two; a cut a fallen-back combination was not scored under.
    """
    if result.get("status") != "ok" or not isinstance(result.get("pokes"), dict):
        raise InvalidArgumentError(
            f"`result` of world {task.get('index')} must be a finished world with its pokes "
            f"stored; got status {result.get('status')!r} and "
            f"{'pokes' if 'pokes' in result else 'no pokes'}")
    if set(settings) - {"merge_seams", "split_by_place"}:
        raise InvalidArgumentError(f"`settings` may set merge_seams and split_by_place only "
                                   f"(the rules that act after the pokes); got "
                                   f"{sorted(settings)}")
    draw, explore = _draw(task)  # the truth is the layout's: no world is built, nothing pressed
    scenario = draw.scenario
    grid = MapGrid.build(scenario.workspace, explore)
    labels, hardness, _ = _material_truth(scenario, grid.xs, grid.ys)
    rest_height = [b.thickness_m for b in scenario.blocks]
    head: dict[tuple[str, str, int], dict[str, Any]] = {}
    for row in result["rows"]:
        head.setdefault((row["strategy"], row["field"], int(row["poke"])), row)
    # a run that fell back from the modulus field to β mapped on two fields in turn: stored before
    # its β pokes were, its rows are carried as they were
    fell_back = fell_back_cuts(result)
    for (strategy, field_name), ran in fell_back.items():
        if set(cuts) - ran:
            raise InvalidArgumentError(
                f"`cuts` must be among those {strategy}/{field_name} of world "
                f"{task.get('index')} was scored under ({sorted(ran)}): its run fell back from "
                f"the modulus field to β, and its rows are carried, not rescored; got "
                f"{sorted(set(cuts) - ran)}")
    rows: list[dict[str, Any]] = []
    for (strategy, field_name, poke), old in sorted(head.items(), key=lambda kv: (
            task["strategies"].index(kv[0][0]), task["fields"].index(kv[0][1]), kv[0][2])):
        if (strategy, field_name) in fell_back:
            rows.extend(r for r in result["rows"] if (r["strategy"], r["field"], r["poke"])
                        == (strategy, field_name, poke) and r["cut"] in cuts)
            continue
        mapped = old.get("map_field", field_name)  # the field the run mapped on at this poke
        data = (result["pokes"] if mapped == field_name
                else result["fallback_pokes"])[f"{strategy}/{field_name}"]
        index = np.asarray(data["index"], dtype=np.int64)
        keep = index < poke
        if "thickness" in data:
            kept = [h for h, k in zip(data["thickness"], keep, strict=True) if k]
            thickness = None if any(h is None for h in kept) else np.asarray(kept, float)
        else:  # stored before the thickness was: the world's rest height stands in
            thickness = np.array([scenario.per_block([x], [y], rest_height, table=0.0)[0, 0]
                                  for x, y, k in zip(data["x"], data["y"], keep, strict=True)
                                  if k])  # fmt: skip
        pokes = PokeSet(np.column_stack([data["x"], data["y"]])[keep],
                        np.asarray(data["value"], float)[keep],
                        np.asarray(data["noise"], float)[keep], index[keep],
                        thickness=thickness)  # fmt: skip
        config = replace(explore, strategy=cast(Any, strategy),
                         field=cast(Any, mapped), **settings)
        if mapped == "modulus":
            mean = ModulusField(pokes, grid.xs, grid.ys, config.modulus_field).mean
        else:  # the map's nugget after k pokes, as the run's β-field had it
            pokes = with_nugget(pokes, config)
            mean = BetaField(pokes, grid.xs, grid.ys, config.beta_field).mean
        sign = -1.0 if mapped == "modulus" else 1.0
        for cut in cuts:  # a finished world has a poke with a value at every k (else it failed)
            found = map_regions(mean, pokes, grid.cells_xy,
                                replace(config, region_labels=cast(RegionLabels, cut)))
            scores = region_scores(found.labels, labels, sign * mean, hardness)
            rows.append({**old, "cut": cut, "accuracy": scores.accuracy,
                         "mean_iou": scores.mean_iou, "found": scores.found,
                         "true": scores.true, "kendall_tau": scores.kendall_tau})  # fmt: skip
    return {**result, "rows": rows}
