"""`deformap map`'s exit code says whether there is a map: 0 with one, 2 when no poke was usable
(the report is still written, nothing lost); user text is printed as written, never as markup."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformap.cli import app

runner = CliRunner()


def test_a_session_with_no_usable_poke_exits_2_after_writing_its_report(
    tmp_path: Path, synthetic, write_synthetic  # type: ignore[no-untyped-def]
) -> None:
    session = write_synthetic(tmp_path / "session", synthetic, sealed=False)
    for cloud in (tmp_path / "session").glob("poke-0[0-9].pcd"):
        cloud.unlink()
    out = tmp_path / "map"
    result = runner.invoke(app, ["map", str(session), "--out", str(out), "--no-figures"])
    assert result.exit_code == 2, result.output
    assert "error: no poke of the session" in result.output
    assert "expected at least one, got 0 of 3" in result.output
    report = json.loads((out / "report.json").read_text())
    assert report["n_pokes"] == 0 and report["regions"] is None
    assert len(report["warnings"]) == 3
    assert (out / "pokes.csv").read_text().count("\n") == 1  # the header, no poke
    import numpy as np

    with np.load(out / "map.npz") as grids:
        assert np.all(grids["region_labels"] == -1)
        assert np.all(np.isnan(grids["modulus_median_pa"]))


def test_a_session_with_usable_pokes_exits_0(tmp_path: Path, synthetic, write_synthetic) -> None:  # type: ignore[no-untyped-def]
    session = write_synthetic(tmp_path / "session", synthetic)
    result = runner.invoke(app, ["map", str(session), "--out", str(tmp_path / "map"),
                                 "--no-figures"])
    assert result.exit_code == 0, result.output


def test_user_text_with_brackets_is_printed_as_written(tmp_path: Path) -> None:
    for name in ("[red]nope[/red", "[bold]x[/bold]"):
        result = runner.invoke(app, ["map", str(tmp_path / name), "--out", str(tmp_path / "o")])
        assert result.exit_code == 2
        assert f"{name}: no such session folder or file" in result.output, result.output
    result = runner.invoke(app, ["world", "show", "[bold]x[/bold].yaml", "--out",
                                 str(tmp_path / "w")])
    assert result.exit_code == 2 and "'[bold]x[/bold].yaml'" in result.output, result.output


def test_a_camera_only_session_maps_on_beta_and_says_so(tmp_path: Path, synthetic,  # type: ignore[no-untyped-def]
                                                        write_synthetic) -> None:
    from dataclasses import replace

    presses = [replace(p, force_travel=None) for p in synthetic.presses]
    session = write_synthetic(tmp_path / "session", replace(synthetic, presses=presses))
    out = tmp_path / "map"
    result = runner.invoke(app, ["map", str(session), "--out", str(out), "--no-figures"])
    assert result.exit_code == 0, result.output
    report = json.loads((out / "report.json").read_text())
    assert report["config"]["exploration"]["field"] == "modulus"  # what the run asked for
    assert report["field"] == "beta" and report["n_pokes"] == 3
    assert report["field_fallback"].startswith("`exploration.field` 'modulus' fell back to 'beta'")
    assert report["field_fallback"] in report["warnings"]
    # said once, though each of the three pokes gives the same reason
    assert result.output.count("fell back to 'beta'") == 1


def test_a_session_with_records_maps_on_the_modulus(tmp_path: Path, synthetic,  # type: ignore[no-untyped-def]
                                                    write_synthetic) -> None:
    session = write_synthetic(tmp_path / "session", synthetic)
    out = tmp_path / "map"
    assert runner.invoke(app, ["map", str(session), "--out", str(out),
                               "--no-figures"]).exit_code == 0
    report = json.loads((out / "report.json").read_text())
    assert report["field"] == "modulus" and report["field_fallback"] is None


@pytest.mark.parametrize("bad", ["nan", "0", "-1"])
def test_map_refuses_a_bad_variance_max_before_reading_the_session(tmp_path: Path,
                                                                   bad: str) -> None:
    out = tmp_path / "result"
    result = CliRunner().invoke(app, ["map", str(tmp_path / "no-session"), "--variance-max", bad,
                                      "--out", str(out)])  # fmt: skip
    assert result.exit_code == 2
    assert "--variance-max must be a finite number > 0" in result.output and not out.exists()
