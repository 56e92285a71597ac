"""Smoke test of the Table I reproduction on a coarse world, one scenario, two pokes: the table is
built from the run's own report and written as JSON and markdown. (All six scenarios run through
the CLI in tests/eval/test_cli_studies.py, marked slow.)"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from deformap.eval import PAPER_TABLE_I, markdown_table
from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.run import RunConfig, reproduce
from deformap.world import WorldConfig

SCENARIOS = ["heterogeneous-150-rigid"]


def test_reproduce_a_subset_of_table_one(tmp_path: Path) -> None:
    base = RunConfig(seed=2, world=WorldConfig.coarse(),
                     exploration=ExplorationConfig(max_pokes=2, strategy="max-variance",
                                                   surface=SurfaceGPConfig(
                                                       fit_hyperparameters=False)))  # fmt: skip
    seen: list[dict[str, Any]] = []
    out = reproduce(tmp_path / "t", base=base, scenarios=SCENARIOS, on_run=seen.append)
    result, tmp_path = out.table, out.folder
    assert result["seed"] == 2 and result["strategy"] == "max-variance"
    assert [r["scenario"] for r in result["rows"]] == SCENARIOS
    assert seen == result["rows"]
    assert json.loads((tmp_path / "table.json").read_text()) == result
    assert (tmp_path / "table.md").read_text() == markdown_table(result)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*SCENARIOS, "table.json",
                                                                 "table.md"])  # fmt: skip
    for row in result["rows"]:
        name = row["scenario"]
        report = json.loads((tmp_path / name / "report.json").read_text())
        assert row["paper"] == PAPER_TABLE_I[name]
        assert row["pokes"] == report["n_pokes"] == 2
        assert row["threshold"] == base.exploration.threshold
        assert row["stop_reason"] == report["stop_reason"] == "max_pokes"
        regions = report["regions"]
        assert row["regions_true"] == regions["true"] == PAPER_TABLE_I[name]["regions"]
        for key in ("found", "accuracy", "mean_iou", "kendall_tau"):
            assert row[key if key != "found" else "regions_found"] == regions[key]
        assert 0.0 < row["accuracy"] <= 1.0
        timings = report["timings"]
        assert row["time_s"] == timings["total_s"] + timings["world_build_s"] > 0
        assert row["max_compute_per_poke_s"] == max(timings["per_poke_compute_s"]) > 0
