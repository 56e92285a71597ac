"""A disk that fills during ``explore`` or ``record-sim`` ends the command with exit code 2 and one
line naming the file and the cause, never a traceback; nothing cut short is left under the file's
name. The failure is injected at the one write path (:mod:`deformap._files`)."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest
from typer.testing import CliRunner

import deformap._files as files_module
from deformap._config import dump_yaml
from deformap._files import is_temporary
from deformap.cli import app
from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.run import RunConfig
from deformap.world import WorldConfig

runner = CliRunner()


@pytest.fixture
def config(tmp_path: Path) -> Path:
    path = tmp_path / "config.yaml"
    dump_yaml(RunConfig(scenario="heterogeneous-60-150", seed=2, world=WorldConfig.coarse(),
                        exploration=ExplorationConfig(
                            max_pokes=1, surface=SurfaceGPConfig(fit_hyperparameters=False))),
              path)  # fmt: skip
    return path


def _full_at(monkeypatch, name: str) -> None:  # type: ignore[no-untyped-def]
    real = files_module.replace_durably

    def full(tmp: Path, path: Path) -> None:
        if path.name == name:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(tmp, path)

    monkeypatch.setattr(files_module, "replace_durably", full)


def _one_error_line(result) -> str:  # type: ignore[no-untyped-def]
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, result.output
    return errors[0]


@pytest.mark.parametrize("name", ["config.yaml", "map.npz"])
def test_explore_on_a_full_disk_exits_2_naming_the_file(tmp_path: Path, monkeypatch, config: Path,  # type: ignore[no-untyped-def]
                                                        name: str) -> None:
    out = tmp_path / "run"
    _full_at(monkeypatch, name)
    result = runner.invoke(app, ["explore", "--config", str(config), "--out", str(out)])
    line = _one_error_line(result)
    assert f"cannot write {str(out / name)!r}: no space left on the device (ENOSPC)" in line
    assert not (out / name).exists()
    assert not [p for p in out.iterdir() if is_temporary(p)]


@pytest.mark.parametrize(("fmt", "name"), [("folder", "observation.pcd"),
                                           ("folder", "session.yaml"),
                                           ("raw-mcap", "robot.mcap")])
def test_record_sim_on_a_full_disk_exits_2_naming_the_file(tmp_path: Path, monkeypatch,  # type: ignore[no-untyped-def]
                                                           config: Path, fmt: str,
                                                           name: str) -> None:
    out = tmp_path / "session"
    _full_at(monkeypatch, name)
    result = runner.invoke(app, ["record-sim", "-s", "heterogeneous-60-150", "--config",
                                 str(config), "--out", str(out), "--format", fmt])  # fmt: skip
    line = _one_error_line(result)
    assert f"cannot write {str(out / name)!r}: no space left on the device (ENOSPC)" in line
    assert not (out / name).exists()
    assert not [p for p in out.iterdir() if is_temporary(p)]
