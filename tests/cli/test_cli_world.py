"""The world's CLI commands: scenarios, world show, bench world."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from deformap.cli import app

runner = CliRunner()


def test_scenarios_lists_table_i() -> None:
    result = runner.invoke(app, ["scenarios"])
    assert result.exit_code == 0, result.output
    for name in ("homogeneous-60", "heterogeneous-60-110-rigid"):
        assert name in result.output


def test_world_show_writes_four_pictures(tmp_path) -> None:
    result = runner.invoke(app, ["world", "show", "heterogeneous-150-rigid", "--out",
                                 str(tmp_path), "--coarse"])
    assert result.exit_code == 0, result.output
    for name in ("layout.png", "rgb.png", "cloud.png", "dent.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_world_show_unknown_scenario_is_one_line_error(tmp_path) -> None:
    result = runner.invoke(app, ["world", "show", "no-such-world", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "unknown scenario 'no-such-world'" in result.output


def test_bench_world_writes_json(tmp_path) -> None:
    out = tmp_path / "world.json"
    result = runner.invoke(app, ["bench", "world", "--coarse", "--json", str(out)])
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert set(data) >= {"construction_s", "press_s", "observe_s", "n_dofs", "n_points_on_area"}
    assert data["n_dofs"] > 0 and data["n_points_on_area"] > 1000
    # one poke's compute with its record, and the camera-only baseline beside it
    assert 0.0 < data["poke_compute_s"] and 0.0 < data["poke_compute_camera_only_s"]
    # the press with the FEM's unit responses, and solved load by load beside it
    assert 0.0 < data["press_s"] and 0.0 < data["press_load_by_load_s"]
    assert "baseline of press_s" in result.output
    assert "poke_compute_camera_only_s" in result.output
