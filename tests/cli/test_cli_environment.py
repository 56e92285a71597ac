"""`deformap explore --environment package.module:factory --env-arg k=v` drives a user's own
Environment through the same loop, with the same files, and refuses what it cannot load."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformap.cli import app

runner = CliRunner()

ROBOT = '''
import numpy as np
from deformap.world import SimulatedWorld, WorldConfig, load_scenario

CALLS = []

def make(scenario="heterogeneous-60-150", seed=0, scale=1.0):
    CALLS.append((scenario, seed, scale))
    return SimulatedWorld(load_scenario(scenario), config=WorldConfig.coarse(),
                          rng=np.random.default_rng(seed))

def not_an_environment():
    return 42

def offline():
    raise ConnectionError("robot offline")

def quits():
    import sys
    sys.exit(0)

VALUE = 3
'''

SMALL = "exploration: {max_pokes: 2, surface: {fit_hyperparameters: false}}\n"


@pytest.fixture
def robot_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "my_robot_env.py").write_text(ROBOT)
    (tmp_path / "my_broken_env.py").write_text("raise RuntimeError('no driver')\n")
    (tmp_path / "small.yaml").write_text(SMALL)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    sys.modules.pop("my_robot_env", None)
    sys.modules.pop("my_broken_env", None)


def test_a_users_environment_is_explored_with_every_output(robot_folder: Path) -> None:
    out = robot_folder / "run"
    import importlib.util

    rerun = ["--rerun"] if importlib.util.find_spec("rerun") else []  # the `rerun` extra
    result = runner.invoke(app, ["explore", "--environment", "my_robot_env:make", "--env-arg",
                                 "seed=1", "--env-arg", "scale=0.5", "--config", "small.yaml",
                                 "--out", str(out), *rerun])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert (out / "run.rrd").is_file() == bool(rerun)
    import my_robot_env  # type: ignore[import-not-found]

    assert my_robot_env.CALLS == [("heterogeneous-60-150", 1, 0.5)]  # YAML scalars: int, float
    report = json.loads((out / "report.json").read_text())
    assert report["environment"] == "my_robot_env:make"
    assert report["env_args"] == {"seed": 1, "scale": 0.5}
    assert report["n_pokes"] == 2 and "true_regions" not in report  # no ground truth here
    for name in ("config.yaml", "journal.jsonl", "map.npz", "pokes.csv", "map.png",
                 "poke-01.png", "poke-02.png"):
        assert (out / name).is_file(), name
    assert "2 pokes" in result.output
    # pokes and regions numbered from 1, as poke-01.png and the map's R1, R2, … are
    import csv

    rows = list(csv.DictReader((out / "pokes.csv").open()))
    assert [r["poke"] for r in rows] == ["1", "2"]
    assert [p["index"] for p in report["pokes"]] == [0, 1]  # report.json keeps its index
    assert all(int(r["region"]) >= 1 for r in rows if r["region"])


@pytest.mark.parametrize(("args", "message"), [
    (["--environment", "my_robot_env"], r"--environment must be package.module:factory"),
    (["--environment", "no_such_module_xyz:make"], r"cannot import 'no_such_module_xyz'"),
    (["--environment", "my_robot_env:VALUE"], r"has no callable 'VALUE'"),
    (["--environment", "my_robot_env:not_an_environment"], r"must return an Environment.*int"),
    (["--environment", "my_robot_env:make", "--env-arg", "colour=red"],
     r"the --env-arg values do not fit make\(\)"),
    (["--environment", "my_robot_env:make", "--env-arg", "seed"], r"--env-arg must be key=value"),
    (["--environment", "my_robot_env:make", "--env-arg", "a=1", "--env-arg", "a=2"],
     r"--env-arg 'a' is given twice"),
    (["--env-arg", "seed=1"], r"--env-arg goes with --environment"),
    (["--environment", ".my_robot_env:make"], r"an absolute module name"),
    (["--environment", "my_broken_env:make"], r"cannot import 'my_broken_env' \(RuntimeError: "
                                              r"no driver"),
    (["--environment", "my_robot_env:offline"], r"offline\(\) raised ConnectionError: robot offline"),
    (["--environment", "my_robot_env:quits"], r"quits\(\) called sys.exit\(0\)"),
    (["--environment", "my_robot_env:make", "--env-arg", "scale=.nan"],
     r"--env-arg 'scale' must be finite"),
    (["--environment", "my_robot_env:make", "--scenario", "homogeneous-60"],
     r"--environment runs without --scenario"),
])
def test_what_cannot_be_loaded_is_one_line_and_exit_2(robot_folder: Path, args: list[str],
                                                      message: str) -> None:
    result = runner.invoke(app, ["explore", *args, "--out", str(robot_folder / "x")])
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    import re

    assert re.search(message, result.output.replace("\n", " ")), result.output
    assert not (robot_folder / "x").exists()  # nothing made before the environment loads
