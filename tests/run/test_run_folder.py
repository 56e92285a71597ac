"""The one run-folder policy: naming, new folders only, failing before any work, atomic writes."""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

import pytest

from deformap import _files as files_module
from deformap._validation import SettingError
from deformap.errors import ConfigError
from deformap.run import RunConfig, default_run_folder, explore_scenario, record_simulation
from deformap.run._folder import atomic_path, create_run_folder, run_stem, write_json, write_text


def test_one_naming_scheme_for_every_kind_of_run() -> None:
    when = 1_700_000_000.0
    stamp = r"\d{8}-\d{6}"
    for stem, kind in (("homogeneous-60", "explore"), ("session", "map"), ("table-i", "reproduce")):
        path = default_run_folder(stem, kind, 7, when=when)
        assert path.parent == Path("runs")
        assert re.fullmatch(rf"{stem}-{kind}-s7-{stamp}", path.name), path.name
    assert run_stem("scenarios/my-table.yaml") == "my-table"
    assert run_stem("heterogeneous-60-150") == "heterogeneous-60-150"
    assert run_stem(Path("sessions/demo/")) == "demo"


def test_a_new_folder_is_created_with_its_parents_and_an_empty_one_is_taken(tmp_path: Path) -> None:
    assert create_run_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert (tmp_path / "a" / "b").is_dir()
    assert create_run_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"  # still empty


def test_a_folder_that_is_not_empty_is_refused_and_kept(tmp_path: Path) -> None:
    (tmp_path / "report.json").write_text("{}")
    with pytest.raises(ConfigError, match=r"exists and is not empty; choose another --out$"):
        create_run_folder(tmp_path)
    with pytest.raises(ConfigError, match="choose another --out or pass --resume"):
        create_run_folder(tmp_path, resume_hint=True)
    assert (tmp_path / "report.json").read_text() == "{}"


def test_a_folder_that_cannot_be_created_names_out(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match=r"cannot create run folder .*file.* \(--out\): something"):
        create_run_folder(tmp_path / "file")
    with pytest.raises(ConfigError, match=r"cannot create run folder .*sub.* \(--out\): Not a dir"):
        create_run_folder(tmp_path / "file" / "sub")


def _no_work(*args: object, **kwargs: object) -> None:
    raise AssertionError("the work started before the folder was checked")


def test_workflows_fail_on_the_folder_before_any_work(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "file").write_text("x")
    monkeypatch.setattr("deformap.run._explore.SimulatedWorld", _no_work)
    monkeypatch.setattr("deformap.run._record.SimulatedWorld", _no_work)
    config = RunConfig(scenario="homogeneous-60")
    with pytest.raises(ConfigError, match="cannot create output folder"):
        explore_scenario(config, tmp_path / "file" / "run")
    with pytest.raises(ConfigError, match="cannot create session folder"):
        record_simulation(config, tmp_path / "file" / "session")
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("x")
    with pytest.raises(ConfigError, match="exists and is not empty"):
        explore_scenario(config, tmp_path / "full")
    assert sorted(p.name for p in (tmp_path / "full").iterdir()) == ["x"]


def test_an_atomic_write_replaces_the_whole_file(tmp_path: Path) -> None:
    path = tmp_path / "report.json"
    write_text(path, "old")
    write_json(path, {"new": [1, 2]})
    assert path.read_text() == '{\n  "new": [\n    1,\n    2\n  ]\n}'
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]
    plain = tmp_path / "plain"
    plain.write_text("x")
    assert stat.S_IMODE(path.stat().st_mode) == stat.S_IMODE(plain.stat().st_mode)


def test_a_write_that_fails_leaves_the_old_file_and_no_temporary(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "config.yaml"
    write_text(path, "old: 1\n")

    def cut(tmp: Path, target: Path) -> None:  # the rename never happens: killed before it
        raise OSError("killed")

    monkeypatch.setattr(files_module, "replace_durably", cut)
    with pytest.raises(OSError, match="killed"):
        write_text(path, "new: 2\n")
    assert path.read_text() == "old: 1\n"
    assert os.listdir(tmp_path) == ["config.yaml"]


def test_a_writer_that_raises_leaves_the_old_file(tmp_path: Path) -> None:
    path = tmp_path / "map.png"
    path.write_bytes(b"old picture")
    with pytest.raises(RuntimeError, match="plot failed"), atomic_path(path) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".png" and tmp != path
        tmp.write_bytes(b"half a pic")
        raise RuntimeError("plot failed")
    assert path.read_bytes() == b"old picture"
    assert os.listdir(tmp_path) == ["map.png"]


def test_a_map_too_large_for_its_workspace_is_refused_before_the_folder(tmp_path: Path) -> None:
    # an 8 × 8 m workspace at the default 0.5 cm grid: 2.56 million map cells
    scenario = tmp_path / "hall.yaml"
    scenario.write_text("name: hall\nworkspace: {lower: [0, 0], upper: [8, 8]}\nblocks:\n"
                        "  - {name: soft, rect: [0.0, 0.0, 0.3, 0.4], hardness_n: 60}\n")
    out = tmp_path / "run"
    with pytest.raises(SettingError, match=r"surface\.grid_spacing_m.*2,560,000 map cells"):
        explore_scenario(RunConfig(scenario=str(scenario)), out)
    with pytest.raises(SettingError, match=r"surface\.grid_spacing_m"):
        record_simulation(RunConfig(scenario=str(scenario)), out)
    assert not out.exists()


def test_json_is_strict_nan_as_null_dates_as_iso(tmp_path: Path) -> None:
    import datetime
    import json

    import numpy as np

    from deformap.run._folder import to_json

    data = {"nan": float("nan"), "inf": np.float64("inf"), "arr": np.array([1.0, np.nan]),
            "when": datetime.date(2020, 1, 2), "where": tmp_path, "ok": (1, True, None, "x")}
    text = to_json(data)
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == {"nan": None, "inf": None, "arr": [1.0, None],
                                "when": "2020-01-02", "where": str(tmp_path),
                                "ok": [1, True, None, "x"]}
    write_json(tmp_path / "r.json", data)
    assert json.loads((tmp_path / "r.json").read_text())["when"] == "2020-01-02"
    with pytest.raises(TypeError, match="not JSON serialisable: object"):
        to_json({"bad": object()})


def test_a_destination_that_is_no_regular_file_is_refused_not_replaced(tmp_path: Path) -> None:
    from deformap._files import check_destination, write_text_atomically
    from deformap.errors import InvalidArgumentError

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    folder = tmp_path / "folder"
    folder.mkdir()
    for path, kind in ((fifo, "a FIFO"), (folder, "a folder"), (Path("/dev/null"), "a device")):
        with pytest.raises(InvalidArgumentError, match=f"got {kind}"):
            write_text_atomically(path, "{}")
    assert fifo.is_fifo() and Path("/dev/null").is_char_device()  # left as they were
    for name in ("", ".", ".."):
        with pytest.raises(InvalidArgumentError, match="expected the name of a file"):
            check_destination(name)
    # a regular file is replaced; a symbolic link is refused (the rename would replace the link,
    # and /dev/stdout is one: a link to /proc/self/fd/1)
    plain = tmp_path / "plain.json"
    plain.write_text("old")
    write_text_atomically(plain, "new")
    assert plain.read_text() == "new"
    link = tmp_path / "stdout"
    link.symlink_to("/proc/self/fd/1")
    with pytest.raises(InvalidArgumentError, match="got a symbolic link"):
        write_text_atomically(link, "{}")
    assert link.is_symlink()
