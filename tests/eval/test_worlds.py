"""The many-worlds benchmark's parts: the world draw, one world mapped, and the summary."""

from __future__ import annotations

import csv
import io
import json
from dataclasses import replace

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval import (
    CSV_COLUMNS,
    FORCES_N,
    THICKNESSES_M,
    WorldResult,
    WorldTask,
    accuracy_curves,
    choices,
    draw_world,
    markdown_summary,
    pokes_to_good,
    rescore_world,
    row_values,
    run_world,
    runs_csv,
    summarise_worlds,
)
from deformap.explore import STRATEGIES, ExplorationConfig
from deformap.world import CAMERA_PRESETS, LAYOUT_FAMILIES, PHYSICS


def test_choices_are_the_config_literals() -> None:
    assert choices("strategy") == STRATEGIES
    assert choices("field") == ("beta", "modulus")
    assert "isopleth" in choices("region_labels")


def test_worlds_take_the_families_in_turn_and_are_drawn_from_seed_and_index() -> None:
    draws = [draw_world(7, i) for i in range(12)]
    assert [d.family for d in draws] == [LAYOUT_FAMILIES[i % 6] for i in range(12)]
    assert draw_world(7, 5).scenario.to_dict() == draws[5].scenario.to_dict()
    assert draw_world(8, 5).scenario.to_dict() != draws[5].scenario.to_dict()
    assert {d.physics for d in draws} <= set(PHYSICS)
    assert {d.camera for d in draws} <= set(CAMERA_PRESETS)
    assert {d.thickness_m for d in draws} <= set(THICKNESSES_M)
    assert {d.force_n for d in draws} <= set(FORCES_N)
    assert all(b.thickness_m == d.thickness_m for d in draws for b in d.scenario.blocks)
    assert draw_world(7, 3, ("stripes",)).family == "stripes"
    assert {draw_world(7, i, physics=("stiffening-foam",)).physics for i in range(4)} == {
        "stiffening-foam"}
    assert {draw_world(7, i, physics=("stiffening-fem",)).physics for i in range(4)} == {
        "stiffening-fem"}
    json.dumps(draws[0].summary())  # plain data


def _result(index: int, family: str, accuracy: dict[str, list[float]], status: str = "ok",
            modulus_error: float | None = 0.2) -> WorldResult:
    rows = [{"appearance": "plain", "prior": "auto",
             "strategy": name.split("/")[0], "field": name.split("/")[1], "cut": "isopleth",
             "poke": k + 1, "purpose": "variance", "map_field": name.split("/")[1],
             "threshold": False, "accuracy": a, "mean_iou": a, "found": 2, "true": 2,
             "kendall_tau": 1.0, "modulus_error": modulus_error, "beta_spread": 0.1,
             "poke_s": 1.0, "elapsed_s": k + 1.0}
            for name, series in accuracy.items() for k, a in enumerate(series)]
    world = {"index": index, "family": family, "physics": "linear-fem", "camera": "primesense",
             "thickness_m": 0.05, "force_n": 0.6}
    if status != "ok":
        return WorldResult(world=world, status="failed", error="Boom: no")
    return WorldResult(world=world, rows=tuple(rows), seconds=3.0)


COMBOS = [("paper", "beta", "isopleth"), ("planned", "beta", "isopleth")]


def _results() -> list[WorldResult]:
    return [
        _result(0, "cuts", {"paper/beta": [0.5, 0.95, 0.97], "planned/beta": [0.92, 0.95, 0.96]}),
        _result(1, "cuts", {"paper/beta": [0.5, 0.6, 0.7], "planned/beta": [0.5, 0.91, 0.93]}),
        _result(4, "cuts", {"paper/beta": [0.95, 0.6, 0.7], "planned/beta": [0.3, 0.5, 0.6]}),
        # paper ran out of targets after poke 1: its last map counts for pokes 2 and 3
        _result(2, "insert", {"paper/beta": [0.95], "planned/beta": [0.4, 0.5, 0.95]}),
        _result(3, "insert", {}, status="failed"),
    ]


def test_summary_counts_never_and_failed_as_max_pokes_plus_one() -> None:
    summary = summarise_worlds(_results(), COMBOS, 3)
    paper, planned = (summary["strategies"][n] for n in ("paper/beta/isopleth",
                                                          "planned/beta/isopleth"))
    # first at 0.9 — paper: 2, never (4), 1, failed (4), 1 → 2; planned: 1, 2, 3, 4, 4 → 3
    assert paper["median_pokes_to_accuracy_0.9"] == 2.0
    assert planned["median_pokes_to_accuracy_0.9"] == 3.0
    # staying at 0.9 — paper's world 4 loses it after poke 1: 2, 4, 1, 4, 4 → 4
    assert paper["median_pokes_to_stay_0.9"] == 4.0 and planned["median_pokes_to_stay_0.9"] == 3.0
    assert paper["worlds"] == 5 and paper["failed"] == 1
    assert paper["share_reaching_0.9"] == pytest.approx(3 / 5)
    assert paper["final_accuracy_median"] == pytest.approx(0.825)  # 0.97, 0.7, 0.95 carried, 0.7
    assert paper["by_family"]["cuts"]["median_pokes_to_accuracy_0.9"] == 2.0
    assert paper["by_family"]["insert"]["median_pokes_to_accuracy_0.9"] == 2.5
    assert set(paper) >= {"median_pokes_to_accuracy_0.9", "final_accuracy_median",
                          "modulus_error_median", "worlds", "by_family"}
    # every world's count on average: paper 2.4, planned 2.8
    assert paper["mean_pokes_to_accuracy_0.9"] == pytest.approx(2.4)
    assert planned["mean_pokes_to_accuracy_0.9"] == pytest.approx(2.8)
    low, high = paper["median_pokes_ci95"]
    assert 1.0 <= low <= 2.0 <= high <= 4.0 and low < high
    assert summarise_worlds(_results(), COMBOS, 3) == summary  # the bootstrap is seeded
    assert summary["best"] == "paper/beta/isopleth"
    assert summary["failed_worlds"] == [{"index": 3, "error": "Boom: no"}]
    # the same counts world by world, for paired comparisons
    by_world = pokes_to_good(_results(), ("paper", "beta", "isopleth"), 3)
    assert by_world == {0: 2, 1: 4, 2: 1, 3: 4, 4: 1}
    table = markdown_summary(summary)
    assert (f"| paper/beta/isopleth (best) | 5 (1 failed) | 2 ({low:g}–{high:g}) | 2.4 | 4 | "
            "60% |") in table
    curves = accuracy_curves(_results(), COMBOS, 3)
    assert curves["all"]["paper/beta/isopleth"].shape == (4, 3)
    assert curves["insert"]["paper/beta/isopleth"].tolist() == [[0.95, 0.95, 0.95]]


def test_best_is_the_fewest_pokes_on_average_not_the_capped_median() -> None:
    """Steady reaches 0.9 at poke 4 in every world; lucky at poke 3 in three of five and never in
    two (counted 7 at 6 pokes): the median (3 against 4) would pick lucky, the mean (4.6 against
    4) picks steady. With equal means the median decides."""
    def series(first: int | None) -> list[float]:
        return [0.95 if first is not None and k + 1 >= first else 0.5 for k in range(6)]

    results = [_result(i, "cuts", {"lucky/beta": series(3 if i < 3 else None),
                                   "steady/beta": series(4)}) for i in range(5)]
    combos = [("lucky", "beta", "isopleth"), ("steady", "beta", "isopleth")]
    summary = summarise_worlds(results, combos, 6)
    lucky, steady = (summary["strategies"][f"{n}/beta/isopleth"] for n in ("lucky", "steady"))
    assert lucky["median_pokes_to_accuracy_0.9"] == 3 and steady["median_pokes_to_accuracy_0.9"] == 4
    assert lucky["mean_pokes_to_accuracy_0.9"] == pytest.approx(4.6)
    assert steady["mean_pokes_to_accuracy_0.9"] == pytest.approx(4.0)
    assert steady["median_pokes_ci95"] == [4.0, 4.0]
    assert summary["best"] == "steady/beta/isopleth"
    # equal means (4 and 4): the smaller median wins
    results = [_result(i, "cuts", {"lucky/beta": series((3, 3, 3, 5, 6)[i]),
                                   "steady/beta": series(4)}) for i in range(5)]
    assert summarise_worlds(results, combos, 6)["best"] == "lucky/beta/isopleth"


def test_the_summary_does_not_depend_on_the_order_the_worlds_finished_in() -> None:
    """Worlds come back in the order they finish (a pool, a cluster, a resumed run): the
    summary, its bootstrap intervals included, is that of the worlds, not of their order."""
    rng = np.random.default_rng(3)

    def reaching(first: int) -> list[float]:  # 0.9 from poke `first` on (11: never in 10)
        return [0.95 if k + 1 >= first else 0.5 for k in range(10)]

    results = [_result(i, ("cuts", "insert")[i % 2],
                       {"paper/beta": reaching(int(rng.integers(1, 12))),
                        "planned/beta": reaching(int(rng.integers(1, 12)))},
                       status="ok" if i != 7 else "failed") for i in range(30)]
    reference = summarise_worlds(results, COMBOS, 10)
    assert reference["failed_worlds"] == [{"index": 7, "error": "Boom: no"}]
    for seed in range(3):
        shuffled = [results[i] for i in np.random.default_rng(seed).permutation(len(results))]
        assert summarise_worlds(shuffled, COMBOS, 10) == reference


def test_the_command_shows_the_mean_beside_the_median_and_marks_the_best() -> None:
    from types import SimpleNamespace

    from rich.console import Console

    from deformap.cli._bench import _show_worlds_summary

    results = [_result(i, "cuts", {"lucky/beta": [0.95 if i < 3 and k >= 2 else 0.5
                                                  for k in range(6)],
                                   "steady/beta": [0.95 if k >= 3 else 0.5 for k in range(6)]})
               for i in range(5)]
    summary = summarise_worlds(results, [("lucky", "beta", "isopleth"),
                                         ("steady", "beta", "isopleth")], 6)
    console = Console(record=True, width=200)
    _show_worlds_summary(console, SimpleNamespace(summary=summary, computed=5, seconds=1.0,
                                                  folder="F"), 5, 6, None)  # fmt: skip
    text = console.export_text()
    assert "best: fewest mean pokes" in text and "mean" in text
    lines = {line.split("│")[1].strip(): [c.strip() for c in line.split("│")[2:]]
             for line in text.splitlines() if "/beta/" in line}
    assert lines["steady/beta/isopleth (best)"][:3] == ["5", "4", "4.0"]
    assert lines["lucky/beta/isopleth"][:3] == ["5", "3", "4.6"]


def test_runs_csv_has_a_row_per_poke_and_the_failed_world_per_combination() -> None:
    rows = list(csv.DictReader(io.StringIO(runs_csv(_results(), COMBOS))))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert len(rows) == 3 + 3 + 3 + 3 + 1 + 3 + 2 + 3 + 3
    failed = [r for r in rows if r["status"] == "failed"]
    assert [r["strategy"] for r in failed] == ["paper", "planned"]
    assert all(r["poke"] == "" and r["error"] == "Boom: no" for r in failed)


def _task(**given) -> WorldTask:
    return WorldTask(**{"seed": 5, "index": 0, "families": ("l-shape",),
                        "physics": ("linear-fem",), "strategies": ("paper",),
                        "fields": ("modulus",), "cuts": ("nearest",), "coarse": True, **given})


def _through_json(result: WorldResult) -> WorldResult:
    """``result`` as a world file holds it and as it crosses processes."""
    return WorldResult.from_dict(json.loads(json.dumps(result.to_dict())))


def test_one_world_is_mapped_to_max_pokes_by_every_combination() -> None:
    task = _task(fields=("beta", "modulus"), cuts=("isopleth", "nearest"), max_pokes=2)
    result = run_world(task)
    assert result.status == "ok" and result.world["family"] == "l-shape"
    assert _through_json(result) == result  # plain data, every bit kept
    rows = result.rows
    assert [(r["field"], r["poke"], r["cut"]) for r in rows] == [
        (f, k, c) for f in ("beta", "modulus") for k in (1, 2) for c in ("isopleth", "nearest")]
    for r in rows:
        assert 0.0 <= r["accuracy"] <= 1.0 and 0.0 <= r["mean_iou"] <= 1.0
        assert r["true"] == 2 and r["found"] >= 1
    assert rows[0]["purpose"] == "first"
    assert rows[-1]["modulus_error"] is not None and rows[-1]["modulus_error"] >= 0
    assert np.isfinite([r["poke_s"] for r in rows]).all()
    for field in ("beta", "modulus"):
        stored = result.pokes[f"plain/auto/paper/{field}"]
        assert sorted(stored) == ["index", "noise", "thickness", "value", "x", "y"]
        assert stored["thickness"] is not None and len(stored["thickness"]) == len(stored["x"])
        assert 1 <= len(stored["value"]) <= 2 and stored["index"] == sorted(stored["index"])
    # the stored pokes score the run's cuts again to the bit, through JSON, in another order
    again = rescore_world(replace(task, cuts=("nearest", "isopleth")), _through_json(result))
    key = lambda r: (r["field"], r["poke"], r["cut"])  # noqa: E731
    assert sorted(again.rows, key=key) == sorted(rows, key=key)


def test_a_stored_world_of_another_format_or_without_pokes_is_refused_in_one_line() -> None:
    stored = {"world": {"index": 0}, "rows": [], "pokes": {}, "fallback_pokes": {},
              "pokes_format": 4, "seconds": 1.0, "status": "ok", "error": None}
    assert WorldResult.from_dict(stored).status == "ok"
    for data, message in (({**stored, "pokes_format": 3}, "`pokes_format` is 3; this version "
                                                          "of deformap reads 4 only"),
                          ({k: v for k, v in stored.items() if k != "pokes_format"},
                           "`pokes_format` is None"),
                          ({**stored, "pokes": None}, "`pokes` must be an object"),
                          ({**stored, "pokes": {"paper/beta": {"x": [0.1]}}},
                           "the pokes of 'paper/beta' must have lists"),
                          ({**stored, "world": {"index": -1}}, "`world.index` must be")):
        with pytest.raises(InvalidArgumentError, match=message) as caught:
            WorldResult.from_dict(data)
        assert len(str(caught.value).splitlines()) == 1
    failed = WorldResult(world={"index": 0, "family": "cuts"}, status="failed", error="Boom")
    assert WorldResult.from_dict(failed.to_dict()) == failed
    with pytest.raises(InvalidArgumentError, match="status 'failed'"):
        rescore_world(_task(), failed)


def test_the_command_refuses_bad_names_in_one_line_before_any_folder(tmp_path) -> None:
    from typer.testing import CliRunner

    from deformap.cli import app

    out = tmp_path / "w"
    for args, message in ((["--strategies", "paper,guess"], "`strategies` must be distinct"),
                          (["--fields", "hardness"], "`fields` must be distinct"),
                          (["--cut", "voronoi"], "got ['voronoi'] (unknown)"),
                          (["--cuts", "nearest,nearest"], "got ['nearest'] more than once"),
                          (["--worlds", "0"], "`worlds` must be an integer >= 1"),
                          (["--set", "merge_seams=maybe"], "`exploration.merge_seams` must be"),
                          (["--set", "merge_seam=false"], "`exploration.merge_seam` is no "
                                                          "setting"),
                          (["--set", "beta_field.signal_std=-1"],
                           "`exploration.beta_field.signal_std` must be"),
                          (["--set", "merge_seams"], "--set must be key=value"),
                          (["--set", "strategy=paper"], "(option: --strategies)")):
        result = CliRunner().invoke(app, ["bench", "worlds", "--out", str(out), *args])
        assert result.exit_code == 2, result.output
        assert message in result.output and len(result.output.strip().splitlines()) == 1
        assert not out.exists()


def test_where_the_pokes_go_does_not_depend_on_the_cut() -> None:
    """What lets `run_world` score every cut on one mapping: mapped under each cut (the
    mapper's own `region_labels`), the level-set strategy and the boundary pokes go to the same
    places, though the cuts label the cells differently."""
    from dataclasses import replace
    from functools import partial

    from deformap.explore import ExplorationConfig, Mapper, Target, poke_step
    from deformap.world import SimulatedWorld, WorldConfig

    draw = draw_world(2, 1, ("insert",), ("linear-fem",))
    world = SimulatedWorld(draw.scenario, config=WorldConfig.coarse(),
                           rng=np.random.default_rng(0))
    base = ExplorationConfig(strategy="level-set", max_pokes=5, boundary_pokes=5,
                             force_n=draw.force_n)
    surface = Mapper(world.workspace, base).initialise(world.observe(),
                                                       np.random.default_rng(1))
    places, labels = {}, {}
    for cut in ("isopleth", "nearest", "indicator-kriging"):
        mapper = Mapper(world.workspace, replace(base, region_labels=cut))
        mapper.surface = surface
        streams = np.random.default_rng(2).spawn(6)
        target: Target | None = Target(np.array(world.workspace.center, float), "first")
        chosen = []
        for index in range(5):
            if index:
                target = mapper.next_target(streams[index])
            assert target is not None
            chosen.append(tuple(np.round(target.xy, 9)))
            poke_step(mapper, index, partial(world.press, target.xy, base.force_n),
                      finish=world.release, target=target, target_s=0.0)
        places[cut], labels[cut] = chosen, mapper.regions().labels
    assert places["isopleth"] == places["nearest"] == places["indicator-kriging"]
    assert not np.array_equal(labels["isopleth"], labels["nearest"])  # the cuts do differ


def test_the_cuts_are_scored_on_the_same_pokes_as_a_run_per_cut() -> None:
    """Each cut's rows from one run scoring every cut equal those of a run scoring that cut
    alone (scoring one cut leaves the others' scores alone)."""
    cuts = ("isopleth", "nearest", "indicator-kriging")
    task = _task(seed=2, index=1, families=("insert",), strategies=("level-set",),
                 fields=("beta",), max_pokes=4, cuts=cuts)
    result = run_world(task)
    together = [row_values(r) for r in result.rows]
    # the β-field's stored pokes, rescored with the map's nugget estimated again after each poke
    rescored = rescore_world(task, _through_json(result))
    assert [row_values(r) for r in rescored.rows] == together
    apart = [row_values(r) for cut in cuts
             for r in run_world(replace(task, cuts=(cut,))).rows]
    key = lambda r: (r["cut"], r["poke"])  # noqa: E731
    assert sorted(together, key=key) == sorted(apart, key=key)
    assert {r["cut"] for r in together} == set(cuts)


def test_rescoring_merges_a_junction_class_within_the_stored_thickness_only() -> None:
    """Stored pokes: a soft left, a stiff right and a column between them on the joint; the
    junction rule merges that column when the stored layer is thick enough to reach it, and
    a poke without a thickness turns the rule off from that poke on."""
    task = _task(max_pokes=25)
    xs, ys = np.linspace(0.1, 0.5, 5), np.linspace(0.05, 0.35, 5)
    xy = np.array([(x, y) for y in ys for x in xs])
    value = np.log(np.where(xy[:, 0] < 0.25, 10e3, np.where(xy[:, 0] > 0.35, 40e3, 20e3)))
    rows = [{"world": 0, "family": "l-shape", "appearance": "plain", "prior": "auto",
             "strategy": "paper", "field": "modulus", "cut": "nearest", "poke": k}
            for k in range(1, 26)]

    def found(thickness, merge: bool) -> list[int]:
        pokes = {"x": xy[:, 0].tolist(), "y": xy[:, 1].tolist(), "value": value.tolist(),
                 "noise": [0.1] * 25, "index": list(range(25)), "thickness": thickness}
        result = WorldResult(world={"index": 0}, rows=tuple(rows),
                             pokes={"plain/auto/paper/modulus": pokes})
        again = rescore_world(_rules(task, merge_seams=merge), result).rows
        return [r["found"] for r in again]

    assert found([0.06] * 25, merge=False)[-1] == 3  # the joint column is a class
    assert found([0.06] * 25, merge=True)[-1] == 2  # within 2 × 6 cm: merged
    assert found([0.01] * 25, merge=True)[-1] == 3  # 1 cm foam: the joint cannot reach
    late = found([0.06] * 24 + [None], merge=True)  # the last poke has no thickness
    assert late[-2] == 2 and late[-1] == 3
    # two foams 20 % apart in E, left and right: one class by value, two by place
    close = np.log(np.where(xy[:, 0] < 0.3, 10e3, 12.2e3))
    pokes = {"x": xy[:, 0].tolist(), "y": xy[:, 1].tolist(), "value": close.tolist(),
             "noise": [0.1] * 25, "index": list(range(25)), "thickness": [0.03] * 25}
    result = WorldResult(world={"index": 0}, rows=tuple(rows),
                         pokes={"plain/auto/paper/modulus": pokes})
    by_value, by_place = (rescore_world(_rules(task, split_by_place=split), result).rows
                          for split in (False, True))
    assert by_value[-1]["found"] == 1 and by_place[-1]["found"] == 2
    assert by_place[-1]["accuracy"] > by_value[-1]["accuracy"]
    # a run that fell back to β from its third poke on needs its β pokes to be rescored
    fell = tuple({**r, "map_field": "modulus" if r["poke"] < 3 else "beta"} for r in rows)
    with pytest.raises(InvalidArgumentError, match="stores no beta pokes of 'plain/auto/paper/"
                                                   "modulus', whose map field was 'beta' at "
                                                   "poke 3"):
        rescore_world(task, replace(result, rows=fell))


def _rules(task: WorldTask, **rules) -> WorldTask:
    return replace(task, exploration=replace(task.exploration, **rules))


def test_a_run_that_fell_back_to_beta_is_rescored_on_its_stored_beta_pokes(monkeypatch) -> None:
    from deformap.world import SimulatedWorld

    recorded = SimulatedWorld.force_travel
    calls = []

    def first_unrecorded(self, *args, **kwargs):  # a robot whose first press logs no record
        calls.append(1)
        return None if len(calls) == 1 else recorded(self, *args, **kwargs)

    monkeypatch.setattr(SimulatedWorld, "force_travel", first_unrecorded)
    task = _task(max_pokes=3)
    result = _through_json(run_world(task))
    # the first poke had no modulus: the map field was β there, the modulus field after it
    assert [r["map_field"] for r in result.rows] == ["beta", "modulus", "modulus"]
    beta = result.fallback_pokes["plain/auto/paper/modulus"]
    modulus = result.pokes["plain/auto/paper/modulus"]
    assert beta["index"] == [0, 1, 2] and modulus["index"] == [1, 2]
    again = rescore_world(task, result)
    assert again.rows == result.rows  # to the bit, the β row included
    # another cut is scored too: on the β pokes at the first poke
    other = rescore_world(replace(task, cuts=("isopleth",)), result).rows
    assert [r["cut"] for r in other] == ["isopleth"] * 3
    assert [r["map_field"] for r in other] == ["beta", "modulus", "modulus"]


def test_a_task_maps_with_its_exploration_settings_and_its_own_axes() -> None:
    task = _task(max_pokes=3, exploration=ExplorationConfig(merge_seams=False))
    draw = task.draw()
    explore = task.exploration_for(draw)
    assert explore == replace(ExplorationConfig(merge_seams=False), max_pokes=3,
                              boundary_pokes=3, force_n=draw.force_n)
    assert draw.summary() == draw_world(5, 0, ("l-shape",), ("linear-fem",)).summary()
