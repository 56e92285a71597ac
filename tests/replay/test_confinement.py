"""A session reads only inside its folder, says how many pokes it holds, and carries a SHA-256
manifest that catches a changed file (issue 14)."""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from deformap.errors import ConfigError, FileFormatError
from deformap.replay import load_session
from deformap.replay._confine import seal


@pytest.fixture
def folder(tmp_path: Path, synthetic, write_synthetic) -> Path:  # type: ignore[no-untyped-def]
    return write_synthetic(tmp_path / "s", synthetic).parent  # type: ignore[no-any-return]


def _doc(folder: Path) -> dict[str, Any]:
    return yaml.safe_load((folder / "session.yaml").read_text())  # type: ignore[no-any-return]


def _save(folder: Path, doc: dict[str, Any]) -> None:
    """Write ``doc`` as the session's file, sealed again when it keeps its manifest (as a tool
    that re-records the session would), so that the checks after the seal are reached."""
    text = yaml.safe_dump(doc, sort_keys=False)
    (folder / "session.yaml").write_text(seal(text) if "sha256" in doc else text)


def _unsealed(folder: Path) -> dict[str, Any]:
    doc = _doc(folder)
    del doc["sha256"]
    return doc


@pytest.mark.parametrize(
    ("key", "value"),
    [("observation", "../outside.pcd"), ("observation", "/etc/hostname"),
     ("ground_truth", "sub/../../ground_truth.npz"), ("pokes.0.cloud", "../poke-01.pcd"),
     ("pokes.2.robot_points", "/tmp/robot.pcd")],
)  # fmt: skip
def test_names_outside_the_folder_fail_the_load(folder: Path, key: str, value: str) -> None:
    doc = _unsealed(folder)
    target: Any = doc
    *parents, last = key.split(".")
    for part in parents:
        target = target[int(part)] if part.isdigit() else target[part]
    target[int(last) if last.isdigit() else last] = value
    _save(folder, doc)
    shown = re.escape(key.replace(".0.", "[0].").replace(".2.", "[2]."))
    with pytest.raises(ConfigError, match=rf"session\.yaml: `{shown}` is '{value}', outside the "
                                          r"session folder; a session's files must lie inside"):
        load_session(folder)


def test_a_name_that_cannot_be_resolved_is_refused_by_name(folder: Path) -> None:
    doc = _unsealed(folder)
    doc["observation"] = "obs\x00ervation.pcd"
    _save(folder, doc)
    with pytest.raises(ConfigError, match=r"`observation` is 'obs\\x00ervation\.pcd', which "
                                          r"cannot be resolved: embedded null byte"):
        load_session(folder)
    os.symlink("loop", folder / "loop")
    doc["observation"] = "loop"
    _save(folder, doc)
    with pytest.raises(ConfigError, match=r"`observation` is 'loop', which cannot be resolved"):
        load_session(folder)


def test_a_link_out_of_the_folder_is_refused_and_so_is_one_inside(folder: Path,
                                                                     tmp_path: Path) -> None:
    outside = tmp_path / "elsewhere.pcd"
    shutil.copy(folder / "poke-02.pcd", outside)
    doc = _unsealed(folder)
    (folder / "poke-02.pcd").unlink()
    os.symlink(outside, folder / "poke-02.pcd")
    _save(folder, doc)
    with pytest.raises(ConfigError, match=r"`pokes\[1\]\.cloud` is 'poke-02\.pcd', a link to "
                                          r"'.*elsewhere\.pcd', outside the session folder"):
        load_session(folder)
    (folder / "poke-02.pcd").unlink()
    (folder / "data").mkdir()
    shutil.move(outside, folder / "data" / "p2.pcd")
    os.symlink(Path("data") / "p2.pcd", folder / "poke-02.pcd")  # relative, stays inside
    with pytest.raises(ConfigError, match=r"poke-02\.pcd: a symbolic link \(to 'data/p2\.pcd'\) "
                                          r"in the session folder"):
        load_session(folder)


def test_bag_metadata_may_not_name_files_outside(tmp_path: Path, synthetic,
                                                 write_synthetic) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("rosbags")
    folder = write_synthetic(tmp_path / "s", synthetic, format="mcap", sealed=False).parent
    meta = folder / "bag" / "metadata.yaml"
    good = meta.read_text()
    name = yaml.safe_load(good)["rosbag2_bagfile_information"]["relative_file_paths"][0]
    assert len(load_session(folder)) == 3
    for bad in (f"../{name}", f"/tmp/{name}"):
        meta.write_text(good.replace(name, bad))
        with pytest.raises(ConfigError, match=r"metadata\.yaml: `rosbag2_bagfile_information\."
                                              rf"relative_file_paths\[0\]` is '{bad}', outside"):
            load_session(folder)
    meta.write_text(good)
    storage = folder / "bag" / name
    shutil.move(storage, tmp_path / name)
    os.symlink(tmp_path / name, storage)
    with pytest.raises(ConfigError, match=rf"{name}: a symbolic link \(to '.*'\) in the session"):
        load_session(folder)


def test_a_session_cut_at_a_poke_boundary_is_refused(folder: Path) -> None:
    text = (folder / "session.yaml").read_text()
    cut = text[: text.index("- cloud: poke-03")]  # still valid YAML, one poke short
    (folder / "session.yaml").write_text(cut)
    with pytest.raises(ConfigError, match=r"session\.yaml: `n_pokes` is 3 but `pokes` lists 2 "
                                          r"entries; the file was cut or edited"):
        load_session(folder)


@pytest.mark.parametrize("value", [-1, 2.5, True, "3"])
def test_n_pokes_must_be_a_count(folder: Path, value: Any) -> None:
    doc = _doc(folder)
    doc["n_pokes"] = value
    _save(folder, doc)
    with pytest.raises(ConfigError, match=r"`n_pokes` must be a whole number >= 0"):
        load_session(folder)


def test_a_session_without_count_or_manifest_still_loads(folder: Path) -> None:
    doc = _unsealed(folder)
    del doc["n_pokes"]
    _save(folder, doc)
    assert len(load_session(folder)) == 3


def test_the_writer_lists_every_file_it_wrote(folder: Path) -> None:
    doc = _doc(folder)
    assert doc["n_pokes"] == 3
    files = sorted(p.name for p in folder.iterdir() if p.name != "session.yaml")
    assert sorted(doc["sha256"]) == files
    assert list(doc)[-1] == "pokes"  # count and manifest survive a cut in the poke list


def _flip(path: Path, at: int) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0x01
    path.write_bytes(bytes(data))


def test_a_flipped_float_is_caught_by_the_manifest(folder: Path) -> None:
    """A PCD body has no checksum: only the manifest sees a changed coordinate bit."""
    _flip(folder / "poke-02.pcd", -5)  # the last point's z, low mantissa bits
    session = load_session(folder)
    session.press_observation(0)
    session.press_observation(2)
    with pytest.raises(FileFormatError, match=r"poke-02\.pcd: SHA-256 is [0-9a-f]{16}…, the "
                                              r"session's manifest says [0-9a-f]{16}…; the file "
                                              r"changed after it was recorded"):
        session.press_observation(1)


def test_ground_truth_and_unlisted_files_and_bad_digests(folder: Path) -> None:
    _flip(folder / "ground_truth.npz", 100)
    with pytest.raises(FileFormatError, match=r"ground_truth\.npz: SHA-256 is"):
        load_session(folder)
    doc = _doc(folder)
    del doc["sha256"]["ground_truth.npz"]
    _save(folder, doc)
    with pytest.raises(FileFormatError, match=r"ground_truth\.npz: not in the session's `sha256` "
                                              r"manifest \(7 files\)"):
        load_session(folder)
    doc["sha256"]["ground_truth.npz"] = "ABC"
    _save(folder, doc)
    with pytest.raises(ConfigError, match=r"`sha256\['ground_truth\.npz'\]` must be 64 lowercase "
                                          r"hex digits; got 'ABC'"):
        load_session(folder)
    doc["sha256"]["ground_truth.npz"] = "0" * 64
    doc["sha256"]["../x.npz"] = "0" * 64
    _save(folder, doc)
    with pytest.raises(ConfigError, match=r"`sha256\['\.\./x\.npz'\]` is '\.\./x\.npz', outside"):
        load_session(folder)


def test_a_changed_bag_is_refused_at_load(tmp_path: Path, synthetic, write_synthetic) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("rosbags")
    folder = write_synthetic(tmp_path / "s", synthetic, format="mcap").parent
    assert len(load_session(folder)) == 3
    storage = next((folder / "bag").glob("*.mcap"))
    size = storage.stat().st_size
    _flip(storage, int(np.clip(size // 2, 0, size - 1)))
    with pytest.raises(FileFormatError, match=r"\.mcap: SHA-256 is .* changed after it was "
                                              r"recorded"):
        load_session(folder)
