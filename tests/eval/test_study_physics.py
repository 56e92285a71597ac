"""`deformap study hardness --physics`: the study under the world's stiffening physics."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformap.cli import app


def test_an_unknown_physics_is_refused_in_one_line_before_any_world(tmp_path: Path) -> None:
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "hardness", "--physics", "rubber",
                                      "--out", str(out)])
    assert result.exit_code != 0
    message = [line for line in result.output.splitlines() if "physics" in line]
    assert message and ("must be one of ['linear-fem', 'stiffening-foam', 'stiffening-fem']"
                        in " ".join(message))
    assert "'rubber'" in result.output
    assert not (out / "hardness.json").exists()


@pytest.mark.slow
@pytest.mark.parametrize("physics", ["stiffening-foam", "stiffening-fem"])
def test_the_study_runs_under_a_stiffening_physics(tmp_path: Path, physics: str) -> None:
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "hardness", "--coarse", "--physics", physics,
                                      "--hardness", "60", "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    assert physics in result.output
    study = json.loads((out / "hardness.json").read_text())
    assert study["physics"] == physics
    rows = [r for r in study["rows"] if r["protocol"] == "force/quadratic"]
    assert all(r["physics"] == physics for r in study["rows"])
    soft, rigid = rows
    assert soft["modulus_pa"] > 0 and not soft["rigid"] and rigid["rigid"]
    assert soft["true_modulus_pa"] > 0 and rigid["true_modulus_pa"] is None
    assert soft["beta"] > rigid["beta"]
