"""Every writer of a file a run or a session holds goes through the one write path: a disk that
fills mid-file or a read-only file system is one FileWriteError line naming the file, and nothing
cut short is left under the final name (the old file stays), nor a temporary beside it.

The failures are injected (the tests may run as root, for whom a read-only mode is no obstacle):
``open`` refusing to create a file (read-only), and a write that stops half-way with ENOSPC."""

from __future__ import annotations

import builtins
import errno
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from deformap._config import dump_yaml
from deformap.cloud import PointCloud
from deformap.cloud.io import write_npz, write_pcd, write_ply
from deformap.errors import FileWriteError
from deformap.replay import GroundTruth
from deformap.replay._truth import write_ground_truth
from deformap.world import load_scenario, save_scenario

_CLOUD = PointCloud(np.random.default_rng(0).uniform(0, 0.3, (500, 3)))
_TRUTH = GroundTruth(np.linspace(0, 0.6, 12), np.linspace(0, 0.4, 8),
                     np.zeros((8, 12), dtype=np.int64), np.full((8, 12), 80.0))

WRITERS: dict[str, tuple[str, Callable[[Path], Any]]] = {
    "pcd": ("observation.pcd", lambda p: write_pcd(p, _CLOUD)),
    "pcd-ascii": ("observation.pcd", lambda p: write_pcd(p, _CLOUD, encoding="ascii")),
    "ply": ("poke-01.ply", lambda p: write_ply(p, _CLOUD)),
    "ply-ascii": ("poke-01.ply", lambda p: write_ply(p, _CLOUD, format="ascii")),
    "npz": ("poke-01.npz", lambda p: write_npz(p, _CLOUD)),
    "ground-truth": ("ground_truth.npz", lambda p: write_ground_truth(p, _TRUTH)),
    "config": ("config.yaml", lambda p: dump_yaml({"seed": 1, "name": "x" * 5000}, p)),
    "scenario": ("scenario.yaml", lambda p: save_scenario(load_scenario("heterogeneous-60-150"), p)),
}


def _writes(mode: str) -> bool:
    return any(c in mode for c in "wxa+")


@pytest.fixture(params=sorted(WRITERS))
def writer(request: pytest.FixtureRequest) -> tuple[str, Callable[[Path], Any]]:
    return WRITERS[request.param]


def test_each_writer_writes_whole_files(tmp_path: Path, writer) -> None:  # type: ignore[no-untyped-def]
    name, write = writer
    write(tmp_path / name)
    assert os.listdir(tmp_path) == [name] and (tmp_path / name).stat().st_size > 100


def test_a_read_only_file_system_is_one_line_and_the_old_file_stays(
        tmp_path: Path, monkeypatch, writer) -> None:  # type: ignore[no-untyped-def]
    name, write = writer
    path = tmp_path / name
    path.write_bytes(b"the old file")
    real_open = builtins.open

    def read_only(file, mode="r", *args, **kwargs):  # type: ignore[no-untyped-def]
        if _writes(mode) and str(file).startswith(str(tmp_path)):
            raise OSError(errno.EROFS, "Read-only file system", str(file))
        return real_open(file, mode, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", read_only)
    with pytest.raises(FileWriteError) as caught:
        write(path)
    monkeypatch.undo()
    assert str(caught.value) == f"cannot write {str(path)!r}: the file system is read-only (EROFS)"
    assert path.read_bytes() == b"the old file" and os.listdir(tmp_path) == [name]


def test_a_disk_that_fills_mid_file_leaves_no_cut_file_under_the_name(
        tmp_path: Path, monkeypatch, writer) -> None:  # type: ignore[no-untyped-def]
    name, write = writer
    path = tmp_path / name
    real_open = builtins.open

    class Filling:
        """A file that takes 64 bytes, then reports the disk full."""

        def __init__(self, fh: Any) -> None:
            self._fh, self._left = fh, 64

        def write(self, data: Any) -> int:
            size = len(data.encode() if isinstance(data, str) else memoryview(data).cast("B"))
            if size > self._left:
                raise OSError(errno.ENOSPC, "No space left on device")
            self._left -= size
            return self._fh.write(data)  # type: ignore[no-any-return]

        def __getattr__(self, attr: str) -> Any:
            return getattr(self._fh, attr)

        def __enter__(self) -> Filling:
            return self

        def __exit__(self, *exc: object) -> None:
            self._fh.close()

    def filling(file, mode="r", *args, **kwargs):  # type: ignore[no-untyped-def]
        fh = real_open(file, mode, *args, **kwargs)
        return Filling(fh) if _writes(mode) and str(file).startswith(str(tmp_path)) else fh

    monkeypatch.setattr(builtins, "open", filling)
    with pytest.raises(FileWriteError) as caught:
        write(path)
    monkeypatch.undo()
    assert str(caught.value) == (f"cannot write {str(path)!r}: no space left on the device "
                                 "(ENOSPC)")
    assert os.listdir(tmp_path) == []  # neither a cut file nor a temporary


def test_a_session_whose_disk_fills_names_the_file_and_is_no_session(tmp_path: Path,
                                                                      monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import deformap._files as files_module
    from deformap.environment import Workspace
    from deformap.errors import DeformapError
    from deformap.replay import load_session, write_session

    real = files_module.replace_durably

    def full_at_the_observation(tmp: Path, path: Path) -> None:
        if path.name == "observation.pcd":
            raise OSError(errno.ENOSPC, "No space left on device")
        real(tmp, path)

    monkeypatch.setattr(files_module, "replace_durably", full_at_the_observation)
    out = tmp_path / "session"
    with pytest.raises(FileWriteError) as caught:
        write_session(out, workspace=Workspace(), observation=_CLOUD, presses=[],
                      tip_radius_m=0.01, ground_truth=_TRUTH)  # fmt: skip
    assert str(caught.value) == (f"cannot write {str(out / 'observation.pcd')!r}: no space left "
                                 "on the device (ENOSPC)")
    assert sorted(os.listdir(out)) == ["ground_truth.npz"]  # whole, and no session.yaml
    with pytest.raises(DeformapError, match="not a session folder"):
        load_session(out)


def test_a_bag_whose_disk_fills_leaves_no_bag_cut_short(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("rosbags")
    import deformap.replay._write as write_module
    from deformap.environment import Workspace
    from deformap.replay import write_session

    real = write_module.write_session_bag

    def full_halfway(path: Path, **kwargs):  # type: ignore[no-untyped-def]
        real(path, **kwargs)  # the whole bag, then the disk is full before it is in place
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(write_module, "write_session_bag", full_halfway)
    out = tmp_path / "session"
    with pytest.raises(FileWriteError, match=r"cannot write '.*bag': no space left"):
        write_session(out, workspace=Workspace(), observation=_CLOUD, presses=[],
                      tip_radius_m=0.01, format="mcap")  # fmt: skip
    assert os.listdir(out) == []  # no bag under its name, no staging folder left
    monkeypatch.undo()
    write_session(out, workspace=Workspace(), observation=_CLOUD, presses=[],
                  tip_radius_m=0.01, format="mcap")  # fmt: skip
    assert sorted(os.listdir(out)) == ["bag", "session.yaml"]
