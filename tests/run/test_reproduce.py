"""Reproducing Table I on a subset of scenarios: one run folder each, and the table."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from deformap.errors import ConfigError
from deformap.eval import PAPER_TABLE_I, markdown_table
from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.msm import ShapeMatchingConfig
from deformap.run import RunConfig, RunHooks, reproduce
from deformap.world import WorldConfig


def test_reproduce_a_subset_writes_a_run_per_scenario_and_the_table(tmp_path: Path) -> None:
    base = RunConfig(
        seed=1,
        world=WorldConfig.coarse(),
        exploration=ExplorationConfig(
            max_pokes=2,
            surface=SurfaceGPConfig(fit_hyperparameters=False),
            shape_matching=ShapeMatchingConfig(n_beta=6, refine=False, max_iter=200),
        ),
    )
    rows, steps = [], []
    out = reproduce(tmp_path / "table", base=base, scenarios=["homogeneous-60"], figures=False,
                    on_run=rows.append, hooks=RunHooks(on_step=steps.append))  # fmt: skip
    assert steps == ["homogeneous-60"] and len(rows) == 1
    table = json.loads((out.folder / "table.json").read_text())
    assert table == out.table and table["rows"] == rows and table["seed"] == 1
    report = json.loads((out.folder / "homogeneous-60" / "report.json").read_text())
    row = rows[0]
    assert row["paper"] == PAPER_TABLE_I["homogeneous-60"]
    assert row["pokes"] == report["n_pokes"] <= 2
    assert row["regions_true"] == report["regions"]["true"] == 1
    assert row["time_s"] == report["timings"]["total_s"] + report["timings"]["world_build_s"]
    assert (out.folder / "table.md").read_text() == markdown_table(table) == out.markdown
    with pytest.raises(ConfigError, match="exists and is not empty"):
        reproduce(out.folder, base=base, scenarios=["homogeneous-60"])


def test_a_scenario_file_runs_in_a_folder_named_by_its_stem_and_twice_is_refused(
    tmp_path: Path,
) -> None:
    scenario = tmp_path / "files" / "bench.yaml"
    scenario.parent.mkdir()
    scenario.write_text("name: bench\nblocks:\n"
                        "  - {name: soft, rect: [0.0, 0.0, 0.6, 0.4], hardness_n: 60}\n")
    base = RunConfig(world=WorldConfig.coarse(),
                     exploration=ExplorationConfig(max_pokes=1,
                                                   surface=SurfaceGPConfig(fit_hyperparameters=False),
                                                   shape_matching=ShapeMatchingConfig(
                                                       n_beta=6, refine=False, max_iter=200)))
    out = reproduce(tmp_path / "t", base=base, scenarios=[str(scenario)], figures=False)
    assert (out.folder / "bench" / "report.json").is_file()
    with pytest.raises(ConfigError, match="each scenario once"):
        reproduce(tmp_path / "t2", base=base, scenarios=[str(scenario), str(scenario)])
    with pytest.raises(ConfigError, match="nope"):
        reproduce(tmp_path / "t3", base=base, scenarios=["nope"])
    assert not (tmp_path / "t2").exists() and not (tmp_path / "t3").exists()
