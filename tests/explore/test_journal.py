from __future__ import annotations

import json
import os
import stat

import pytest

from deformap.errors import ConfigError, FileFormatError
from deformap.explore._journal import Journal, read_journal


def test_append_and_read_back(tmp_path) -> None:
    journal = Journal.create(tmp_path, {"seed": 1})
    journal.append({"index": 0, "beta": 0.5})
    journal.append({"index": 1, "beta": 0.25})
    contents = read_journal(journal.path)
    assert contents.header == {"kind": "header", "seed": 1}
    assert [p["beta"] for p in contents.pokes] == [0.5, 0.25]
    assert contents.broken_line is None
    with pytest.raises(FileExistsError):
        Journal.create(tmp_path, {"seed": 1})


def test_a_line_cut_mid_write_is_dropped_and_reported(tmp_path) -> None:
    journal = Journal.create(tmp_path, {"seed": 1})
    journal.append({"index": 0, "beta": 0.5})
    with open(journal.path, "a") as fh:
        fh.write('{"kind": "poke", "index": 1, "be')
    contents = read_journal(journal.path)
    assert len(contents.pokes) == 1 and contents.broken_line is not None
    resumed, kept = Journal.resume(tmp_path, {"seed": 1})
    assert len(kept.pokes) == 1
    resumed.append({"index": 1, "beta": 0.7})
    lines = journal.path.read_text().splitlines()
    assert [json.loads(line)["kind"] for line in lines] == ["header", "poke", "poke"]


def test_resume_refuses_another_run_and_a_damaged_middle(tmp_path) -> None:
    journal = Journal.create(tmp_path, {"seed": 1, "threshold": 0.06})
    with pytest.raises(ConfigError, match=r"differs from this one in \['seed'\]"):
        Journal.resume(tmp_path, {"seed": 2, "threshold": 0.06})
    journal.append({"index": 0})
    text = journal.path.read_text().splitlines()
    journal.path.write_text(text[0] + "\n{broken\n" + text[1] + "\n")
    with pytest.raises(FileFormatError, match="line 2 is not valid JSON"):
        read_journal(journal.path)
    with pytest.raises(FileFormatError, match="cannot read journal"):
        read_journal(tmp_path / "nothing.jsonl")


def test_a_journal_is_created_whole_or_not_at_all(tmp_path, monkeypatch) -> None:
    import deformap.explore._journal as journal_module

    def killed(*args: object) -> None:
        raise KeyboardInterrupt  # the process dies between writing the header and renaming it

    monkeypatch.setattr(journal_module.os, "replace", killed)
    with pytest.raises(KeyboardInterrupt):
        Journal.create(tmp_path, {"seed": 1})
    assert not (tmp_path / "journal.jsonl").exists()
    monkeypatch.undo()
    journal = Journal.create(tmp_path, {"seed": 1})  # a leftover temporary file is no obstacle
    assert read_journal(journal.path).header == {"kind": "header", "seed": 1}


@pytest.mark.skipif(os.name != "posix", reason="folders are fsynced on POSIX only")
def test_the_rename_that_creates_a_journal_is_made_durable(tmp_path, monkeypatch) -> None:
    # After the rename the folder itself is fsynced, else a power cut may lose the new name.
    synced: list[bool] = []
    real_fsync = os.fsync

    def recording_fsync(fd: int) -> None:
        synced.append(stat.S_ISDIR(os.fstat(fd).st_mode))
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", recording_fsync)
    Journal.create(tmp_path, {"seed": 1})
    assert synced[-1] is True and False in synced  # the file's data first, then its folder
