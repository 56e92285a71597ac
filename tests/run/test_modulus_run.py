"""A whole run on a coarse simulated world with the map on the modulus field (issue 13, item 3):
it explores to the end, its regions are the modulus field's, ``report.json`` holds the field, and
a killed run resumes to the same field."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from deformap.explore import ExplorationConfig, SurfaceGPConfig, field_settings
from deformap.run import RunConfig, RunHooks, explore_scenario
from deformap.world import WorldConfig


class Killed(Exception):
    """Stands for the process being killed right after a poke was journalled."""


def _config(field: str) -> RunConfig:
    return RunConfig(
        scenario="heterogeneous-60-150",
        seed=4,
        world=WorldConfig.coarse(),
        exploration=ExplorationConfig(
            max_pokes=3, threshold=1e-3, strategy="max-variance", field=field,  # type: ignore[arg-type]
            surface=SurfaceGPConfig(fit_hyperparameters=False),
        ),
    )  # fmt: skip


@pytest.fixture(scope="module")
def modulus_run(tmp_path_factory):  # type: ignore[no-untyped-def]
    return explore_scenario(_config("modulus"), tmp_path_factory.mktemp("runs") / "modulus")


def test_field_modulus_explores_to_the_end_and_its_regions_use_the_modulus(modulus_run) -> None:  # type: ignore[no-untyped-def]
    report = json.loads((modulus_run.folder / "report.json").read_text())
    assert report["n_pokes"] == 3 and report["stop_reason"] == "max_pokes"
    assert report["field"] == "modulus"
    config = _config("modulus").exploration
    assert report["threshold"] == pytest.approx(field_settings(config).threshold)
    field = report["modulus_field"]
    assert field["n_used"] == 3
    assert report["max_variance"] == report["pokes"][-1]["max_variance_after"]
    assert report["max_variance"] == pytest.approx(field["max_variance"])
    regions = report["regions"]
    # the classes are on the ln E axis (ln Pa of foams: 7 to 14), not β's [0, 1]
    logs = [p["log_modulus_ln_pa"] for p in field["pokes"]]
    assert all(np.log(1e3) < v < np.log(1e6) for v in regions["class_values"])
    assert min(logs) <= min(regions["class_values"]) <= max(regions["class_values"]) <= max(logs)
    medians = regions["class_modulus_median_pa"]
    assert len(medians) == len(regions["class_values"]) == len(regions["class_betas"])
    assert all(1e3 < m < 1e6 for m in medians)
    assert regions["true"] == 2 and regions["found"] >= 1
    assert (modulus_run.folder / "map.png").stat().st_size > 10_000


def test_report_json_holds_the_modulus_field_on_the_grid_with_units(modulus_run) -> None:  # type: ignore[no-untyped-def]
    field = modulus_run.report["modulus_field"]
    assert {"units", "xs_m", "ys_m", "log_mean_ln_pa", "log_std", "max_variance", "n_used",
            "pokes"} <= set(field)  # fmt: skip
    assert field["units"]["log_mean_ln_pa"].startswith("ln Pa")
    mean, std = np.array(field["log_mean_ln_pa"]), np.array(field["log_std"])
    assert mean.shape == std.shape == (len(field["ys_m"]), len(field["xs_m"]))
    assert np.all(std > 0) and np.all(np.isfinite(mean))
    for poke, reading in zip(modulus_run.report["pokes"], field["pokes"], strict=True):
        assert reading["used"] and reading["index"] == poke["index"]
        assert np.exp(reading["log_modulus_ln_pa"]) == pytest.approx(
            poke["stiffness"]["modulus_pa"])


def test_the_beta_map_reports_the_modulus_field_too(tmp_path: Path) -> None:
    report = explore_scenario(_config("beta"), tmp_path / "beta", figures=False).report
    assert report["field"] == "beta" and report["threshold"] == 1e-3
    assert report["modulus_field"]["n_used"] == 3
    assert all(0.0 <= v <= 1.0 for v in report["regions"]["class_values"])
    assert report["regions"]["class_values"] == report["regions"]["class_betas"]


def test_a_killed_run_resumes_to_the_same_modulus_field(tmp_path: Path, modulus_run) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "killed"

    def kill(poke) -> None:  # type: ignore[no-untyped-def]
        if poke.index == 1:
            raise Killed

    with pytest.raises(Killed):
        explore_scenario(_config("modulus"), out, hooks=RunHooks(on_poke=kill), figures=False)
    resumed = explore_scenario(_config("modulus"), out, resume=True, figures=False).report
    full = modulus_run.report
    assert [p["target_xy"] for p in resumed["pokes"]] == [p["target_xy"] for p in full["pokes"]]
    assert resumed["modulus_field"] == full["modulus_field"]
    assert resumed["regions"] == full["regions"]
