"""A live robot that fails (raises, hangs, presses elsewhere, exits, is interrupted, returns NaN)
ends `deformap explore --environment` with one line and exit 2 (130 for an interrupt), its journal
keeping every finished poke, and `--resume` continues it to the uninterrupted run's result."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformap.cli import app

runner = CliRunner()

# A deterministic robot: the simulated world (its noise keyed by the press), with the fault that
# fault.txt in the current folder names ("KIND N": at the press N, counted from 0).
ROBOT = '''
import math
import sys
import time
from pathlib import Path

import numpy as np

from deformap.mechanics import TactileContact
from deformap.world import SimulatedWorld, WorldConfig, load_scenario


class Robot:
    def __init__(self, seed):
        self._world = SimulatedWorld(load_scenario("heterogeneous-60-150"),
                                     config=WorldConfig.coarse(), rng=np.random.default_rng(seed))
        fault = Path("fault.txt")
        kind, at = fault.read_text().split() if fault.exists() else ("none", "-1")
        self._fault, self._at, self._presses = kind, int(at), 0

    @property
    def workspace(self):
        return self._world.workspace

    def observe(self):
        if self._fault == "observe":
            raise OSError("camera unplugged")
        return self._world.observe()

    def press(self, target_xy, force_n):
        n, self._presses = self._presses, self._presses + 1
        kind = self._fault if n == self._at else "none"
        if kind == "raise":
            raise RuntimeError("arm fault:\\njoint 3 over current")
        if kind == "hang":
            time.sleep(60)
        if kind == "exit":
            sys.exit(3)
        if kind == "interrupt":
            raise KeyboardInterrupt
        if kind == "nan":
            TactileContact(tip_center=[0.3, 0.2, 0.01], force=[0.0, 0.0, math.nan],
                           tip_radius_m=0.01)
        if kind == "elsewhere":
            x, y = target_xy
            target_xy = (x + 0.03 if x < 0.3 else x - 0.03, y)
        return self._world.press(target_xy, force_n)

    def release(self):
        self._world.release()


def make(seed=0):
    return Robot(seed)
'''

SMALL = ("exploration: {max_pokes: 3, surface: {fit_hyperparameters: false}}\n"
         "robot: {call_timeout_s: 2.0}\n")
ENV = ["explore", "--environment", "fault_robot:make", "--env-arg", "seed=1"]


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    root = tmp_path_factory.mktemp("robot")
    (root / "fault_robot.py").write_text(ROBOT)
    (root / "small.yaml").write_text(SMALL)
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(root)
        mp.syspath_prepend(str(root))
        yield root
    sys.modules.pop("fault_robot", None)


@pytest.fixture(scope="module")
def uninterrupted(folder: Path) -> Path:
    out = folder / "full"
    result = runner.invoke(app, [*ENV, "--config", "small.yaml", "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


def _pokes(out: Path) -> list[dict[str, object]]:
    lines = (out / "journal.jsonl").read_text().splitlines()[1:]
    return [{k: v for k, v in json.loads(line).items() if k != "timings"} for line in lines]


def _assert_same_result(out: Path, reference: Path) -> None:
    assert _pokes(out) == _pokes(reference)
    with np.load(out / "map.npz") as got, np.load(reference / "map.npz") as want:
        assert sorted(got.files) == sorted(want.files)
        for key in want.files:
            np.testing.assert_array_equal(got[key], want[key], err_msg=key)


@pytest.mark.parametrize(("fault", "code", "message"), [
    ("raise 1", 2, r"press\(\(0\.\d+, 0\.\d+\) m, 0\.6 N\) raised RuntimeError: arm fault: "
                   r"joint 3 over current; 1 poke\(s\) kept"),
    ("observe 0", 2, r"observe\(\) raised OSError: camera unplugged; 0 poke\(s\) kept"),
    ("hang 1", 2, r"press\(.*\) did not return within 2 s \(robot.call_timeout_s\)"),
    ("exit 2", 2, r"press\(.*\) called sys.exit\(3\); 2 poke\(s\) kept"),
    ("interrupt 1", 130, r"press\(.*\) raised KeyboardInterrupt; 1 poke\(s\) kept"),
    ("nan 1", 2, r"press\(.*\) raised InvalidArgumentError: `force` must be a \(3,\) array of "
                 r"finite newtons"),
    ("elsewhere 1", 2, r"press\(\((0\.\d+), (0\.\d+)\) m, 0\.6 N\) held the tip at \(0\.\d+, "
                       r"\2\) m, 30\.0 mm from the target \(tolerance 10\.0 mm"),
])
def test_a_failing_robot_stops_in_one_line_and_resumes_to_the_same_result(
        folder: Path, uninterrupted: Path, fault: str, code: int, message: str) -> None:
    import re

    out = folder / fault.replace(" ", "-")
    (folder / "fault.txt").write_text(fault)
    try:
        result = runner.invoke(app, [*ENV, "--config", "small.yaml", "--out", str(out)])
    finally:
        (folder / "fault.txt").unlink()
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.output, result.stderr
    assert lines[0].startswith("error: --environment fault_robot:make: "), lines[0]
    assert re.search(message, lines[0]), lines[0]
    assert f"--resume {out}" in lines[0]
    kept = len(_pokes(out))
    assert _pokes(out) == _pokes(uninterrupted)[:kept]  # every finished poke, as it was
    assert not (out / "report.json").exists()
    if fault.startswith("hang"):  # more time on resume: the folder's config.yaml, robot only
        config = out / "config.yaml"
        config.write_text(config.read_text().replace("call_timeout_s: 2.0", "call_timeout_s: 60"))

    resumed = runner.invoke(app, [*ENV, "--resume", str(out)])
    assert resumed.exit_code == 0, resumed.output
    _assert_same_result(out, uninterrupted)


@pytest.mark.parametrize(("args", "message"), [
    (["--environment", "fault_robot:make", "--env-arg", "seed=2"],
     r"cannot resume .* differs from this one in \['env_args'\]"),
    (["--environment", "fault_robot:other", "--env-arg", "seed=1"],  # checked before it loads
     r"cannot resume .* differs from this one in \['environment'\]"),
    ([], r"cannot resume .* as a simulated run: it explored --environment fault_robot:make"),
])
def test_resume_refuses_another_robot_in_one_line(folder: Path, uninterrupted: Path,
                                                  args: list[str], message: str) -> None:
    import re
    import shutil

    out = folder / "stopped"
    shutil.rmtree(out, ignore_errors=True)
    shutil.copytree(uninterrupted, out)
    journal = out / "journal.jsonl"
    journal.write_text("".join(journal.read_text().splitlines(keepends=True)[:2]))
    result = runner.invoke(app, ["explore", *args, "--resume", str(out)])
    assert result.exit_code == 2, result.output
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert re.search(message, result.stderr.replace("\n", " ")), result.stderr
    assert len(_pokes(out)) == 1  # nothing pressed, nothing written


def test_an_off_target_press_is_kept_with_a_warning_when_the_config_says_so(folder: Path) -> None:
    (folder / "warn.yaml").write_text(
        "exploration: {max_pokes: 2, surface: {fit_hyperparameters: false}}\n"
        "robot: {off_target: warn, target_tolerance_m: 0.005}\n")
    (folder / "fault.txt").write_text("elsewhere 1")
    try:
        result = runner.invoke(app, [*ENV, "--config", "warn.yaml", "--out",
                                     str(folder / "warned")])  # fmt: skip
    finally:
        (folder / "fault.txt").unlink()
    assert result.exit_code == 0, result.output
    assert "30.0 mm from the target (tolerance 5.0 mm" in result.stderr
    assert "kept (robot.off_target: warn)" in result.stderr


def test_ctrl_c_while_the_robot_works_stops_as_cleanly() -> None:
    import _thread
    import threading

    from deformap.run._robot import GuardedEnvironment, RobotConfig, RobotFault

    env = GuardedEnvironment("lab.arm:make", RobotConfig(call_timeout_s=30.0))
    done = threading.Event()

    def slow_press() -> None:
        _thread.interrupt_main()  # as Ctrl-C in the terminal, while the main thread waits
        done.wait(10.0)

    with pytest.raises(RobotFault, match=r"^--environment lab.arm:make: interrupted during "
                                         r"press\(\)$") as info:  # fmt: skip
        env.call("press()", slow_press)
    done.set()
    assert info.value.exit_code == 130
