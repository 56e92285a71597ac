"""The appearance axis of ``deformap bench worlds``: painted worlds mapped blind and with the
prior on the same world, the columns and summary keys it adds, the figure, and the refusals."""

from __future__ import annotations

import csv
import io
import json
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from deformap.errors import InvalidArgumentError
from deformap.eval import (
    CSV_COLUMNS,
    TIME_COLUMNS,
    WorldResult,
    WorldTask,
    accuracy_curves,
    draw_world,
    markdown_summary,
    pokes_to_good,
    row_values,
    run_world,
    runs_csv,
    summarise_worlds,
)
from deformap.world import APPEARANCE_FAMILIES

ARMS = (("plain", "auto"), ("informative", "off"), ("informative", "auto"))


def _task(**given) -> WorldTask:
    return WorldTask(**{"seed": 5, "index": 0, "families": ("l-shape",),
                        "physics": ("linear-fem",), "strategies": ("paper",),
                        "fields": ("beta",), "cuts": ("nearest",), "coarse": True,
                        "max_pokes": 2, **given})


def test_every_family_paints_the_same_layout_and_only_a_painted_one_is_paired() -> None:
    plain = draw_world(3, 2)
    for family in APPEARANCE_FAMILIES:
        painted = draw_world(3, 2, appearance=family)
        assert painted.appearance == family and painted.summary() == plain.summary()
        assert [(b.polygon.tolist(), b.hardness, b.rigid) for b in painted.scenario.blocks] == \
            [(b.polygon.tolist(), b.hardness, b.rigid) for b in plain.scenario.blocks]
    painted = draw_world(3, 2, appearance="informative").scenario.blocks
    assert [b.appearance for b in painted] != [b.appearance for b in plain.scenario.blocks]
    assert _task(appearances=("plain", "informative")).arms() == ARMS
    assert _task().arms() == (("plain", "auto"),)
    for bad in (("glossy",), (), ("split", "split")):
        with pytest.raises(InvalidArgumentError, match="`appearances` must be distinct names"):
            _task(appearances=bad)


def test_a_painted_world_is_mapped_blind_and_with_the_prior_on_the_same_presses() -> None:
    task = _task(appearances=("plain", "informative"))
    result = run_world(task)
    assert [(r["appearance"], r["prior"]) for r in result.rows] == [
        arm for arm in ARMS for _ in range(2)]  # two pokes each
    assert sorted(result.pokes) == sorted(WorldResult.run_key(*arm, "paper", "beta")
                                          for arm in ARMS)
    # both arms press the same world: the first poke is one press, read the same in each
    blind, prior = (result.pokes[f"informative/{p}/paper/beta"] for p in ("off", "auto"))
    for column in ("x", "y", "value", "noise", "thickness"):
        assert blind[column][0] == prior[column][0]
    rows = {arm: [r for r in result.rows if (r["appearance"], r["prior"]) == arm]
            for arm in ARMS}
    assert [r["true"] for r in rows[ARMS[1]]] == [r["true"] for r in rows[ARMS[2]]]
    assert rows[ARMS[1]][0]["purpose"] == rows[ARMS[2]][0]["purpose"] == "first"
    # a painted family leaves the plain runs as a benchmark of plain worlds alone makes them
    alone = run_world(replace(task, appearances=("plain",)))
    assert [row_values(r) for r in alone.rows] == [row_values(r) for r in rows[ARMS[0]]]


def _result(index: int, counts: dict[tuple[str, str], int | None], max_pokes: int = 4,
            found: int = 2, status: str = "ok") -> WorldResult:
    """A world whose accuracy reaches 0.95 at each arm's count (None: never)."""
    world = {"index": index, "family": "cuts", "physics": "linear-fem",
             "camera": "primesense", "thickness_m": 0.05, "force_n": 0.6}
    if status != "ok":
        return WorldResult(world=world, status="failed", error="Boom: no")
    rows = [{"world": index, "family": "cuts", "appearance": a, "prior": p,
             "strategy": "paper", "field": "beta", "cut": "nearest", "poke": k,
             "purpose": "variance", "map_field": "beta", "threshold": False,
             "accuracy": 0.95 if first is not None and k >= first else 0.5, "mean_iou": 0.5,
             "found": found if p == "auto" else 1, "true": 2, "kendall_tau": 1.0,
             "modulus_error": None, "beta_spread": 0.1, "poke_s": 1.0, "elapsed_s": 1.0}
            for (a, p), first in counts.items() for k in range(1, max_pokes + 1)]
    return WorldResult(world=world, rows=tuple(rows), seconds=1.0)


COMBO = ("paper", "beta", "nearest")


def _paired_results() -> list[WorldResult]:
    # informative: blind at 4, 3, never (5) and prior at 2, 2, 3; plain at 1, 2, 3
    firsts = ((4, 2, 1), (3, 2, 2), (None, 3, 3))
    return [_result(i, dict(zip(ARMS[::-1], (p, b, plain), strict=True)))
            for i, (b, p, plain) in enumerate(firsts)] + [_result(3, {}, status="failed")]


def test_the_summary_sets_the_blind_map_beside_the_prior_per_family_paired() -> None:
    summary = summarise_worlds(_paired_results(), [COMBO], 4, arms=ARMS)
    entry = summary["appearance"]["informative"]["paper/beta/nearest"]
    blind, prior = entry["blind"], entry["prior"]
    # counts with the failed world at 5 — blind 4, 3, 5, 5; prior 2, 2, 3, 5
    assert blind["mean_pokes_to_accuracy_0.9"] == pytest.approx(17 / 4)
    assert prior["mean_pokes_to_accuracy_0.9"] == pytest.approx(3.0)
    assert blind["median_pokes_to_accuracy_0.9"] == 4.5 and prior["worlds"] == 4
    assert prior["median_pokes_to_accuracy_0.9"] == 2.5
    # of the worlds that ran: blind 0.95, 0.95, 0.5
    assert blind["final_accuracy_median"] == 0.95 and prior["final_accuracy_median"] == 0.95
    assert blind["share_right_count"] == 0.0 and prior["share_right_count"] == 1.0
    # paired: prior − blind world by world: −2, −1, −2, 0
    d = np.array([-2.0, -1.0, -2.0, 0.0])
    half = stats.t.ppf(0.975, 3) * d.std(ddof=1) / 2.0
    assert entry["paired_worlds"] == 4
    assert entry["mean_pokes_difference"] == pytest.approx(-1.25)
    assert entry["mean_pokes_difference_ci95"] == pytest.approx([-1.25 - half, -1.25 + half])
    # plain is mapped under the prior only: nothing to pair
    plain = summary["appearance"]["plain"]["paper/beta/nearest"]
    assert plain["blind"] is None and plain["mean_pokes_difference"] is None
    assert plain["prior"]["mean_pokes_to_accuracy_0.9"] == pytest.approx(11 / 4)
    # `strategies` counts each world once per family, under the prior: 2 2 3 5 and 1 2 3 5
    overall = summary["strategies"]["paper/beta/nearest"]
    assert overall["worlds"] == 8
    assert overall["mean_pokes_to_accuracy_0.9"] == pytest.approx(23 / 8)
    assert pokes_to_good(_paired_results(), COMBO, 4, ("informative", "off")) == {
        0: 4, 1: 3, 2: 5, 3: 5}
    table = markdown_summary(summary)
    assert "| informative | paper/beta/nearest | 4 | 4.5 / 2.5 | 4.2 / 3.0 | -1.25 (" in table
    assert "| plain | paper/beta/nearest | 4 | – / 2.5 | – / 2.8 | – |" in table  # prior only
    json.dumps(summary)  # plain data


def test_runs_csv_names_each_rows_appearance_and_prior() -> None:
    text = runs_csv(_paired_results(), [COMBO], ARMS)
    rows = list(csv.DictReader(io.StringIO(text)))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert {"appearance", "prior"} <= set(CSV_COLUMNS)
    assert len(rows) == 3 * 3 * 4 + 3  # the failed world: one row per arm
    failed = [(r["appearance"], r["prior"]) for r in rows if r["status"] == "failed"]
    assert failed == list(ARMS)
    assert {(r["appearance"], r["prior"]) for r in rows} == set(ARMS)


def test_the_curves_are_drawn_per_appearance_family_blind_beside_the_prior() -> None:
    from deformap.viz import plot_world_curves

    results = _paired_results()
    prior = accuracy_curves(results, [COMBO], 4, arms=ARMS, by="appearance")
    blind = accuracy_curves(results, [COMBO], 4, arms=ARMS, by="appearance", prior="off")
    assert list(prior) == ["plain", "informative"] and list(blind) == ["informative"]
    assert blind["informative"]["paper/beta/nearest"][2].tolist() == [0.5] * 4
    assert accuracy_curves(results, [COMBO], 4, arms=ARMS)["all"][
        "paper/beta/nearest"].shape == (6, 4)  # three worlds ran, under two families
    with pytest.raises(InvalidArgumentError, match="`by` must be"):
        accuracy_curves(results, [COMBO], 4, by="camera")
    fig = plot_world_curves(prior, blind=blind)
    panels = [ax for ax in fig.axes if ax.axison]
    assert [ax.get_title().split(" (")[0] for ax in panels] == ["informative", "plain"]
    lines = {ln.get_label(): ln for ln in panels[0].get_lines()}
    assert lines["paper/beta/nearest (the paper's strategy), blind"].get_linestyle() == ":"
    assert "paper/beta/nearest (the paper's strategy), prior" in lines
    assert "prior solid, blind dotted" in fig.get_suptitle()


def test_the_command_shows_the_paired_table_and_refuses_a_bad_family(tmp_path) -> None:
    from types import SimpleNamespace

    from rich.console import Console
    from typer.testing import CliRunner

    from deformap.cli import app
    from deformap.cli._bench import _show_worlds_summary

    summary = summarise_worlds(_paired_results(), [COMBO], 4, arms=ARMS)
    console = Console(record=True, width=250)
    _show_worlds_summary(console, SimpleNamespace(summary=summary, computed=4, seconds=1.0,
                                                  folder="F"), 4, 4, None)  # fmt: skip
    text = console.export_text()
    lines = [[c.strip() for c in ln.split("│")[1:-1]] for ln in text.splitlines()
             if "paper/beta/nearest" in ln and ("informative" in ln or "plain" in ln)]
    assert [cells[0] for cells in lines] == ["plain", "informative"]
    assert lines[0][3:6] == ["– / 2.5", "– / 2.8", "–"]
    cells = lines[1]
    assert cells[:5] == ["informative", "paper/beta/nearest", "4", "4.5 / 2.5", "4.2 / 3.0"]
    assert cells[5].startswith("-1.25 (") and cells[6:] == ["0.950 / 0.950", "0% / 100%"]
    out = tmp_path / "w"
    for args, message in ((["--appearance", "plain,glossy"], "`appearances` must be distinct "
                                                             "names from ['plain'"),
                          (["--set", "appearance='off'"], "(option: --appearance)")):
        result = CliRunner().invoke(app, ["bench", "worlds", "--out", str(out), *args])
        assert result.exit_code == 2, result.output
        assert message in result.output and len(result.output.strip().splitlines()) == 1
        assert not out.exists()


def test_a_painted_benchmark_is_written_and_rescored_to_the_bit(tmp_path) -> None:
    from deformap.run import WorldsBenchConfig, bench_worlds, rescore_worlds

    config = WorldsBenchConfig(worlds=2, seed=3, families=("cuts",), physics=("linear-fem",),
                               appearances=("misleading",), coarse=True, strategies=("paper",),
                               fields=("beta",), cuts=("isopleth",), max_pokes=2)
    output = bench_worlds(config, tmp_path / "src")
    rows = list(csv.DictReader(io.StringIO((tmp_path / "src" / "runs.csv").read_text())))
    assert [(r["world"], r["appearance"], r["prior"], r["poke"]) for r in rows] == [
        (str(w), "misleading", p, str(k)) for w in (0, 1) for p in ("off", "auto")
        for k in (1, 2)]
    entry = output.summary["appearance"]["misleading"]["paper/beta/isopleth"]
    assert entry["paired_worlds"] == 2 and entry["blind"]["worlds"] == 2
    assert output.summary["settings"]["appearances"] == ["misleading"]
    assert "| misleading | paper/beta/isopleth | 2 |" in (
        tmp_path / "src" / "summary.md").read_text()
    assert (tmp_path / "src" / "curves.png").stat().st_size > 0
    again = rescore_worlds(tmp_path / "src", tmp_path / "again")
    assert again.computed == 2
    rescored = list(csv.DictReader(io.StringIO((tmp_path / "again" / "runs.csv").read_text())))
    strip = lambda rs: [{k: v for k, v in r.items() if k not in TIME_COLUMNS}  # noqa: E731
                        for r in rs]
    # rescore refits from the stored pokes alone (no first observation, so no appearance prior): the
    # blind arm is reproduced to the bit, the prior arm's rows are rescored under the same keys
    blind = lambda rs: [r for r in strip(rs) if r["prior"] == "off"]  # noqa: E731
    assert blind(rescored) == blind(rows) and len(blind(rows)) == 4
    assert [(r["world"], r["prior"], r["poke"]) for r in rescored] == [
        (r["world"], r["prior"], r["poke"]) for r in rows]


def test_the_prior_arm_is_scored_on_the_map_the_mapper_draws(monkeypatch) -> None:
    """Under the prior, ``nearest`` labels each cell by its most correlated poke
    (``Mapper.regions``); the bench must score that map, not the blind labelling."""
    import deformap.eval._worlds as worlds

    calls: list[bool] = []
    real = worlds.map_regions

    def spy(*args, correlation=None, **kwargs):
        calls.append(correlation is not None)
        return real(*args, correlation=correlation, **kwargs)

    monkeypatch.setattr(worlds, "map_regions", spy)
    run_world(_task(appearances=("informative",), max_pokes=3))
    # blind first (three pokes, no correlation), then the prior's (with the looks' correlation)
    assert calls[:3] == [False] * 3 and len(calls) == 6 and all(calls[4:])
