"""``deformap bench worlds`` on the local process pool and on a Dask cluster: the same numbers,
resumed without redoing a world, a failing world reported (issue 16, items 2 and 3)."""

from __future__ import annotations

import csv
import io
import json
import os
from dataclasses import replace

import pytest

from deformap.errors import ConfigError, InvalidArgumentError
from deformap.eval import POKES_FORMAT, TIME_COLUMNS
from deformap.run import WorldsBenchConfig, bench_worlds
from deformap.run._worlds import _local_results


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
    # a folder from before the split by place ran without it: resumed as such, refused with it
    settings_file = tmp_path / "pool" / "bench.json"
    header = json.loads(settings_file.read_text())
    del header["settings"]["split_by_place"]
    settings_file.write_text(json.dumps(header))
    assert bench_worlds(_config(worlds=2, split_by_place=False), tmp_path / "pool").computed == 0
    with pytest.raises(ConfigError, match="split_by_place: False there, True here"):
        bench_worlds(_config(worlds=2, split_by_place=True), tmp_path / "pool")
    # and one from before unread_place gave a run to β at an unread place, and scored its
    # boundary pokes by straddle
    del header["settings"]["unread_place"], header["settings"]["boundary_score"]
    settings_file.write_text(json.dumps(header))
    resumed = _config(worlds=2, split_by_place=False, unread_place="beta",
                      boundary_score="straddle")
    assert bench_worlds(resumed, tmp_path / "pool").computed == 0
    with pytest.raises(ConfigError, match="unread_place: 'beta' there, 'avoid' here"):
        bench_worlds(replace(resumed, unread_place="avoid"), tmp_path / "pool")
    with pytest.raises(ConfigError, match="boundary_score: 'straddle' there, 'nearest-poke'"):
        bench_worlds(replace(resumed, boundary_score="nearest-poke"), tmp_path / "pool")


def test_a_failing_world_is_tried_twice_then_reported_not_dropped(caplog) -> None:
    bad = {**_config(worlds=1).task(0), "families": ["spiral"]}  # fails as it is drawn
    with caplog.at_level("WARNING"):
        results = list(_local_results([bad], workers=1))
    assert [r["status"] for r in results] == ["failed"]
    assert "spiral" in results[0]["error"] and results[0]["rows"] == []
    assert results[0]["world"] == {"index": 0, "family": "spiral"}
    assert "trying once more" in caplog.text


def test_settings_are_checked_against_the_config_literals() -> None:
    with pytest.raises(InvalidArgumentError, match="`strategies` must be distinct names"):
        WorldsBenchConfig(strategies=("paper", "guess"))
    with pytest.raises(InvalidArgumentError, match="`cuts` must be distinct names"):
        WorldsBenchConfig(cuts=("voronoi",))
    with pytest.raises(InvalidArgumentError, match="`families` must be"):
        WorldsBenchConfig(families=())


def test_rescore_scores_other_cuts_on_the_stored_pokes_and_names_what_it_cannot(tmp_path) -> None:
    from typer.testing import CliRunner

    from deformap.cli import app

    runner = CliRunner()
    bench_worlds(_config(worlds=2), tmp_path / "src")
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "again"), "--cuts", "isopleth,nearest",
                                 "--no-merge-seams"])
    assert result.exit_code == 0, result.output
    again = _values(tmp_path / "again")
    assert [r for r in again if r["cut"] == "isopleth"] == _values(tmp_path / "src")
    assert {r["cut"] for r in again} == {"isopleth", "nearest"} and len(again) == 2 * 2 * 2
    settings = json.loads((tmp_path / "again" / "bench.json").read_text())
    assert settings["rescored_from"] == str(tmp_path / "src")
    assert settings["settings"]["cuts"] == ["isopleth", "nearest"]
    assert "paper/beta/nearest" in json.loads((tmp_path / "again" / "summary.json").read_text())[
        "strategies"]
    # the split by place is a rule after the pokes too; a source from before it had it off
    source_settings = tmp_path / "src" / "bench.json"
    stored = json.loads(source_settings.read_text())
    del stored["settings"]["split_by_place"]
    source_settings.write_text(json.dumps(stored))
    del stored["settings"]["unread_place"], stored["settings"]["boundary_score"]  # and before
    source_settings.write_text(json.dumps(stored))
    for flag, expected, folder in (([], False, "before"), (["--split-by-place"], True, "split")):
        result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                     str(tmp_path / folder), "--cuts", "nearest", *flag])
        assert result.exit_code == 0, result.output
        written = json.loads((tmp_path / folder / "bench.json").read_text())["settings"]
        assert written["split_by_place"] is expected
        assert written["unread_place"] == "beta"  # what such a run did
        assert written["boundary_score"] == "straddle"
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
    assert "world-00001.json is not a rescorable world: no `pokes`" in result.output
    assert "Traceback" not in result.output and not (tmp_path / "third").exists()
    # damaged stored worlds: one line naming the file and what is wrong, before any folder
    assert stored["pokes_format"] == POKES_FORMAT == 3
    stored["pokes"] = {"paper/beta": {"x": [0.1], "y": [0.1, 0.2], "value": [1.0],
                                      "noise": [0.1], "index": [0], "thickness": [0.05]}}
    unthick = {"paper/beta": {k: v for k, v in stored["pokes"]["paper/beta"].items()
                              if k != "thickness"}}
    for damaged, why in (([1, 2], "expected an object"),
                         ({**stored, "world": {"index": "a"}}, "`world.index` must be"),
                         (stored, "columns of different lengths"),
                         ({**stored, "pokes": {}}, "no stored pokes of 'paper/beta'"),
                         ({**stored, "pokes_format": 4},
                          "`pokes_format` must be an integer from 1 to 3 (the formats this "
                          "deformap reads); got 4 (written by a newer version?)"),
                         ({**original, "fallback_pokes": []},
                          "`fallback_pokes` must be an object; got list"),
                         ({**original, "fallback_pokes": {"paper/beta": {"x": [0.1]}}},
                          "the fallback pokes of 'paper/beta' must have lists"),
                         ({**original, "rows": [{**r, "map_field": "hardness"}
                                                for r in original["rows"]]},
                          "has `map_field` 'hardness', expected one of ['beta', 'modulus']"),
                         ({**original, "rows": [{**r, "map_field": "modulus"}
                                                for r in original["rows"]]},
                          "no stored fallback pokes of 'paper/beta', whose map field was "
                          "'modulus' at poke 1 (pokes_format 3)"),
                         ({**stored, "pokes_format": True}, "`pokes_format` must be"),
                         ({**stored, "pokes_format": 2.0}, "`pokes_format` must be an integer"),
                         ({**stored, "pokes": unthick},
                          "the pokes of 'paper/beta' have no `thickness` (pokes_format 3)")):
        world.write_text(json.dumps(damaged))
        result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                     str(tmp_path / "third")])
        assert result.exit_code == 2 and why in result.output, result.output
        assert "Traceback" not in result.output and not (tmp_path / "third").exists()
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path), "--out",
                                 str(tmp_path / "fourth")])
    assert result.exit_code == 2 and "is not a worlds benchmark" in result.output
    # a world stored before the format key and the thickness were is read as the first format
    legacy = {k: v for k, v in original.items() if k != "pokes_format"}
    legacy["pokes"] = {combo: {k: v for k, v in data.items() if k != "thickness"}
                       for combo, data in original["pokes"].items()}
    world.write_text(json.dumps(legacy))
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "fifth"), "--no-merge-seams"])
    assert result.exit_code == 0, result.output
    assert "pokes_format" not in json.loads(
        (tmp_path / "fifth" / "worlds" / "world-00001.json").read_text())
    # a run whose map changed field on the way, stored without its β pokes (before the third
    # format), is carried, and so only under its own cuts
    fell = {**original, "rows": [{**r, "map_field": "modulus"} for r in original["rows"]],
            "pokes_format": 2}
    del fell["fallback_pokes"]
    world.write_text(json.dumps(fell))
    result = runner.invoke(app, ["bench", "rescore", str(tmp_path / "src"), "--out",
                                 str(tmp_path / "sixth"), "--cuts", "isopleth,nearest"])
    assert result.exit_code == 2 and "world-00001.json" in result.output, result.output
    assert "fell back from the modulus field to β" in result.output
    assert not (tmp_path / "sixth").exists()


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
        "from deformap.run._worlds import worker_pool\n"
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
