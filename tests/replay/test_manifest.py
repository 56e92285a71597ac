"""What a session's manifest covers: ``session.yaml`` itself (its seal line), no links anywhere in
the folder, a manifest once written required, every entry present; and a raw bag whose messages
were written twice."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from deformap.errors import ConfigError, FileFormatError
from deformap.replay import load_session


@pytest.fixture
def folder(tmp_path: Path, synthetic, write_synthetic) -> Path:  # type: ignore[no-untyped-def]
    return write_synthetic(tmp_path / "s", synthetic).parent  # type: ignore[no-any-return]


def _lines(folder: Path) -> list[str]:
    return (folder / "session.yaml").read_text().splitlines(keepends=True)


def _write(folder: Path, lines: list[str]) -> None:
    (folder / "session.yaml").write_text("".join(lines))


def test_the_writer_seals_session_yaml_and_the_sealed_session_loads(folder: Path) -> None:
    assert _lines(folder)[0].startswith("# deformap seal: sha256 ")
    assert len(load_session(folder)) == 3


@pytest.mark.parametrize(("old", "new"), [("tip_radius_m: 0.0", "tip_radius_m: 0.1"),
                                          ("force_n: 1.0", "force_n: 2.0"),
                                          ("units: m", "units: mm")])
def test_an_edit_of_session_yaml_itself_is_refused(folder: Path, old: str, new: str) -> None:
    text = (folder / "session.yaml").read_text()
    assert old in text
    (folder / "session.yaml").write_text(text.replace(old, new, 1))
    with pytest.raises(FileFormatError, match=r"session\.yaml: SHA-256 of the lines below its "
                                              r"seal is [0-9a-f]{16}…, the seal says [0-9a-f]{16}…; "
                                              r"the file changed after it was recorded"):
        load_session(folder)


def _without_manifest(lines: list[str]) -> list[str]:
    start = next(i for i, line in enumerate(lines) if line.startswith("sha256:"))
    end = next(i for i in range(start + 1, len(lines)) if not lines[i].startswith(" "))
    return lines[:start] + lines[end:]


def test_a_removed_manifest_is_refused_not_skipped(folder: Path) -> None:
    _write(folder, _without_manifest(_lines(folder)))
    with pytest.raises(FileFormatError, match=r"session\.yaml: SHA-256 of the lines below"):
        load_session(folder)  # the seal covers the manifest's lines


def test_a_manifest_removed_and_the_seal_redone_is_refused(folder: Path) -> None:
    from deformap.replay._confine import seal

    _write(folder, [seal("".join(_without_manifest(_lines(folder)[1:])))])
    with pytest.raises(FileFormatError, match=r"session\.yaml: is sealed but has no `sha256` "
                                              r"manifest: a session recorded with one is read "
                                              r"only with it"):
        load_session(folder)


def test_a_removed_seal_with_the_manifest_kept_is_refused(folder: Path) -> None:
    _write(folder, _lines(folder)[1:])
    with pytest.raises(FileFormatError, match=r"session\.yaml: has a `sha256` manifest but its "
                                              r"first line is not the seal"):
        load_session(folder)


def test_a_session_with_neither_seal_nor_manifest_is_read_unchecked(folder: Path) -> None:
    _write(folder, _without_manifest(_lines(folder)[1:]))
    assert len(load_session(folder)) == 3


def test_missing_entries_are_refused_by_name(folder: Path) -> None:
    (folder / "poke-02.pcd").unlink()
    (folder / "poke-03-robot.pcd").unlink()
    with pytest.raises(FileFormatError, match=r"session\.yaml: the `sha256` manifest lists 2 "
                                              r"file\(s\) missing from the session: "
                                              r"'poke-02\.pcd', 'poke-03-robot\.pcd'; the session "
                                              r"lost files after it was recorded"):
        load_session(folder)


def test_session_yaml_as_a_link_out_of_the_folder_is_refused(folder: Path,
                                                             tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere.yaml"
    shutil.move(folder / "session.yaml", elsewhere)
    os.symlink(elsewhere, folder / "session.yaml")
    with pytest.raises(ConfigError, match=r"session\.yaml: a symbolic link \(to '.*elsewhere\.yaml'"
                                          r"\) in the session folder; a session's files may not "
                                          r"be links"):
        load_session(folder)


def test_a_link_anywhere_in_the_folder_is_refused(folder: Path) -> None:
    (folder / "notes").mkdir()
    os.symlink("../poke-01.pcd", folder / "notes" / "spare.pcd")  # not even read
    with pytest.raises(ConfigError, match=r"notes/spare\.pcd: a symbolic link \(to "
                                          r"'\.\./poke-01\.pcd'\)"):
        load_session(folder)
    (folder / "notes" / "spare.pcd").unlink()
    assert len(load_session(folder)) == 3


def test_the_folder_itself_may_be_named_through_a_link(folder: Path, tmp_path: Path) -> None:
    os.symlink(folder, tmp_path / "latest")
    assert len(load_session(tmp_path / "latest")) == 3


def test_a_raw_bag_with_every_message_written_twice_is_refused(
        tmp_path: Path, monkeypatch, make_synthetic, write_synthetic) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("mcap_ros2")
    import yaml

    import deformap.testing.robotbag as robotbag
    from deformap.replay import load_raw_bag, load_raw_config

    session = load_session(write_synthetic(tmp_path / "s", make_synthetic(n_points=300)).parent)
    bag = tmp_path / "lab.mcap"
    bag.with_name("lab.deformap.yaml").write_text(
        yaml.safe_dump(robotbag.raw_settings(session, force_n=1.0)))
    robotbag.write_raw_bag(bag, session, camera_hz=15.0, tf_hz=25.0, wrench_hz=100.0)
    assert len(load_raw_bag(bag, load_raw_config(bag), default_force_n=1.0)) == 3
    once = robotbag.raw_messages

    def twice(*args, **kwargs):  # type: ignore[no-untyped-def]
        for msg in once(*args, **kwargs):
            yield msg
            yield msg

    monkeypatch.setattr(robotbag, "raw_messages", twice)
    robotbag.write_raw_bag(bag, session, camera_hz=15.0, tf_hz=25.0, wrench_hz=100.0)
    with pytest.raises(FileFormatError, match=r"lab\.mcap \[/\S+ message \d+\]: repeats message "
                                              r"\d+ byte for byte \(same header stamp\); the bag "
                                              r"holds messages written twice"):
        load_raw_bag(bag, load_raw_config(bag), default_force_n=1.0)
