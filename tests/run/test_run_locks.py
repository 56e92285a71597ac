"""Every command that writes a folder holds its lock (one writer per folder): a folder another
process holds is refused in one line naming that process's PID, before any work; a holder killed
with SIGKILL leaves the folder free (the kernel releases the lock). A world over its budget is
refused before any folder is made."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.errors import ConfigError
from deformap.explore import ExplorationConfig
from deformap.run import RunConfig, RunHooks
from deformap.run._estimate import estimate_one_poke
from deformap.run._explore import explore_scenario
from deformap.run._folder import claim_run_folder
from deformap.run._lock import LOCK_NAME, folder_holder
from deformap.run._record import record_simulation
from deformap.run._reproduce import reproduce
from deformap.run._studies import run_cluster_size_study
from deformap.run._world import show_scenario
from deformap.run._worlds import bench_worlds
from deformap.run._worlds_config import WorldsBenchConfig
from deformap.world import WorldConfig

pytestmark = pytest.mark.skipif(os.name != "posix", reason="folders are locked with fcntl")

_HOLD = """
import sys, time
from pathlib import Path
from deformap.run._lock import lock_run_folder
lock = lock_run_folder(Path(sys.argv[1]))
print("held", flush=True)
time.sleep(60)
"""


def _holder(folder: Path) -> subprocess.Popen[str]:
    """Another process holding ``folder``'s lock (it has said so when this returns)."""
    folder.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen([sys.executable, "-c", _HOLD, str(folder)], stdout=subprocess.PIPE,
                            text=True, env=env)  # fmt: skip
    assert proc.stdout is not None and proc.stdout.readline() == "held\n"
    return proc


@pytest.fixture
def held(tmp_path: Path) -> Iterator[tuple[Path, int]]:
    folder = tmp_path / "out"
    proc = _holder(folder)
    try:
        yield folder, proc.pid
    finally:
        proc.kill()
        proc.wait()


def _config() -> RunConfig:
    return RunConfig(scenario="heterogeneous-60-150", seed=1, world=WorldConfig.coarse(),
                     exploration=ExplorationConfig(max_pokes=2))


def _estimate(out: Path) -> Any:
    from deformap.cloud import PointCloud
    from deformap.cloud.io import write_cloud

    xy = np.random.default_rng(0).uniform(0.0, 0.1, (400, 2))
    before = PointCloud(np.column_stack([xy, np.full(len(xy), 0.05)]))
    write_cloud(out.parent / "before.pcd", before)
    write_cloud(out.parent / "after.pcd", before)
    return estimate_one_poke(before=out.parent / "before.pcd", after=out.parent / "after.pcd",
                             tip_center=[0.05, 0.05, 0.06], force=[0.0, 0.0, -1.0],
                             tip_radius_m=0.01, config=_config(), out=out)  # fmt: skip


COMMANDS: dict[str, Callable[[Path], Any]] = {
    "explore": lambda out: explore_scenario(_config(), out, figures=False),
    "explore --resume": lambda out: explore_scenario(_config(), out, resume=True, figures=False),
    "record-sim": lambda out: record_simulation(_config(), out),
    "estimate": _estimate,
    "reproduce": lambda out: reproduce(out, base=_config(), scenarios=["heterogeneous-60-150"]),
    "study cluster-size": lambda out: run_cluster_size_study(out, coarse=True),
    "world": lambda out: show_scenario("heterogeneous-60-150", out, coarse=True),
    "bench worlds": lambda out: bench_worlds(WorldsBenchConfig(worlds=1, coarse=True), out),
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_folder_held_by_another_process_is_refused_naming_its_pid(
        held: tuple[Path, int], command: str) -> None:
    folder, pid = held
    with pytest.raises(ConfigError) as caught:
        COMMANDS[command](folder)
    message = str(caught.value)
    assert f"is in use by another deformap process (PID {pid})" in message, message
    assert "\n" not in message
    assert os.listdir(folder) == [LOCK_NAME]  # nothing written beside the holder's lock


def test_a_holder_killed_with_sigkill_leaves_the_folder_free(tmp_path: Path) -> None:
    folder = tmp_path / "out"
    proc = _holder(folder)
    assert folder_holder(folder) == str(proc.pid)
    with pytest.raises(ConfigError, match=rf"\(PID {proc.pid}\)"):
        claim_run_folder(folder)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert folder_holder(folder) is None
    assert os.listdir(folder) == [LOCK_NAME]  # the lock file stays; its lock went with the process
    with claim_run_folder(folder) as lock:  # a new run takes it
        assert lock.held and folder_holder(folder) == str(os.getpid())
    assert os.listdir(folder) == []


class Stop(Exception):
    """Ends a command once it has started its work."""


def _started(folder: Path) -> RunHooks:
    def start(info: Any) -> None:
        raise Stop(folder_holder(folder))

    return RunHooks(on_start=start)


WORKING: dict[str, Callable[[Path, RunHooks], Any]] = {
    "record-sim": lambda out, hooks: record_simulation(_config(), out, hooks=hooks),
    "reproduce": lambda out, hooks: reproduce(out, base=_config(),
                                              scenarios=["heterogeneous-60-150"], hooks=hooks),
    "study cluster-size": lambda out, hooks: run_cluster_size_study(out, coarse=True, hooks=hooks),
    "world": lambda out, hooks: show_scenario("heterogeneous-60-150", out, coarse=True,
                                              hooks=hooks),
    "bench worlds": lambda out, hooks: bench_worlds(WorldsBenchConfig(worlds=1, coarse=True), out,
                                                    hooks=hooks),
}


@pytest.mark.parametrize("command", sorted(WORKING))
def test_each_command_holds_its_folder_while_it_works(tmp_path: Path, command: str) -> None:
    out = tmp_path / "out"
    with pytest.raises(Stop) as stopped:
        WORKING[command](out, _started(out))
    assert stopped.value.args == (str(os.getpid()),)  # locked by this process as it works
    assert LOCK_NAME not in os.listdir(out)  # and released when it ends, however it ends


def test_estimate_holds_its_folder_while_it_works(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "out"

    def estimate_poke(*args: Any, **kwargs: Any) -> Any:
        raise Stop(folder_holder(out))

    monkeypatch.setattr("deformap.run._estimate.estimate_poke", estimate_poke)
    with pytest.raises(Stop) as stopped:
        _estimate(out)
    assert stopped.value.args == (str(os.getpid()),)


@pytest.mark.parametrize("command", ["explore", "record-sim"])
def test_a_world_over_its_budget_leaves_no_folder(tmp_path: Path, command: str) -> None:
    import dataclasses

    config = dataclasses.replace(_config(), world=WorldConfig(element_size_m=0.001))
    out = tmp_path / "run"
    with pytest.raises(SettingError, match="element_size_m"):
        if command == "explore":
            explore_scenario(config, out, figures=False)
        else:
            record_simulation(config, out)
    assert not out.exists()


def test_a_holder_that_has_not_yet_written_its_pid_is_waited_for(tmp_path: Path) -> None:
    """Two runs started at once: the second may find the lock taken before the first has written
    its PID into the file; it waits for the PID instead of saying "unknown"."""
    import fcntl
    import threading

    folder = tmp_path / "out"
    folder.mkdir()
    fd = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        # as a new holder does, a moment later: a thread's own open file, so the lock conflicts
        threading.Timer(0.1, os.pwrite, (fd, b"4242\n", 0)).start()
        with pytest.raises(ConfigError, match=r"is in use by another deformap process \(PID 4242\)"):
            claim_run_folder(folder, resume=True)
    finally:
        os.close(fd)
