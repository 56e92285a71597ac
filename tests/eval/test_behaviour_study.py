"""`deformap study behaviour`: the behaviour class each press reads against the material's own,
its confusion matrix (behaviour.json, behaviour.png), and its refusals."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from PIL import Image
from typer.testing import CliRunner

from deformap.cli import app
from deformap.eval import (
    BEHAVIOUR_READS,
    BEHAVIOUR_TRUTHS,
    FULL_BEHAVIOUR_MATERIALS,
    QUICK_BEHAVIOUR_MATERIALS,
    behaviour_summary,
)
from deformap.viz import plot_behaviour_study

runner = CliRunner()


def _row(truth: str, read: str, camera: str = "primesense", material: str = "m") -> dict:
    return {"truth": truth, "read": read, "camera": camera, "thickness_m": 0.03,
            "material": material}


def test_the_summary_counts_each_truth_against_each_read() -> None:
    rows = [_row("elastic", "elastic"), _row("elastic", "unknown"), _row("elastic", "plastic"),
            _row("viscoelastic", "viscoelastic", "kinect-v1", "v"),
            _row("plastic", "plastic", "kinect-v1", "p"), _row("plastic", "elastic", material="p")]
    summary = behaviour_summary(rows)
    assert summary["n_presses"] == 6
    assert summary["confusion"]["elastic"] == {"elastic": 1, "viscoelastic": 0, "plastic": 1,
                                               "unknown": 1}
    assert summary["confusion"]["plastic"]["elastic"] == 1
    assert summary["right"] == pytest.approx(3 / 6)
    assert summary["elastic_flagged"] == pytest.approx(1 / 3)
    assert summary["unknown"] == pytest.approx(1 / 6)
    by_camera = {c["camera"]: c for c in summary["by_condition"]}
    assert by_camera["kinect-v1"]["right"] == 1.0 and by_camera["primesense"]["n_presses"] == 4
    by_material = {m["material"]: m for m in summary["by_material"]}
    assert by_material["p"]["right"] == pytest.approx(0.5)
    empty = behaviour_summary([])
    assert empty["right"] is None and empty["elastic_flagged"] is None


def test_the_matrices_hold_the_issues_materials() -> None:
    truths = [m.truth for m in FULL_BEHAVIOUR_MATERIALS]
    assert truths.count("viscoelastic") == 4 and truths.count("plastic") == 2
    elastic = [m for m in FULL_BEHAVIOUR_MATERIALS if m.truth == "elastic"]
    assert sorted(m.hardness_n for m in elastic if m.anisotropy is None) == [30, 60, 110, 150, 250]
    assert sorted(m.anisotropy.ratio for m in elastic if m.anisotropy is not None) == [1.5, 3.0]
    assert {m.truth for m in QUICK_BEHAVIOUR_MATERIALS} == set(BEHAVIOUR_TRUTHS)


def test_the_confusion_figure_shows_counts_and_shares() -> None:
    fig = plot_behaviour_study(behaviour_summary([_row("elastic", "unknown"),
                                                  _row("plastic", "plastic")]))
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == list(BEHAVIOUR_READS)
    assert [t.get_text() for t in ax.get_yticklabels()] == [
        "elastic (1)", "viscoelastic (0)", "plastic (1)"]
    assert "1\n(100%)" in [t.get_text() for t in ax.texts]
    assert "2 presses, 50% read right, elastic flagged otherwise 0%" in ax.get_title()


@pytest.mark.slow
def test_study_behaviour_writes_its_confusion_matrix(tmp_path: Path) -> None:
    out = tmp_path / "behaviour"
    result = runner.invoke(app, ["study", "behaviour", "--coarse", "--kind", "viscoelastic",
                                 "--out", str(out)])
    assert result.exit_code == 0, result.output
    study = json.loads((out / "behaviour.json").read_text())
    assert study["matrix"]["cameras"] == ["primesense"]
    assert study["matrix"]["thicknesses_m"] == [0.03]
    assert [m["kind"] for m in study["matrix"]["materials"]] == ["viscoelastic"]
    assert study["n_presses"] == len(study["rows"]) == 3
    for row in study["rows"]:
        assert row["truth"] == row["kind"] == "viscoelastic" and row["read"] in BEHAVIOUR_READS
        assert row["evidence"] and row["true"]["relaxation_fraction"] == pytest.approx(0.5)
        assert row["true"]["relaxation_time_s"] == pytest.approx(1.0)
        assert set(row["quantities"]) >= {"relaxation", "tau_s", "loss_ratio", "residual_dent_m"}
    assert sum(study["confusion"]["viscoelastic"].values()) == 3
    assert "behaviour read against the world's truth" in result.output
    with Image.open(out / "behaviour.png") as image:
        assert image.format == "PNG" and image.size[0] > 300


@pytest.mark.parametrize(("args", "message"), [
    (["--kind", "rubbery"], "kinds: expected one or more of elastic, viscoelastic"),
    (["--camera", "webcam"], "webcam"),
    (["--thickness", "-0.1"], "thickness"),
    (["--force", "0.001"], "force_n"),
])
def test_study_behaviour_refuses_bad_options_before_any_folder(
        tmp_path: Path, args: list[str], message: str) -> None:
    out = tmp_path / "never"
    result = runner.invoke(app, ["study", "behaviour", *args, "--out", str(out)])
    assert result.exit_code == 2, result.output
    assert message in result.output and "Traceback" not in result.output
    assert not out.exists()
