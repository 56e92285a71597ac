"""A whole run on a coarse simulated world: the report, the figures, and resuming a killed run.

One test kills a real ``deformap explore`` process with SIGKILL mid-run and resumes it.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import deformap
from deformap._config import dump_yaml
from deformap.errors import ConfigError, FileFormatError
from deformap.explore import JOURNAL_NAME, ExplorationConfig, SurfaceGPConfig, read_journal
from deformap.run import RunConfig, RunHooks, explore_scenario, load_run_config
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
    return explore_scenario(_config(), out)


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


def test_the_maps_as_numbers(full_run) -> None:  # type: ignore[no-untyped-def]
    import csv

    import numpy as np

    folder, result = full_run.folder, full_run.result
    with np.load(folder / "map.npz") as grids:  # no pickle needed
        assert str(grids["frame"]) == "world" and str(grids["field"]) == result.map_field_name
        ny, nx = grids["ys_m"].size, grids["xs_m"].size
        for name in ("beta_mean", "beta_std", "modulus_median_pa", "log_modulus_mean",
                     "log_modulus_std", "region_labels"):
            assert grids[name].shape == (ny, nx), name
        np.testing.assert_array_equal(grids["beta_mean"], result.beta_field.mean)
        np.testing.assert_array_equal(grids["region_labels"], result.regions.labels)
        assert np.all(np.isfinite(grids["modulus_median_pa"]))  # the world gives records
        np.testing.assert_allclose(grids["modulus_median_pa"],
                                   np.exp(grids["log_modulus_mean"]))
    rows = list(csv.DictReader((folder / "pokes.csv").open()))
    assert [int(r["poke"]) for r in rows] == [p.record.index + 1 for p in result.pokes]
    for row, poke in zip(rows, result.pokes, strict=True):
        assert float(row["beta"]) == poke.record.beta
        assert float(row["contact_x_m"]) == poke.record.contact_xy[0]
        assert row["purpose"] == poke.record.purpose and row["region"] != ""
        stiffness = poke.record.stiffness
        assert stiffness is not None and row["rigid"] == str(stiffness.rigid)
        if not stiffness.rigid:
            assert float(row["modulus_pa"]) == stiffness.modulus_pa


def _run_killed_after_two_pokes(out: Path) -> None:
    """Start the test run in ``out`` and kill it right after its second poke was journalled."""

    def kill(poke) -> None:  # type: ignore[no-untyped-def]
        if poke.index == 1:
            raise Killed

    with pytest.raises(Killed):
        explore_scenario(_config(), out, hooks=RunHooks(on_poke=kill), figures=False)


def test_a_killed_run_resumes_to_the_same_result(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "killed"
    _run_killed_after_two_pokes(out)
    journal = out / "journal.jsonl"
    assert len(read_journal(journal).pokes) == 2
    with open(journal, "a") as fh:  # and the kill cut a third line mid-write
        fh.write('{"kind": "poke", "index": 2, "be')
    resumed = explore_scenario(_config(), out, resume=True, figures=False).report
    full = full_run.report
    assert [p["target_xy"] for p in resumed["pokes"]] == [p["target_xy"] for p in full["pokes"]]
    assert [p["beta"] for p in resumed["pokes"]] == [p["beta"] for p in full["pokes"]]
    assert resumed["regions"] == full["regions"]
    assert len(read_journal(journal).pokes) == 3


def test_a_run_killed_before_its_journal_existed_resumes_from_poke_one(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    # Regression: the journal used to be created before config.yaml, so a SIGKILL in between left
    # a folder that `explore --resume` could not read and a fresh run refused as occupied.
    out = tmp_path / "early"
    out.mkdir()
    dump_yaml(_config(), out / "config.yaml")  # what a kill right after the first write leaves
    (out / "journal.tmp").write_text('{"kind": "hea')
    other = RunConfig(**{**_config().__dict__, "seed": 5})
    with pytest.raises(ConfigError, match=r"its config\.yaml differs"):
        explore_scenario(other, out, resume=True, figures=False)
    resumed = explore_scenario(_config(), out, resume=True, figures=False).report
    assert [p["beta"] for p in resumed["pokes"]] == [p["beta"] for p in full_run.report["pokes"]]
    assert len(read_journal(out / JOURNAL_NAME).pokes) == 3


def test_a_run_journalled_before_a_config_field_existed_resumes(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    # A run begun before `region_labels` and `boundary_pokes` existed: its journal header and
    # config.yaml lack them. Read at their defaults (the behaviour before them) it is this run.
    out = tmp_path / "older"
    _run_killed_after_two_pokes(out)
    journal = out / JOURNAL_NAME
    lines = journal.read_text().splitlines()
    header = json.loads(lines[0])

    def with_header(header: dict) -> None:  # type: ignore[type-arg]
        journal.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")

    for key in ("region_labels", "boundary_pokes"):
        del header["config"]["exploration"][key]
    with_header(header)
    resumed = explore_scenario(_config(), out, resume=True, figures=False).report
    assert [p["beta"] for p in resumed["pokes"]] == [p["beta"] for p in full_run.report["pokes"]]
    # a real difference in such a header is still refused
    header["config"]["seed"] = 5
    with_header(header)
    with pytest.raises(ConfigError, match="differs from this one"):
        explore_scenario(_config(), out, resume=True, figures=False)


@pytest.mark.parametrize("edit", ["repeat", "drop", "swap"])
def test_a_journal_whose_poke_lines_are_not_in_order_is_refused_on_resume(
    tmp_path: Path, edit: str
) -> None:
    out = tmp_path / "killed"
    _run_killed_after_two_pokes(out)
    journal = out / JOURNAL_NAME
    header, first, second = journal.read_text().splitlines()
    lines = {"repeat": [first, first, second], "drop": [second],
             "swap": [second, first]}[edit]  # fmt: skip
    journal.write_text("\n".join([header, *lines]) + "\n")
    got = {"repeat": 0, "drop": 1, "swap": 1}[edit]
    where = {"repeat": 2, "drop": 1, "swap": 1}[edit]
    with pytest.raises(FileFormatError, match=rf"poke line {where} must hold poke index "
                       rf"{where - 1}; got {got} \(a line repeated, missing or out of order\)"):
        explore_scenario(_config(), out, resume=True, figures=False)


def test_a_killed_and_resumed_run_has_every_poke_figure(tmp_path: Path, full_run) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "killed"

    def kill(poke) -> None:  # type: ignore[no-untyped-def]
        if poke.index == 1:
            raise Killed

    with pytest.raises(Killed):
        explore_scenario(_config(), out, hooks=RunHooks(on_poke=kill))
    # drawn as the pokes were made: the kill keeps them
    assert sorted(p.name for p in out.glob("poke-*.png")) == ["poke-01.png", "poke-02.png"]
    (out / "poke-02.png").unlink()  # as if killed between poke 2's journal line and its figure
    resumed = explore_scenario(_config(), out, resume=True)
    assert sorted(p.name for p in out.glob("poke-*.png")) == [
        "poke-01.png", "poke-02.png", "poke-03.png"]
    assert (out / "poke-02.png").stat().st_size > 10_000
    assert [p["beta"] for p in resumed.report["pokes"]] == [
        p["beta"] for p in full_run.report["pokes"]]


def test_resume_refuses_a_different_configuration(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    other = RunConfig(**{**_config().__dict__, "seed": 5})
    with pytest.raises(ConfigError, match="differs from this one"):
        explore_scenario(other, full_run.folder, resume=True, figures=False)


def _journalled_pokes(path: Path) -> list[str]:
    """The complete poke lines of a journal (a line cut mid-write is not complete)."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return []
    complete = text.split("\n")[:-1]
    return [line for line in complete if json.loads(line).get("kind") == "poke"]


def _deformap(*args: str) -> list[str]:
    return [sys.executable, "-m", "deformap", *args]


def _child_env() -> dict[str, str]:
    """The child imports this deformap (the tree under test), single-threaded like the suite."""
    src = str(Path(deformap.__file__).resolve().parents[1])
    path = os.pathsep.join(p for p in (src, os.environ.get("PYTHONPATH")) if p)
    return {**os.environ, "PYTHONPATH": path, "OMP_NUM_THREADS": "1"}


def _kill_after_a_poke(config_file: Path, out: Path, *, timeout_s: float = 120.0) -> list[str]:
    """Run `deformap explore` and SIGKILL it once 1 or 2 pokes are journalled; return those lines.

    Returns an empty list when the run got past its second poke (or ended) before the kill landed,
    as a starved poller might let it, so that the caller can try again.
    """
    journal = out / JOURNAL_NAME
    log = out.with_suffix(".log")
    with open(log, "wb") as sink:  # a file, not a pipe: a full pipe would stall the child
        child = subprocess.Popen(
            _deformap("explore", "--config", str(config_file), "--out", str(out)),
            env=_child_env(),
            stdout=sink,
            stderr=subprocess.STDOUT,
        )
    try:
        deadline = time.monotonic() + timeout_s
        while not _journalled_pokes(journal):
            if child.poll() is not None:
                raise AssertionError(f"explore ended before its first poke:\n{log.read_text()}")
            if time.monotonic() > deadline:
                raise AssertionError(f"no poke journalled within {timeout_s:.0f} s")
            time.sleep(0.005)
        os.kill(child.pid, signal.SIGKILL)
        killed = child.wait(timeout=30) == -signal.SIGKILL
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    kept = _journalled_pokes(journal)
    return kept if killed and len(kept) < 3 else []


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL (POSIX)")
def test_a_run_killed_with_sigkill_resumes_to_the_same_result(tmp_path, full_run) -> None:  # type: ignore[no-untyped-def]
    config_file = tmp_path / "config.yaml"
    dump_yaml(_config(), config_file)
    assert load_run_config(config_file) == _config()  # the CLI runs what full_run ran
    for attempt in range(3):
        out = tmp_path / f"killed-{attempt}"
        kept = _kill_after_a_poke(config_file, out)
        if kept:
            break
        print(f"attempt {attempt}: three pokes were journalled before SIGKILL landed")
    else:
        pytest.fail("the run finished its pokes before SIGKILL landed, three times")
    assert not (out / "report.json").exists()

    resumed = subprocess.run(
        _deformap("explore", "--resume", str(out)),
        env=_child_env(),
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert resumed.returncode == 0, resumed.stderr
    report = json.loads((out / "report.json").read_text())
    full = json.loads((full_run.folder / "report.json").read_text())
    assert report["config"] == full["config"]
    assert [p["target_xy"] for p in report["pokes"]] == [p["target_xy"] for p in full["pokes"]]
    assert [p["beta"] for p in report["pokes"]] == [p["beta"] for p in full["pokes"]]
    assert report["regions"] == full["regions"]
    # Nothing journalled before the kill was lost or rewritten: those lines lead the journal.
    after = _journalled_pokes(out / JOURNAL_NAME)
    assert len(after) == 3 and after[: len(kept)] == kept
    assert [json.loads(line)["beta"] for line in kept] == [
        p["beta"] for p in report["pokes"][: len(kept)]
    ]


def test_each_poke_figure_draws_the_simulated_dent_at_its_beta(
    full_run, tmp_path: Path, monkeypatch: pytest.MonkeyPatch  # type: ignore[no-untyped-def]
) -> None:
    import numpy as np
    from scipy.spatial import cKDTree

    import deformap.viz
    from deformap.run._figures import write_poke_figure

    drawn: dict[str, object] = {}
    real = deformap.viz.plot_poke

    def spy(**kwargs: object) -> object:
        drawn.update(kwargs)
        return real(**kwargs)

    monkeypatch.setattr(deformap.viz, "plot_poke", spy)
    for poke in full_run.result.pokes:
        dent, record = poke.dent, poke.record
        surface = poke.estimate.surface
        assert surface.shape == (*dent.rest_z.shape, 3)
        # the body kept is β̂'s: its matching error is E(β̂) of the record
        gx, gy = np.meshgrid(dent.roi_xs, dent.roi_ys)
        observed = np.column_stack([gx.ravel(), gy.ravel(), dent.deformed_z.ravel()])
        error = cKDTree(observed).query(surface.reshape(-1, 3))[0].mean()
        assert error == pytest.approx(record.errors[record.betas.index(record.beta)], rel=1e-6)
        path = write_poke_figure(tmp_path, poke)
        assert path.exists()
        assert np.array_equal(drawn["simulated_z"], surface[..., 2])


def test_a_bad_variance_max_is_refused_before_any_folder(tmp_path: Path) -> None:
    from deformap.errors import InvalidArgumentError

    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InvalidArgumentError, match="`variance_max` must be"):
            explore_scenario(_config(), tmp_path / "run", variance_max=bad)
    assert not (tmp_path / "run").exists()
