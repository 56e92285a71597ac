"""`deformap study hardness --full` (issue 13): the matrix of conditions in one hardness.json with
a summary per condition and per physics, foams the world refuses to press recorded rather than
fatal, and the summary's numbers checked on hand-made rows.

The CLI test shrinks the matrix to two cameras (the run layer's module constant) and pins one
thickness and one physics on the command line, and presses a 30 N foam 3 cm thick with 3 N: the
world refuses it (the tip would sink deeper than the block), while the 110 N foam takes it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from deformap.cli import app
from deformap.eval import collect_presses, hardness_study, hardness_summary
from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.world import WorldConfig


def _row(hardness: float | None, beta: float, moduli: list[float | None],
         stds: list[float | None], true: float | None, *, camera: str = "primesense",
         physics: str = "linear-fem", protocol: str = "force/quadratic",
         refused: str | None = None) -> dict[str, Any]:  # fmt: skip
    read = [m for m in moduli if m is not None]
    return {
        "protocol": protocol, "hardness_n": hardness, "camera": camera, "thickness_m": 0.05,
        "physics": physics, "force_n": 0.6, "refused": refused,
        "beta": None if refused else beta, "beta_std": None if refused else 0.02,
        "beta_estimate_std": None if refused else 0.01,
        "rigid": None if refused else hardness is None, "true_modulus_pa": true,
        "modulus_pa": float(np.mean(read)) if read else None,
        "moduli_pa": moduli, "modulus_stds_pa": stds,
    }  # fmt: skip


def _condition(camera: str, physics: str, *, soft_e: float = 10e3) -> list[dict[str, Any]]:
    """Three foams (the hardest refused) and the rigid board: the soft foam read at 0.75·, 1·
    and 1.3· its true E with σ 0.1·E (one of its three presses within 2σ), the 110 N one exactly
    (σ 1 Pa)."""
    return [
        _row(30.0, 0.6, [0.75 * soft_e, soft_e, 1.3 * soft_e], [0.1 * soft_e] * 3, soft_e,
             camera=camera, physics=physics),
        _row(110.0, 0.3, [40e3, 40e3, 40e3], [1.0] * 3, 40e3, camera=camera, physics=physics),
        _row(250.0, 0.1, [], [], 90e3, camera=camera, physics=physics, refused="too deep"),
        _row(None, 0.0, [None] * 3, [None] * 3, None, camera=camera, physics=physics),
        # another protocol's row: not read by the summary
        _row(30.0, 0.9, [1.0] * 3, [1.0] * 3, soft_e, camera=camera, physics=physics,
             protocol="pinned/linear"),
    ]  # fmt: skip


def test_the_summary_counts_presses_not_foam_means() -> None:
    rows = _condition("primesense", "linear-fem") + _condition("kinect-v1", "linear-fem")
    # a stiffening condition where β is out of order and one soft press read nothing
    stiff = _condition("primesense", "stiffening-foam")
    stiff[0]["moduli_pa"] = [7e3, None, 13e3]
    stiff[0]["modulus_stds_pa"] = [1e3, None, 1e3]
    stiff[1]["beta"] = 0.7
    result = hardness_summary(rows + stiff)
    summary = {(s["camera"], s["physics"]): s for s in result["summary"]}
    assert list(summary) == [("primesense", "linear-fem"), ("kinect-v1", "linear-fem"),
                             ("primesense", "stiffening-foam")]  # fmt: skip
    one = summary["primesense", "linear-fem"]
    assert one["thickness_m"] == 0.05 and one["force_n"] == 0.6
    assert one["n_presses"] == 6 and one["n_unread"] == 0 and one["n_refused"] == 1
    # |errors| 0.25, 0, 0.3, 0, 0, 0: median 0; within 2σ: the soft foam's 1·E and the exact three
    assert one["modulus_median_abs_rel_error"] == pytest.approx(0.0)
    assert one["modulus_within_2sigma"] == pytest.approx(4 / 6)
    assert one["modulus_monotone"] is True and one["beta_monotone"] is True
    assert one["beta_claimed_std"] == pytest.approx(0.01)
    assert one["beta_spread"] == pytest.approx(0.02)
    two = summary["primesense", "stiffening-foam"]
    assert two["n_presses"] == 6 and two["n_unread"] == 1
    assert two["modulus_median_abs_rel_error"] == pytest.approx(0.0)  # 0.3, 0.3, 0, 0, 0
    assert two["modulus_within_2sigma"] == pytest.approx(3 / 6)  # the unread one counts out
    assert two["beta_monotone"] is False and two["modulus_monotone"] is True
    overall = {o["physics"]: o for o in result["overall"]}
    assert overall["linear-fem"]["n_conditions"] == 2
    assert overall["linear-fem"]["n_presses"] == 12 and overall["linear-fem"]["n_refused"] == 2
    assert overall["linear-fem"]["modulus_within_2sigma"] == pytest.approx(8 / 12)
    assert overall["stiffening-foam"]["n_unread"] == 1
    assert overall["linear-fem"]["beta_monotone"] is True
    assert overall["stiffening-foam"]["beta_monotone"] is False
    # a median that is not zero: the soft foam alone (|errors| 0.25, 0, 0.3)
    alone = hardness_summary(rows[:1])["summary"][0]
    assert alone["modulus_median_abs_rel_error"] == pytest.approx(0.25)
    assert alone["modulus_within_2sigma"] == pytest.approx(1 / 3)


def test_a_soft_foam_read_rigid_breaks_the_modulus_order() -> None:
    rows = _condition("primesense", "linear-fem")
    rows[1]["modulus_pa"], rows[1]["rigid"] = None, True
    rows[1]["moduli_pa"] = [None] * 3
    entry = hardness_summary(rows)["summary"][0]
    assert entry["modulus_monotone"] is False
    assert entry["n_unread"] == 3


def test_a_foam_the_world_refuses_is_recorded_not_fatal() -> None:
    config = ExplorationConfig(force_n=3.0, surface=SurfaceGPConfig(fit_hyperparameters=False))
    foams = collect_presses((30.0, None), world_config=WorldConfig.coarse(), config=config,
                            positions=((0.30, 0.20),), thickness_m=0.03,
                            rng=np.random.default_rng(0))  # fmt: skip
    soft, rigid = foams
    assert soft.presses == [] and soft.refused is not None and "force_n" in soft.refused
    assert rigid.refused is None and len(rigid.presses) == 1
    study = hardness_study(foams, protocols={"force/quadratic": {}})
    assert study["n_refused"] == 1
    row = study["rows"][0]
    assert row["refused"] == soft.refused
    assert row["beta"] is None and row["modulus_pa"] is None and row["moduli_pa"] == []
    assert row["true_modulus_pa"] is not None and row["true_modulus_pa"] > 0
    assert study["rows"][1]["refused"] is None and study["rows"][1]["rigid"] is True
    # the refused foam left out, and one surface read shows no order
    assert study["monotone"] == {"force/quadratic": False}


@pytest.mark.slow
def test_full_writes_every_condition_with_its_summary(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from deformap.run import _studies

    monkeypatch.setattr(_studies, "FULL_CAMERAS", ("primesense", "kinect-v1"))
    out = tmp_path / "full"
    # --thickness and --physics given pin those axes of the matrix; the cameras span it
    result = CliRunner().invoke(app, ["study", "hardness", "--full", "--coarse", "--force", "3",
                                      "--hardness", "30", "--hardness", "110",
                                      "--thickness", "0.03", "--physics", "linear-fem",
                                      "--protocol", "force/quadratic", "--protocol",
                                      "pinned/linear", "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, (result.output, result.exception)
    assert "per physics" in result.output and "kinect-v1" in result.output, result.output
    study = json.loads((out / "hardness.json").read_text())
    assert study["matrix"]["cameras"] == ["primesense", "kinect-v1"]
    assert study["matrix"]["thicknesses_m"] == [0.03] and study["matrix"]["force_n"] == 3.0
    conditions = {(r["camera"], r["thickness_m"], r["physics"], r["force_n"])
                  for r in study["rows"]}  # fmt: skip
    assert conditions == {("primesense", 0.03, "linear-fem", 3.0),
                          ("kinect-v1", 0.03, "linear-fem", 3.0)}  # fmt: skip
    assert len(study["rows"]) == 2 * 2 * 3  # conditions × protocols × foams
    assert {r["protocol"] for r in study["rows"]} == {"force/quadratic", "pinned/linear"}
    assert [(s["camera"], s["n_refused"]) for s in study["summary"]] == [
        ("primesense", 1), ("kinect-v1", 1)]  # fmt: skip
    for row in study["rows"]:
        if row["hardness_n"] == 30.0:
            assert "force_n" in row["refused"] and row["beta"] is None
        else:
            assert row["refused"] is None and 0.0 <= row["beta"] < 1.0
        if row["hardness_n"] == 110.0:
            errors = row["modulus_rel_errors"]
            assert len(errors) == 3 and all(math.isfinite(e) for e in errors)
            assert np.mean(errors) == pytest.approx(row["modulus_rel_error"])
    for entry in study["summary"]:
        assert entry["n_presses"] == 3 and entry["n_unread"] == 0
        assert 0.0 <= entry["modulus_median_abs_rel_error"] < 1.0
        assert entry["modulus_monotone"] is True  # 110 N read, rigid read rigid
    (overall,) = study["overall"]
    assert overall["physics"] == "linear-fem" and overall["n_presses"] == 6
    assert overall["n_refused"] == 2
    with Image.open(out / "hardness.png") as image:
        assert image.format == "PNG" and image.size[0] > 600


def test_an_unknown_protocol_is_refused_before_any_world(tmp_path: Path) -> None:
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "hardness", "--protocol", "pinned/cubic",
                                      "--out", str(out)])  # fmt: skip
    assert result.exit_code == 2
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and "protocols" in lines[0] and "'pinned/cubic'" in lines[0]
    assert "force/quadratic" in lines[0] and not out.exists()


def test_the_quick_study_fits_the_default_and_the_papers_protocol() -> None:
    from deformap.eval import DEFAULT_PROTOCOL, PAPER_PROTOCOL, STUDY_PROTOCOLS
    from deformap.run._studies import _protocols

    assert STUDY_PROTOCOLS == (DEFAULT_PROTOCOL, PAPER_PROTOCOL)
    assert list(_protocols(None)) == ["force/quadratic", "pinned/quadratic"]
    assert list(_protocols(["pinned/linear", "pinned/linear"])) == ["pinned/linear"]


@pytest.mark.parametrize(("args", "names"), [
    (["--thickness", "1e-320"], "thickness_m"),
    (["--thickness", "0.0005"], "thickness_m"),
    (["--hardness", "1e400"], "hardness_n"),
    (["--force", "1e-320"], "force_n"),
    (["--force", "0.05"], "force_n"),
    (["--element-size", "0.0005"], "--element-size"),
    (["--element-size", "nan"], "--element-size"),
    (["--element-size", "0.01", "--coarse"], "--element-size"),
    (["--element-size", "0.002"], "--element-size"),  # over the world's mesh budget at 5 cm
])
def test_a_study_nothing_can_press_is_refused_before_any_folder(tmp_path: Path, args: list[str],
                                                                names: str) -> None:
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "hardness", *args, "--out", str(out)])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and names in lines[0] and not out.exists()


def test_the_element_size_reaches_the_world_and_the_study_records_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from deformap.run import _studies

    seen = []
    real = _studies.collect_presses

    def spy(foams: Any, **kwargs: Any) -> Any:
        seen.append((kwargs["world_config"].element_size_m, kwargs["world_config"].top_layer_m))
        return real(foams, **kwargs)

    monkeypatch.setattr(_studies, "collect_presses", spy)
    out = tmp_path / "mesh"
    result = CliRunner().invoke(app, ["study", "hardness", "--element-size", "0.02",
                                      "--hardness", "110", "--thickness", "0.03",
                                      "--protocol", "force/quadratic", "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    assert seen == [(0.02, WorldConfig().top_layer_m)]  # the top layer already finer: kept
    study = json.loads((out / "hardness.json").read_text())
    assert study["element_size_m"] == 0.02
    assert [r["hardness_n"] for r in study["rows"]] == [110.0, None]
    fine = _studies._foams((), seed=0, coarse=False, hooks=_studies.NO_HOOKS,
                           element_size_m=0.003)
    assert fine == [] and seen[-1] == (0.003, 0.003)  # finer than the top layer: it follows


@pytest.mark.slow
def test_full_presses_on_a_contact_resolving_mesh_thickness_first(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`--full` without `--element-size` or `--coarse` is the measurement: its worlds have
    FULL_ELEMENT_SIZE_M elements (the quick look keeps the default). It presses the thicknesses
    one after the other (one FEM factorisation each) and writes the rows in the matrix's own
    order, camera first."""
    from deformap.run import _studies

    assert _studies.FULL_ELEMENT_SIZE_M < WorldConfig().element_size_m
    monkeypatch.setattr(_studies, "FULL_CAMERAS", ("primesense", "kinect-v1"))
    monkeypatch.setattr(_studies, "FULL_THICKNESSES_M", (0.05, 0.03))
    seen: list[tuple[float, float]] = []
    real = _studies.collect_presses

    def spy(foams: Any, **kwargs: Any) -> Any:  # records the mesh, presses on a coarse one
        seen.append((kwargs["thickness_m"], kwargs["world_config"].element_size_m))
        coarse = WorldConfig.coarse(camera=kwargs["world_config"].camera)
        return real(foams, **{**kwargs, "world_config": coarse})

    monkeypatch.setattr(_studies, "collect_presses", spy)
    out = tmp_path / "full"
    result = CliRunner().invoke(app, ["study", "hardness", "--full", "--hardness", "110",
                                      "--physics", "linear-fem", "--protocol",
                                      "force/quadratic", "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, (result.output, result.exception)
    full_mesh = _studies.FULL_ELEMENT_SIZE_M
    assert seen == [(0.03, full_mesh), (0.03, full_mesh), (0.05, full_mesh), (0.05, full_mesh)]
    study = json.loads((out / "hardness.json").read_text())
    assert study["matrix"]["element_size_m"] == full_mesh
    assert [(r["camera"], r["thickness_m"]) for r in study["rows"]][::2] == [
        ("primesense", 0.05), ("primesense", 0.03), ("kinect-v1", 0.05), ("kinect-v1", 0.03)]
    assert [(s["camera"], s["thickness_m"]) for s in study["summary"]] == [
        ("primesense", 0.05), ("primesense", 0.03), ("kinect-v1", 0.05), ("kinect-v1", 0.03)]
    seen.clear()  # the quick look (one condition) stays on the default mesh
    quick = CliRunner().invoke(app, ["study", "hardness", "--hardness", "110", "--protocol",
                                     "force/quadratic", "--out", str(tmp_path / "quick")])
    assert quick.exit_code == 0, (quick.output, quick.exception)
    assert seen == [(0.05, WorldConfig().element_size_m)]
