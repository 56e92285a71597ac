"""`deformap explore` and `deformap config dump`: bad input is one line, never a traceback."""

from __future__ import annotations

import json

import pytest
import yaml
from typer.testing import CliRunner

from deformap._config import dump_yaml
from deformap.cli import app
from deformap.run import RunConfig

runner = CliRunner()


def _error_line(result) -> str:  # type: ignore[no-untyped-def]
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = [line for line in result.output.strip().splitlines() if line.strip()]
    return " ".join(lines)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--scenario", "no-such-world"], "no-such-world"),
        (["--threshold", "0"], "`threshold` must be > 0"),
        (["--threshold", "-1"], "`threshold` must be > 0"),
        (["--max-pokes", "0"], "`max_pokes` must be an integer >= 1"),
        (["--strategy", "greedy"], "`strategy` must be one of"),
        (["--field", "hardness"], "`field` must be one of"),
    ],
)
def test_bad_options_are_one_line_errors(tmp_path, args: list[str], message: str) -> None:
    result = runner.invoke(app, ["explore", "--out", str(tmp_path / "run"), *args])
    assert message in _error_line(result)


def test_config_dump_round_trips_and_bad_configs_name_the_field(tmp_path) -> None:
    result = runner.invoke(app, ["config", "dump", "--out", str(tmp_path / "c.yaml")])
    assert result.exit_code == 0, result.output
    data = yaml.safe_load((tmp_path / "c.yaml").read_text())
    assert data["exploration"]["threshold"] == 0.06
    assert data["scenario"] == "heterogeneous-60-110-rigid"
    data["exploration"]["treshold"] = 0.1
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    result = runner.invoke(
        app, ["explore", "--config", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "run")]
    )
    assert "exploration` has unknown key(s) ['treshold']" in _error_line(result)
    (tmp_path / "worse.yaml").write_text("exploration: {max_pokes: many}\n")
    result = runner.invoke(
        app, ["explore", "--config", str(tmp_path / "worse.yaml"), "--out", str(tmp_path / "run")]
    )
    assert "`worse.yaml.exploration.max_pokes` must be an integer" in _error_line(result)


def test_an_occupied_folder_is_refused_and_nothing_in_it_is_lost(tmp_path) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "report.json").write_text(json.dumps({"precious": True}))
    result = runner.invoke(app, ["explore", "--out", str(out)])
    assert "exists and is not empty; choose another --out or pass --resume" in _error_line(result)
    assert json.loads((out / "report.json").read_text()) == {"precious": True}
    result = runner.invoke(app, ["explore", "--resume", str(tmp_path / "empty")])
    assert "holds no config.yaml, so no run started there" in _error_line(result)


def test_resume_refuses_other_settings_before_any_work(tmp_path) -> None:  # type: ignore[no-untyped-def]
    run = tmp_path / "run"
    run.mkdir()
    dump_yaml(RunConfig(seed=4), run / "config.yaml")
    result = runner.invoke(app, ["explore", "--resume", str(run), "--seed", "5", "--max-pokes", "2"])
    assert "with different settings (max_pokes, seed); drop those options" in _error_line(result)
    result = runner.invoke(app, ["explore", "--resume", str(run), "--config", str(run / "config.yaml")])
    assert "do not pass --config too" in _error_line(result)
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml"]


def test_the_summary_line_on_the_modulus_field() -> None:
    from deformap.cli._explore import modulus_summary

    assert "no poke has a modulus" in modulus_summary({"modulus_field": None})
    pokes = [{"used": True, "rigid": False}, {"used": True, "rigid": True},
             {"used": False, "rigid": False}]
    report = {"modulus_field": {"n_used": 2, "pokes": pokes},
              "regions": {"class_modulus_median_pa": [7_500.0, 2.5e6]}}
    line = modulus_summary(report)
    assert "median E per region [kPa]: 7.5, 2.5e+03" in line
    assert "from 2 poke(s), 1 rigid" in line and "1 left out" in line
