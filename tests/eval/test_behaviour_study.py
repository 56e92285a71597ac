"""`deformap study behaviour`: the behaviour class each press reads against the material's own,
its confusion matrix (behaviour.json, behaviour.png), and its refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from deformap.cli import app
from deformap.eval import (
    BEHAVIOUR_READS,
    BEHAVIOUR_TOLERANCES,
    BEHAVIOUR_TRUTHS,
    DEFAULT_POSITIONS,
    FULL_BEHAVIOUR_MATERIALS,
    QUICK_BEHAVIOUR_MATERIALS,
    BehaviourMaterial,
    behaviour_presses,
    behaviour_summary,
)
from deformap.run import run_behaviour_study
from deformap.stiffness._behaviour import RELAXATION_FLOOR
from deformap.viz import plot_behaviour_study
from deformap.world import Viscoelastic, WorldConfig

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


def test_the_summary_sets_each_reading_against_the_worlds() -> None:
    def row(kind: str, quantities: dict, true: dict) -> dict:
        return {**_row("elastic", "elastic", material=kind), "kind": kind,
                "quantities": quantities, "true": true}

    rows = [row("viscoelastic", {"relaxation": 0.30, "tau_s": 1.5, "residual_dent_m": 4e-3},
                {"creep_fraction": 0.32, "creep_time_s": 2.0, "tip_rest_dent_m": 1e-3}),
            row("viscoelastic", {"relaxation": 0.40, "tau_s": 2.2, "residual_dent_m": None},
                {"creep_fraction": 0.32, "creep_time_s": 2.0, "tip_rest_dent_m": 1e-3}),
            row("plastic", {"relaxation": 0.001, "tau_s": None, "residual_dent_m": 2.2e-3},
                {"creep_fraction": 0.0, "creep_time_s": None, "tip_rest_dent_m": 2.0e-3})]
    errors = behaviour_summary(rows)["errors"]
    assert errors["relaxation"]["n"] == 3 and errors["relaxation"]["within"] == 2
    assert errors["relaxation"]["largest"] == pytest.approx(0.08)
    assert errors["tau"]["n"] == 2 and errors["tau"]["within"] == 1  # 25 % and 10 % off
    assert errors["tau"]["tolerance"] == 0.20
    assert errors["tau"]["median"] == pytest.approx(0.175)
    # a viscoelastic dent recovers in time: only the plastic press's is set against the world's
    assert errors["residual_dent"]["n"] == 1 and errors["residual_dent"]["within"] == 1
    assert errors["residual_dent"]["largest"] == pytest.approx(2e-4)
    assert BEHAVIOUR_TOLERANCES == {"relaxation": 0.05, "tau": 0.20, "residual_dent": 3e-4}
    by_material = {m["material"]: m for m in behaviour_summary(rows)["by_material"]}
    assert by_material["plastic"]["errors"]["tau"]["n"] == 0


@pytest.mark.slow
def test_a_small_seeded_study_reads_each_press_as_its_world_did(tmp_path: Path) -> None:
    """The quick study on the coarse world: no press read as a class its material did not show;
    every viscoelastic press read so, with its creep and time constant; every press on a
    rate-independent block rules the hold's creep out (the hold read at the sensors' rate)."""
    study = run_behaviour_study(tmp_path / "study", coarse=True).study
    assert study["n_presses"] == 12
    for row in study["rows"]:
        assert row["read"] in (row["truth"], "unknown"), row["evidence"]
        q, true = row["quantities"], row["true"]
        if row["truth"] == "viscoelastic":
            assert row["read"] == "viscoelastic"
            assert abs(q["relaxation"] - true["creep_fraction"]) <= 0.05
            assert abs(q["tau_s"] / true["creep_time_s"] - 1.0) <= 0.20
        else:
            assert true["creep_fraction"] == 0.0
            assert q["relaxation"] + 2.0 * q["relaxation_sigma"] < RELAXATION_FLOOR
    assert study["confusion"]["viscoelastic"]["viscoelastic"] == 3
    assert study["elastic_flagged"] == 0.0
    assert study["errors"]["relaxation"]["within"] == study["errors"]["relaxation"]["n"] == 12


@pytest.mark.parametrize("relaxed_ratio", [0.5, 0.9])
def test_a_relaxation_time_as_long_as_the_ramp_reads_viscoelastic(relaxed_ratio: float) -> None:
    """τ 0.3 s against the 0.29 s ramp of a 0.6 N press at 2 N/s, held 3 s and unloaded: part of
    the relaxation happens on the ramp and the hold still shows the rest: it reads viscoelastic."""
    material = BehaviourMaterial(f"memory τ 0.3 s g∞ {relaxed_ratio:g}", 60.0, viscoelastic=(
        Viscoelastic(relaxed_ratio=relaxed_ratio, times_s=(0.3,))))
    config = WorldConfig.coarse(hold_s=3.0, unload=True)
    rows = behaviour_presses(material, world_config=config, force_n=0.6,
                             rng=np.random.default_rng(11), thickness_m=0.03,
                             positions=DEFAULT_POSITIONS[:2])
    for row in rows:
        assert row["truth"] == "viscoelastic"
        assert row["read"] == "viscoelastic", row["evidence"]
        assert abs(row["quantities"]["relaxation"] - row["true"]["creep_fraction"]) <= 0.05


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
        assert row["truth"] == row["kind"] == row["read"] == "viscoelastic"
        assert row["evidence"] and row["true"]["relaxation_fraction"] == pytest.approx(0.5)
        assert row["true"]["relaxation_time_s"] == pytest.approx(1.0)
        assert set(row["quantities"]) >= {"relaxation", "tau_s", "loss_ratio", "residual_dent_m"}
    assert sum(study["confusion"]["viscoelastic"].values()) == 3
    assert "behaviour read against the world's truth" in result.output
    errors = study["errors"]
    assert (errors["relaxation"]["n"], errors["tau"]["n"], errors["residual_dent"]["n"]) == (3, 3, 0)
    assert (f"relaxation within 0.05 {errors['relaxation']['within']}/3, time constant within "
            f"20% {errors['tau']['within']}/3, residual dent within 0.3 mm 0/0") in result.output
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
