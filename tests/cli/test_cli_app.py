"""The command's shape: ``deformap --help`` loads no library package, every command is there."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

import deformap
from deformap.cli import app

runner = CliRunner()


def test_the_command_loads_neither_the_world_nor_the_estimator() -> None:
    # `deformap --help` must stay fast: the run layer and eval import their names on first use.
    src = str(Path(deformap.__file__).resolve().parents[1])
    heavy = ("matplotlib", "scipy", "deformap.world", "deformap.explore", "deformap.gp",
             "deformap.msm", "deformap.replay")  # fmt: skip
    code = (f"import sys; sys.path.insert(0, {src!r}); import deformap.cli; "
            f"print(sorted(m for m in {heavy!r} if m in sys.modules))")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_command_group_is_registered() -> None:
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    for name in ("explore", "record-sim", "map", "estimate", "reproduce", "scenarios", "bench",
                 "config", "study", "world"):  # fmt: skip
        assert name in result.output
    for group, names in (("bench", ("speed", "world", "io", "memory", "worlds", "rescore")),
                         ("study", ("hardness", "cluster-size", "behaviour")),
                         ("world", ("show",))):  # fmt: skip
        result = runner.invoke(app, [group, "--help"])
        assert result.exit_code == 0 and all(n in result.output for n in names), result.output


def test_every_command_with_a_seed_refuses_a_negative_one_before_running(tmp_path: Path) -> None:
    commands = [["explore", "-s", "heterogeneous-60-150"], ["record-sim", "-s", "homogeneous-60"],
                ["map", str(tmp_path)], ["reproduce"], ["study", "hardness"],
                ["study", "cluster-size"], ["study", "behaviour"],
                ["world", "show", "homogeneous-60", "--out",
                                            str(tmp_path / "w")],
                ["bench", "world"], ["bench", "io"], ["bench", "speed"], ["bench", "memory"],
                ["bench", "worlds", "--out", str(tmp_path / "b")]]
    for command in commands:
        result = runner.invoke(app, [*command, "--seed", "-3"])
        assert result.exit_code == 2, (command, result.output)
        assert "`--seed` must be an integer >= 0; got -3" in result.output, (command, result.output)
        assert "Traceback" not in result.output
    assert not (tmp_path / "w").exists() and not (tmp_path / "b").exists()  # before any work
