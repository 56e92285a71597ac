"""A whole run on a coarse simulated world: the report, the figures, and resuming a killed run."""

from __future__ import annotations

import json

import pytest

from deformap.eval import RunConfig, run_experiment
from deformap.explore import ExplorationConfig, SurfaceGPConfig, read_journal
from deformap.world import WorldConfig


class Killed(Exception):
    """Stands for the process being killed right after a poke was journalled."""


def _config() -> RunConfig:
    return RunConfig(
        scenario="heterogeneous-60-150",
        seed=4,
        world=WorldConfig.coarse(),
        exploration=ExplorationConfig(
            max_pokes=3,
            threshold=1e-3,
            strategy="max-variance",
            surface=SurfaceGPConfig(fit_hyperparameters=False),
        ),
    )


@pytest.fixture(scope="module")
def full_run(tmp_path_factory):  # type: ignore[no-untyped-def]
    out = tmp_path_factory.mktemp("runs") / "full"
    return run_experiment(_config(), out)


def test_report_and_figures(full_run) -> None:  # type: ignore[no-untyped-def]
    folder = full_run.folder
    report = json.loads((folder / "report.json").read_text())
    assert report["n_pokes"] == 3 == len(report["pokes"])
    assert report["stop_reason"] == "max_pokes"
    for poke in report["pokes"]:
        assert 0.0 <= poke["beta"] < 1.0 and poke["beta_std"] > 0
        assert {"target_xy", "contact", "force_n", "max_variance_after", "timings"} <= set(poke)
    assert set(report["regions"]) >= {"found", "true", "accuracy", "mean_iou", "kendall_tau"}
    assert report["regions"]["true"] == 2
    assert {"total_s", "per_poke_s"} <= set(report["timings"])
    assert (folder / "config.yaml").exists() and (folder / "map.png").stat().st_size > 10_000
    assert sorted(p.name for p in folder.glob("poke-*.png")) == [
        "poke-01.png",
        "poke-02.png",
        "poke-03.png",
    ]
    variances = [p["max_variance_after"] for p in report["pokes"]]
    assert variances[-1] <= variances[0]


def test_a_killed_run_resumes_to_the_same_result(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "killed"

    def kill(poke) -> None:  # type: ignore[no-untyped-def]
        if poke.record["index"] == 1:
            raise Killed

    with pytest.raises(Killed):
        run_experiment(_config(), out, on_poke=kill, figures=False)
    journal = out / "journal.jsonl"
    assert len(read_journal(journal).pokes) == 2
    with open(journal, "a") as fh:  # and the kill cut a third line mid-write
        fh.write('{"kind": "poke", "index": 2, "be')
    resumed = run_experiment(_config(), out, resume=True, figures=False).report
    full = full_run.report
    assert [p["target_xy"] for p in resumed["pokes"]] == [p["target_xy"] for p in full["pokes"]]
    assert [p["beta"] for p in resumed["pokes"]] == [p["beta"] for p in full["pokes"]]
    assert resumed["regions"] == full["regions"]
    assert len(read_journal(journal).pokes) == 3


def test_resume_refuses_a_different_configuration(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    from deformap.errors import ConfigError

    other = RunConfig(**{**_config().__dict__, "seed": 5})
    with pytest.raises(ConfigError, match="differs from this one"):
        run_experiment(other, full_run.folder, resume=True, figures=False)
