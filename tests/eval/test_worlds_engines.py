"""``deformap bench worlds`` on the local process pool and on a Dask cluster: the same numbers,
resumed without redoing a world, a failing world reported, a stored benchmark rescored."""

from __future__ import annotations

import csv
import io
import json
import os
from dataclasses import replace

import pytest

from deformap.errors import ConfigError, InvalidArgumentError
from deformap.eval import POKES_FORMAT, TIME_COLUMNS
from deformap.explore import ExplorationConfig
from deformap.run import WorldsBenchConfig, bench_worlds
from deformap.run._worlds_engines import world_results


def _values(folder) -> list[dict[str, str]]:
    rows = list(csv.DictReader(io.StringIO((folder / "runs.csv").read_text())))
    return [{k: v for k, v in r.items() if k not in TIME_COLUMNS} for r in rows]


def _config(**kw) -> WorldsBenchConfig:
    # coarse worlds on the linear FEM: a poke costs an eighth of the stiffening foam's
    settings = {"seed": 3, "families": ("cuts", "checker"), "physics": ("linear-fem",),
                "coarse": True,
                "strategies": ("paper",), "fields": ("beta",), "cuts": ("isopleth",),
                "max_pokes": 2, **kw}
    return WorldsBenchConfig(**settings)


def test_pool_and_dask_agree_byte_for_byte_apart_from_times_and_resume(tmp_path) -> None:
    distributed = pytest.importorskip("distributed")
    pool = bench_worlds(_config(worlds=2), tmp_path / "pool")
    assert pool.computed == 2
    with distributed.LocalCluster(processes=True, n_workers=1, threads_per_worker=1,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        dask = bench_worlds(_config(worlds=2, scheduler=cluster.scheduler_address),
                            tmp_path / "dask")
    assert dask.computed == 2
    assert _values(tmp_path / "pool") == _values(tmp_path / "dask")
    assert len(_values(tmp_path / "pool")) == 2 * 2  # worlds × pokes
    for name in ("worlds/world-00000.json", "worlds/world-00001.json"):
        a, b = (json.loads((tmp_path / f / name).read_text()) for f in ("pool", "dask"))
        assert a["world"] == b["world"]
        assert [{k: v for k, v in r.items() if k not in TIME_COLUMNS} for r in a["rows"]] == \
            [{k: v for k, v in r.items() if k not in TIME_COLUMNS} for r in b["rows"]]
    summary = json.loads((tmp_path / "pool" / "summary.json").read_text())
    assert summary == json.loads((tmp_path / "dask" / "summary.json").read_text())
    assert summary["strategies"]["paper/beta/isopleth"]["worlds"] == 2
    assert (tmp_path / "pool" / "curves.png").stat().st_size > 0
    assert "| paper/beta/isopleth" in (tmp_path / "pool" / "summary.md").read_text()
    again = bench_worlds(_config(worlds=2), tmp_path / "pool")  # resumed: nothing redone
    assert again.computed == 0 and again.summary == pool.summary
    with pytest.raises(ConfigError, match=r"other settings \(max_pokes: 2 there, 3 here\)"):
        bench_worlds(_config(worlds=2, max_pokes=3), tmp_path / "pool")
    # the exploration settings are the benchmark's: another is refused, naming it
    with pytest.raises(ConfigError, match=r"other settings \(exploration: \{\} there, "
                                          r"\{'split_by_place': False\} here\)"):
        bench_worlds(_config(worlds=2, exploration=ExplorationConfig(split_by_place=False)),
                     tmp_path / "pool")
    # a folder of the format before: refused in one line naming both versions
    settings_file = tmp_path / "pool" / "bench.json"
    header = json.loads(settings_file.read_text())
    assert header["format"] == 3 and header["settings"]["exploration"] == {}
    assert header["settings"]["appearances"] == ["plain"]
    del header["format"]
    settings_file.write_text(json.dumps(header))
    with pytest.raises(ConfigError, match="is a worlds benchmark of format 1; this version of "
                                          "deformap reads format 3 only"):
        bench_worlds(_config(worlds=2), tmp_path / "pool")


def test_a_failing_world_is_tried_twice_then_reported_not_dropped(caplog) -> None:
    bad = replace(_config(worlds=1).task(0), families=("spiral",))  # fails as it is drawn
    with caplog.at_level("WARNING"):
        results = list(world_results([bad], workers=1))
    assert [r.status for r in results] == ["failed"]
    assert "spiral" in results[0].error and results[0].rows == ()
    assert results[0].world == {"index": 0, "family": "spiral"}
    assert "trying once more" in caplog.text


def test_settings_are_checked_against_the_config_literals() -> None:
    with pytest.raises(InvalidArgumentError, match="`strategies` must be distinct names"):
        WorldsBenchConfig(strategies=("paper", "guess"))
    with pytest.raises(InvalidArgumentError, match="`cuts` must be distinct names"):
        WorldsBenchConfig(cuts=("voronoi",))
    with pytest.raises(InvalidArgumentError, match="`families` must be"):
        WorldsBenchConfig(families=())
    with pytest.raises(InvalidArgumentError, match=r"`appearances` must be distinct names .* "
                                                   r"got \['glossy'\] \(unknown\)"):
        WorldsBenchConfig(appearances=("plain", "glossy"))
    arms = WorldsBenchConfig(appearances=("split", "plain")).arms()
    assert arms == (("split", "off"), ("split", "auto"), ("plain", "auto"))
    # the exploration settings the benchmark's axes set are its own
    for given, option in (({"strategy": "paper"}, "--strategies"),
                          ({"max_pokes": 3}, "--max-pokes"),
                          ({"region_labels": "isopleth"}, "--cuts"),
                          ({"force_n": 0.4}, "none: each world"),
                          ({"appearance": "off"}, "--appearance")):
        with pytest.raises(InvalidArgumentError, match=f"`exploration.{next(iter(given))}` is "
                                                       f"the benchmark's to set .option: {option}"):
            WorldsBenchConfig(exploration=ExplorationConfig(**given))


def test_rescore_scores_other_cuts_on_the_stored_pokes_and_names_what_it_cannot(tmp_path) -> None:
    from typer.testing import CliRunner

    from deformap.cli import app

    runner = CliRunner()
    bench_worlds(_config(worlds=2), tmp_path / "src")
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "again"), "--cuts", "isopleth,nearest",
                                 "--set", "merge_seams=false"])
    assert result.exit_code == 0, result.output
    again = _values(tmp_path / "again")
    assert [r for r in again if r["cut"] == "isopleth"] == _values(tmp_path / "src")
    assert {r["cut"] for r in again} == {"isopleth", "nearest"} and len(again) == 2 * 2 * 2
    settings = json.loads((tmp_path / "again" / "bench.json").read_text())
    assert settings["rescored_from"] == str(tmp_path / "src")
    assert settings["settings"]["cuts"] == ["isopleth", "nearest"]
    assert "paper/beta/nearest" in json.loads((tmp_path / "again" / "summary.json").read_text())[
        "strategies"]
    assert settings["settings"]["exploration"] == {"merge_seams": False}
    # the region rules after the pokes are rescored on top of the source's; any other setting
    # would move the pokes, and is refused before any folder
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "again"), "--out",
                                 str(tmp_path / "split"), "--set", "split_by_place=false"])
    assert result.exit_code == 0, result.output
    written = json.loads((tmp_path / "split" / "bench.json").read_text())["settings"]
    assert written["exploration"] == {"merge_seams": False, "split_by_place": False}
    for args, why in ((["--set", "threshold=0.1"], "--set threshold: a rescore scores the stored "
                                                   "pokes again, so it may change only "
                                                   "merge_seams, split_by_place"),
                      (["--set", "merge_seams=2"], "`exploration.merge_seams` must be"),
                      (["--cuts", "voronoi"], "`cuts` must be distinct names")):
        result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                     str(tmp_path / "moved"), *args])
        assert result.exit_code == 2 and why in result.output, result.output
        assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "moved").exists()
    # the folder must be new; a world from before the pokes were stored is named
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "again")])
    assert result.exit_code == 2 and "--out" in result.output
    world = tmp_path / "src" / "worlds" / "world-00001.json"
    stored = json.loads(world.read_text())
    original = json.loads(world.read_text())
    del stored["pokes"]
    world.write_text(json.dumps(stored))
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "third")])
    assert result.exit_code == 2
    assert "world-00001.json is not a stored world: `pokes` must be an object" in result.output
    assert "Traceback" not in result.output and not (tmp_path / "third").exists()
    # damaged stored worlds: one line naming the file and what is wrong, before any folder
    assert stored["pokes_format"] == POKES_FORMAT == 4
    key = "plain/auto/paper/beta"
    stored["pokes"] = {key: {"x": [0.1], "y": [0.1, 0.2], "value": [1.0], "noise": [0.1],
                             "index": [0], "thickness": [0.05]}}
    unthick = {key: {k: v for k, v in stored["pokes"][key].items() if k != "thickness"}}
    for damaged, why in (([1, 2], "expected an object"),
                         ({**stored, "world": {"index": "a"}}, "`world.index` must be"),
                         (stored, "columns of different lengths"),
                         ({**stored, "pokes": {}}, f"no stored pokes of '{key}'"),
                         ({**stored, "pokes_format": 5},
                          "`pokes_format` is 5; this version of deformap reads 4 only"),
                         ({**stored, "pokes_format": 3},
                          "`pokes_format` is 3; this version of deformap reads 4 only"),
                         ({**original, "fallback_pokes": []},
                          "`fallback_pokes` must be an object; got list"),
                         ({**original, "fallback_pokes": {key: {"x": [0.1]}}},
                          f"the fallback_pokes of '{key}' must have lists"),
                         ({**original, "rows": [{**r, "map_field": "hardness"}
                                                for r in original["rows"]]},
                          "has `map_field` 'hardness', expected one of ['beta', 'modulus']"),
                         ({**original, "rows": [{**r, "map_field": "modulus"}
                                                for r in original["rows"]]},
                          f"no stored fallback pokes of '{key}', whose map field was "
                          "'modulus' at poke 1"),
                         ({**original, "rows": [{**r, "prior": "off"}
                                                for r in original["rows"]]},
                          "(plain/off) at poke 1 is not of this benchmark"),
                         ({**stored, "pokes_format": True}, "`pokes_format` is True"),
                         ({**stored, "pokes_format": 4.0}, "`pokes_format` is 4.0"),
                         ({**stored, "pokes": unthick},
                          f"the pokes of '{key}' must have lists")):
        world.write_text(json.dumps(damaged))
        result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                     str(tmp_path / "third")])
        assert result.exit_code == 2 and why in result.output, result.output
        assert "Traceback" not in result.output and not (tmp_path / "third").exists()
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path), "--out",
                                 str(tmp_path / "fourth")])
    assert result.exit_code == 2 and "bench.json cannot be read" in result.output
    # a benchmark of the format before is refused in one line naming both versions
    world.write_text(json.dumps(original))
    header = json.loads((tmp_path / "src" / "bench.json").read_text())
    (tmp_path / "src" / "bench.json").write_text(json.dumps({**header, "format": 1}))
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "fifth")])
    assert result.exit_code == 2 and len(result.output.strip().splitlines()) == 1
    assert "is a worlds benchmark of format 1; this version of deformap reads format 3 only" \
        in result.output


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, dead but not yet reaped by its new parent, does not)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_pool_workers_end_when_the_run_is_killed(tmp_path) -> None:
    """A run killed without time to stop its pool (SIGKILL; SIGTERM's default) leaves no worker
    computing a world for nobody: the worker ends as soon as its parent is gone."""
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    import deformap

    pid_file = tmp_path / "worker.pid"
    script = (
        "import os, signal, sys, time\n"
        "from deformap.run._worlds_engines import worker_pool\n"
        "pool = worker_pool(1)\n"
        f"open({str(pid_file)!r}, 'w').write(str(pool.submit(os.getpid).result()))\n"
        "pool.submit(time.sleep, 600)\n"
        "time.sleep(0.5)\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n")
    src = str(Path(deformap.__file__).resolve().parents[1])  # the tree under test
    env = {**os.environ, "OMP_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join(p for p in (src, os.environ.get("PYTHONPATH")) if p)}
    run = subprocess.Popen([sys.executable, "-c", script], env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    assert run.wait(timeout=120) == -signal.SIGKILL
    worker = int(pid_file.read_text())
    try:
        deadline = time.monotonic() + 10.0
        while _alive(worker) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _alive(worker)
    finally:
        if _alive(worker):  # the check failed: leave no orphan behind
            os.kill(worker, signal.SIGKILL)
