"""Smoke tests of `deformap study hardness`, `deformap study cluster-size` and `deformap
reproduce` through the CLI on coarse worlds: the files each writes (JSON content, PNGs that are
valid images).

The commands have no option to skip the surface GP's hyperparameter fit or to choose fewer
foams, places or cluster sizes, so the two studies take tens of seconds and are marked slow;
`reproduce` runs all six scenarios of Table I (no option chooses fewer), made as fast as a
configuration file can (coarse world, two pokes, fixed hyperparameters): slow too.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from PIL import Image
from typer.testing import CliRunner

from deformap.cli import app
from deformap.eval import PAPER_TABLE_I, PROTOCOLS, STUDY_PROTOCOLS


def _invoke(*args: str) -> None:
    result = CliRunner().invoke(app, list(args))
    assert result.exit_code == 0, (result.output, result.exception)


def _check_png(path: Path) -> None:
    with Image.open(path) as image:
        assert image.format == "PNG"
        assert image.size[0] > 100 and image.size[1] > 100
        image.verify()


def _check_beta_row(row: dict[str, Any]) -> None:
    assert 0.0 <= row["beta"] < 1.0
    assert row["fit_error_m"] > 0 and math.isfinite(row["fit_error_m"])
    assert isinstance(row["converged"], bool)


@pytest.mark.slow
def test_study_hardness_writes_its_table_and_figure(tmp_path: Path) -> None:
    out = tmp_path / "hardness"
    _invoke("study", "hardness", "--coarse", "--hardness", "60", "--out", str(out))
    study = json.loads((out / "hardness.json").read_text())
    _check_png(out / "hardness.png")
    rows = study["rows"]
    # the default protocol and the paper's, unless --protocol asks for others
    assert [(r["protocol"], r["hardness_n"]) for r in rows] == [
        (p, h) for p in STUDY_PROTOCOLS for h in (60.0, None)
    ]
    for row in rows:
        _check_beta_row(row)
    assert set(study["monotone"]) == set(STUDY_PROTOCOLS) and set(STUDY_PROTOCOLS) < set(PROTOCOLS)
    for name, flag in study["monotone"].items():
        soft, rigid = (r["beta"] for r in rows if r["protocol"] == name)
        assert flag == (soft > rigid)
    # the default protocol tells the 60 N foam from the rigid board
    soft, rigid = (r["beta"] for r in rows if r["protocol"] == "force/quadratic")
    assert soft > 0.5 and rigid < 0.05


@pytest.mark.slow
def test_study_cluster_size_writes_its_table_and_figure(tmp_path: Path) -> None:
    out = tmp_path / "cluster"
    _invoke("study", "cluster-size", "--coarse", "--out", str(out))
    study = json.loads((out / "cluster-size.json").read_text())
    _check_png(out / "cluster-size.png")
    rows = study["rows"]
    assert [(r["cluster_size"], r["hardness_n"]) for r in rows] == [
        (k, h) for k in (2, 3, 4, 5, 6) for h in (60.0, 110.0, 150.0, None)
    ]
    for row in rows:
        _check_beta_row(row)
    for k in (2, 3, 4, 5, 6):
        betas = [r["beta"] for r in rows if r["cluster_size"] == k]
        assert betas == sorted(betas, reverse=True) and betas[0] > betas[-1], k


@pytest.mark.slow
def test_reproduce_runs_every_scenario_and_writes_the_table(tmp_path: Path) -> None:
    config = tmp_path / "coarse.yaml"
    config.write_text(yaml.safe_dump({
        "world": {"element_size_m": 0.02, "top_layer_m": 0.01,
                  "camera": {"width": 320, "height": 240}},
        "exploration": {"max_pokes": 2, "surface": {"fit_hyperparameters": False}},
    }))  # fmt: skip
    out = tmp_path / "reproduce"
    _invoke("reproduce", "--config", str(config), "--seed", "3", "--out", str(out))
    table = json.loads((out / "table.json").read_text())
    assert table["seed"] == 3 and table["strategy"] == "planned"
    assert [r["scenario"] for r in table["rows"]] == list(PAPER_TABLE_I)
    markdown = (out / "table.md").read_text()
    for row in table["rows"]:
        name = row["scenario"]
        assert row["paper"] == PAPER_TABLE_I[name]
        report = json.loads((out / name / "report.json").read_text())
        # the table is built from each run's own report
        assert row["pokes"] == report["n_pokes"] == 2
        assert row["stop_reason"] == report["stop_reason"] == "max_pokes"
        assert row["regions_true"] == report["regions"]["true"] == PAPER_TABLE_I[name]["regions"]
        assert row["regions_found"] == report["regions"]["found"] >= 1
        assert row["accuracy"] == report["regions"]["accuracy"]
        assert 0.0 < row["accuracy"] <= 1.0 and row["time_s"] > 0
        _check_png(out / name / "map.png")
        assert f"| {name} | {PAPER_TABLE_I[name]['interactions']} |" in markdown


def test_camera_presets_are_named_cameras_with_their_specs() -> None:
    from deformap.errors import InvalidArgumentError
    from deformap.world import CAMERA_PRESETS, CameraConfig, camera_preset

    assert camera_preset("primesense") == CameraConfig()
    kinect, d435 = camera_preset("kinect-v1"), camera_preset("realsense-d435")
    assert (kinect.width, kinect.height, kinect.height_m) == (320, 240, 1.0)
    assert (d435.fov_deg, d435.baseline_m) == ((87.0, 58.0), 0.05)
    assert set(CAMERA_PRESETS) == {"primesense", "kinect-v1", "realsense-d435"}
    with pytest.raises(InvalidArgumentError, match="`camera` must be one of"):
        camera_preset("webcam")


@pytest.mark.slow
def test_the_hardness_study_runs_under_another_camera_and_thickness(tmp_path: Path) -> None:
    from deformap import run

    out = run.run_hardness_study(tmp_path / "s", hardness=[60.0], coarse=True,
                                 camera="kinect-v1", thickness_m=0.03)
    study = json.loads((out.folder / "hardness.json").read_text())
    assert (study["camera"], study["thickness_m"], study["force_n"]) == ("kinect-v1", 0.03, 0.6)
    rows = {(r["protocol"], r["hardness_n"]): r for r in study["rows"]}
    foam, board = rows[("force/quadratic", 60.0)], rows[("force/quadratic", None)]
    assert foam["camera"] == "kinect-v1" and foam["thickness_m"] == 0.03
    assert foam["modulus_pa"] is not None and not foam["rigid"] and board["rigid"]
