"""When the machine refuses a write: a full disk, a read-only file system, a quota, no permission.

Every write of a run goes through :mod:`deformap._files`: the failure is one
:class:`FileWriteError` line naming the file and the cause, nothing half-written is left under a
final name, and the journal stays resumable. The failures are injected (an ``OSError`` from the
one write path), since the tests may not run as root; as root, where a tmpfs can be mounted, one
test fills a real one.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

import deformap._files as files_module
import deformap.explore._journal as journal_module
from deformap._config import dump_yaml
from deformap._files import atomic_path, is_temporary, write_text_atomically
from deformap.errors import DeformapError, FileWriteError
from deformap.explore import JOURNAL_NAME, ExplorationConfig, SurfaceGPConfig, read_journal
from deformap.explore._journal import Journal
from deformap.run import RunConfig, RunHooks, explore_scenario
from deformap.world import WorldConfig

CAUSES = {
    errno.ENOSPC: "no space left on the device (ENOSPC)",
    errno.EROFS: "the file system is read-only (EROFS)",
    errno.EDQUOT: "the disk quota is exceeded (EDQUOT)",
    errno.EACCES: "permission denied (EACCES)",
    errno.EPERM: "operation not permitted (EPERM)",
}


def _refuse(code: int):  # type: ignore[no-untyped-def]
    def refused(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise OSError(code, os.strerror(code))

    return refused


def _config() -> RunConfig:
    return RunConfig(
        scenario="heterogeneous-60-150", seed=4, world=WorldConfig.coarse(),
        exploration=ExplorationConfig(max_pokes=3, threshold=1e-3, strategy="max-variance",
                                      surface=SurfaceGPConfig(fit_hyperparameters=False)),
    )  # fmt: skip


class Killed(Exception):
    """Stands for the process being killed right after a poke was journalled."""


@pytest.fixture(scope="module")
def full_run(tmp_path_factory):  # type: ignore[no-untyped-def]
    return explore_scenario(_config(), tmp_path_factory.mktemp("runs") / "full", figures=False)


def _killed_after_two_pokes(out: Path) -> None:
    def kill(poke) -> None:  # type: ignore[no-untyped-def]
        if poke.index == 1:
            raise Killed

    with pytest.raises(Killed):
        explore_scenario(_config(), out, hooks=RunHooks(on_poke=kill), figures=False)


@pytest.mark.parametrize("code", sorted(CAUSES))
def test_a_refused_write_is_one_line_naming_the_file_and_the_cause(tmp_path: Path, monkeypatch,  # type: ignore[no-untyped-def]
                                                                   code: int) -> None:
    path = tmp_path / "report.json"
    write_text_atomically(path, "old")
    monkeypatch.setattr(files_module, "replace_durably", _refuse(code))
    with pytest.raises(FileWriteError) as caught:
        write_text_atomically(path, "new")
    assert str(caught.value) == f"cannot write {str(path)!r}: {CAUSES[code]}"
    assert caught.value.errno == code and isinstance(caught.value, (DeformapError, OSError))
    assert path.read_text() == "old"  # nothing half-written under the final name
    assert os.listdir(tmp_path) == ["report.json"]  # and no temporary left


def test_a_writer_that_runs_out_of_space_mid_file_leaves_the_old_file(tmp_path: Path) -> None:
    path = tmp_path / "map.npz"
    path.write_bytes(b"old map")
    with pytest.raises(FileWriteError, match=r"map\.npz': no space left on the device"):
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            fh.write(b"half a m")
            raise OSError(errno.ENOSPC, "No space left on device")
    assert path.read_bytes() == b"old map"
    assert os.listdir(tmp_path) == ["map.npz"]


def test_a_journal_line_cut_by_a_full_disk_is_removed_and_the_journal_resumes(
        tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    journal = Journal.create(tmp_path, {"run": 1})
    journal.append({"index": 0, "beta": 0.5})
    real_write = os.write

    def half_then_full(fd: int, data) -> int:  # type: ignore[no-untyped-def]
        real_write(fd, bytes(data[: len(data) // 2]))
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(journal_module.os, "write", half_then_full)
    with pytest.raises(FileWriteError, match=rf"{JOURNAL_NAME}': no space left on the device"):
        journal.append({"index": 1, "beta": 0.6})
    monkeypatch.undo()
    contents = read_journal(tmp_path / JOURNAL_NAME)
    assert contents.broken_line is None and contents.pokes == [
        {"kind": "poke", "index": 0, "beta": 0.5}]
    Journal.resume(tmp_path, {"run": 1})[0].append({"index": 1, "beta": 0.6})
    assert [p["index"] for p in read_journal(tmp_path / JOURNAL_NAME).pokes] == [0, 1]


@pytest.mark.parametrize("failing", ["map.npz", "report.json", "poke-02.png"])
def test_a_run_whose_disk_fills_says_how_to_resume_and_resumes(tmp_path: Path, monkeypatch,  # type: ignore[no-untyped-def]
                                                               full_run, failing: str) -> None:
    out = tmp_path / "run"
    real = files_module.replace_durably

    def full_at(tmp: Path, path: Path) -> None:
        if path.name == failing:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(tmp, path)

    monkeypatch.setattr(files_module, "replace_durably", full_at)
    with pytest.raises(FileWriteError) as caught:
        explore_scenario(_config(), out, figures=failing.endswith(".png"))
    kept = 2 if failing == "poke-02.png" else 3  # a poke is journalled before its figure
    assert str(caught.value) == (
        f"cannot write {str(out / failing)!r}: no space left on the device (ENOSPC); {kept} "
        f"poke(s) kept in the journal: once that is fixed, continue with `deformap explore "
        f"--resume {out}`")
    assert not (out / failing).exists()
    assert not [p for p in out.iterdir() if is_temporary(p)]
    assert not (out / ".deformap.lock").exists()  # the lock goes with the run
    monkeypatch.undo()
    resumed = explore_scenario(_config(), out, resume=True, figures=False).report
    assert [p["beta"] for p in resumed["pokes"]] == [p["beta"] for p in full_run.report["pokes"]]
    assert json.loads((out / "report.json").read_text())["regions"] == full_run.report["regions"]


def test_temporaries_of_an_interrupted_write_are_removed_at_resume(tmp_path: Path) -> None:
    out = tmp_path / "killed"
    _killed_after_two_pokes(out)
    left = [out / ".map.0123abcd.tmp.npz", out / ".config.89abcdef.tmp.yaml",
            out / ".poke-03.deadbeef.tmp.png"]
    for path in left:
        path.write_bytes(b"half")
    mine = out / ".notes.tmp.txt"  # not a name deformap writes: the user's, kept
    mine.write_text("keep")
    explore_scenario(_config(), out, resume=True, figures=False)
    assert not any(p.exists() for p in left)
    assert mine.read_text() == "keep"
    assert (out / "map.npz").is_file()


def test_an_empty_journal_is_a_run_killed_before_its_header_and_starts_over(
        tmp_path: Path, full_run) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "early"
    out.mkdir()
    dump_yaml(_config(), out / "config.yaml")
    (out / JOURNAL_NAME).write_bytes(b"")  # killed right after creating it
    resumed = explore_scenario(_config(), out, resume=True, figures=False).report
    assert [p["beta"] for p in resumed["pokes"]] == [p["beta"] for p in full_run.report["pokes"]]
    assert len(read_journal(out / JOURNAL_NAME).pokes) == 3


def test_resuming_on_a_read_only_file_system_is_one_line_before_any_work(
        tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "killed"
    _killed_after_two_pokes(out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real_open = os.open

    def read_only(path, flags, *args, **kwargs):  # type: ignore[no-untyped-def]
        if flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
            raise OSError(errno.EROFS, "Read-only file system", str(path))
        return real_open(path, flags, *args, **kwargs)

    def no_world(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("the world was built before the refusal")

    monkeypatch.setattr(os, "open", read_only)
    monkeypatch.setattr("deformap.run._explore.SimulatedWorld", no_world)
    with pytest.raises(FileWriteError) as caught:
        explore_scenario(_config(), out, resume=True, figures=False)
    monkeypatch.undo()
    assert str(caught.value) == (f"cannot write in run folder {str(out)!r}: the file system is "
                                 "read-only (EROFS)")
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def _mount_tmpfs(where: Path, size: str) -> bool:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    where.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                          capture_output=True, check=False)  # fmt: skip
    return done.returncode == 0


@pytest.mark.skipif(os.name != "posix", reason="a tmpfs needs Linux")
def test_a_real_full_tmpfs_then_read_only_then_room(tmp_path: Path, full_run) -> None:  # type: ignore[no-untyped-def]
    disk = tmp_path / "disk"
    if not _mount_tmpfs(disk, "48k"):
        pytest.skip("needs root and a mountable tmpfs")
    try:
        out = disk / "run"
        with pytest.raises(FileWriteError, match=r"no space left on the device \(ENOSPC\); "
                           r"\d poke\(s\) kept in the journal"):
            explore_scenario(_config(), out, figures=True)
        read_journal(out / JOURNAL_NAME)  # whole lines only
        assert not [p for p in out.iterdir() if is_temporary(p)]
        subprocess.run(["mount", "-o", "remount,ro", str(disk)], check=True)
        with pytest.raises(FileWriteError, match="the file system is read-only"):
            explore_scenario(_config(), out, resume=True, figures=False)
        subprocess.run(["mount", "-o", "remount,rw,size=16m", str(disk)], check=True)
        resumed = explore_scenario(_config(), out, resume=True, figures=False).report
        assert [p["beta"] for p in resumed["pokes"]] == [
            p["beta"] for p in full_run.report["pokes"]]
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)
