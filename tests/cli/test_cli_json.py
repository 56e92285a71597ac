"""``--json`` means the same in every command: ``--json FILE`` also writes the command's result as
JSON to FILE; ``--json -`` writes it to stdout alone, the tables going to stderr.

The workflows are replaced by stubs returning a known result, so that these tests check the
command's handling of ``--json`` in milliseconds (the workflows have their own tests).
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from typer.testing import CliRunner

from deformap import eval as evaluation
from deformap import run
from deformap.cli import app

runner = CliRunner()

REGIONS = {"found": 2, "true": 2, "accuracy": 0.9, "mean_iou": 0.8, "kendall_tau": 1.0,
           "class_betas": [0.1, 0.5]}  # fmt: skip
TIMINGS = {"total_s": 1.0, "world_build_s": 0.5, "per_poke_compute_s": [0.2]}
REPORT = {"scenario": "homogeneous-60", "seed": 0, "n_pokes": 1, "stop_reason": "threshold",
          "max_variance": 0.01, "regions": REGIONS, "timings": TIMINGS, "warnings": []}  # fmt: skip
ESTIMATE = {"beta": 0.5, "beta_std": 0.01, "n_roi_points": 100}
STUDY = {"rows": [{"protocol": "force/quadratic", "cluster_size": 3, "hardness_n": None,
                   "beta": 0.0, "beta_std": 0.0, "beta_estimate_std": 0.0, "fit_error_m": 0.001}],
         "monotone": {"force/quadratic": True}}  # fmt: skip
TABLE = {"seed": 0, "strategy": "planned", "rows": []}
SPEED = {"surface_gp": [], "beta_sweep": {"n_beta": 1, "n_particles": 1, "batched_s": 1.0,
                                          "loop_s": 2.0, "speedup": 2.0}}  # fmt: skip
WORLD = {"scenario": "x", "construction_s": 1.0, "n_dofs": 10}
IO = {"n_points": 10, "goal_s": 0.5, "pcd_s": 0.1}
MEMORY = {"surface_gp": [], "beta_estimation": []}
RECORD = {"session_file": "s/session.yaml", "folder": "s", "n_pokes": 2, "format": "folder",
          "live_betas": [0.5, 0.6]}  # fmt: skip


def _stubs(tmp_path: Path) -> dict[str, Any]:
    """(module, name) → stub, and the result each command writes as JSON."""
    out = SimpleNamespace(report=REPORT, folder=tmp_path, session=[1], files=[tmp_path / "a"],
                          study=STUDY, table=TABLE, markdown="| table |")  # fmt: skip
    estimate = SimpleNamespace(report=ESTIMATE, folder=None)
    recorded = run.RecordOutput(session_file=Path(RECORD["session_file"]),
                                folder=Path(RECORD["folder"]), n_pokes=2, format="folder",
                                live_betas=RECORD["live_betas"])  # fmt: skip
    return {
        "explore_scenario": (run, lambda *a, **k: out),
        "map_recorded_session": (run, lambda *a, **k: out),
        "estimate_one_poke": (run, lambda *a, **k: estimate),
        "record_simulation": (run, lambda *a, **k: recorded),
        "run_hardness_study": (run, lambda *a, **k: out),
        "run_cluster_size_study": (run, lambda *a, **k: out),
        "reproduce": (run, lambda *a, **k: out),
        "bench_surface_gp": (evaluation, lambda *a, **k: SPEED["surface_gp"]),
        "bench_beta_sweep": (evaluation, lambda *a, **k: SPEED["beta_sweep"]),
        "bench_world": (evaluation, lambda *a, **k: WORLD),
        "bench_io": (evaluation, lambda *a, **k: IO),
        "bench_memory": (evaluation, lambda *a, **k: MEMORY),
    }


ESTIMATE_ARGS = ["estimate", "--before", "b.pcd", "--after", "a.pcd", "--contact", "0", "0", "0",
                 "--force", "0", "0", "-1", "--tip-radius", "0.01"]  # fmt: skip
COMMANDS = [
    (["explore"], REPORT),
    (["map", "session"], REPORT),
    (ESTIMATE_ARGS, ESTIMATE),
    (["record-sim", "--scenario", "homogeneous-60"], RECORD),
    (["study", "hardness"], STUDY),
    (["study", "cluster-size"], STUDY),
    (["reproduce"], TABLE),
    (["bench", "speed"], SPEED),
    (["bench", "world"], WORLD),
    (["bench", "io"], IO),
    (["bench", "memory"], MEMORY),
]


@pytest.mark.parametrize(("args", "expected"), COMMANDS, ids=lambda v: " ".join(v[:2])
                         if isinstance(v, list) else "")  # fmt: skip
def test_json_file_and_json_stdout(tmp_path: Path, monkeypatch, args: list[str],
                                   expected: dict[str, Any]) -> None:  # type: ignore[no-untyped-def]  # fmt: skip
    for name, (module, stub) in _stubs(tmp_path).items():
        monkeypatch.setattr(module, name, stub)
    target = tmp_path / "deep" / "result.json"
    result = runner.invoke(app, [*args, "--json", str(target)])
    assert result.exit_code == 0, result.output
    assert json.loads(target.read_text()) == expected
    assert f"wrote {target}" in " ".join(result.stdout.split())

    result = runner.invoke(app, [*args, "--json", "-"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout) == expected  # stdout is the JSON alone
    assert result.stderr.strip()  # the human rendering went to stderr


def test_estimate_without_out_writes_its_json_to_stdout(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    for name, (module, stub) in _stubs(tmp_path).items():
        monkeypatch.setattr(module, name, stub)
    result = runner.invoke(app, ESTIMATE_ARGS)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout) == ESTIMATE
    assert result.stdout.count("\n") == 1  # one line, for pipes


def test_a_json_file_that_cannot_be_written_is_one_line(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    for name, (module, stub) in _stubs(tmp_path).items():
        monkeypatch.setattr(module, name, stub)
    (tmp_path / "file").write_text("x")
    result = runner.invoke(app, ["bench", "io", "--json", str(tmp_path / "file" / "io.json")])
    assert result.exit_code == 2
    assert "--json must name a file that can be written" in result.stderr
    assert "Traceback" not in result.output


@pytest.mark.parametrize("where", ["folder", "under-a-file", "unwritable"])
def test_a_json_target_that_cannot_be_written_is_refused_before_the_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, where: str
) -> None:
    ran: list[str] = []
    monkeypatch.setattr(evaluation, "bench_io", lambda *a, **k: ran.append("bench") or {})
    (tmp_path / "afile").write_text("x")
    target = {"folder": tmp_path, "under-a-file": tmp_path / "afile" / "r.json",
              "unwritable": Path("/proc/deformap-none/r.json")}[where]  # fmt: skip
    result = CliRunner().invoke(app, ["bench", "io", "--json", str(target)])
    assert result.exit_code == 2, result.output
    assert "--json must name a file that can be written" in result.output
    assert str(target) in result.output and ran == []
