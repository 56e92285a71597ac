"""Seeded mutants of every reader's input (PCD ascii/binary/compressed, PLY ascii/binary, NPZ, and
folder and MCAP sessions, the YAML of a run configuration and of a scenario, and a raw robot bag
as ``deformap map BAG`` reads it, MCAP and sqlite3, with the YAML beside it) load to a valid
result or raise a DeformapError: never another exception, never a hang, never a corruption a
check could have caught accepted.

The mutants, the per-case time limit and the classification are
:mod:`deformap.testing.mutants`'s, which ``benchmarks/robustness.py`` runs by the thousand; here a
few hundred, every kind of every reader in turn (about seven of each).
"""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path

import pytest

from deformap.testing import mutants


def test_every_mutant_is_read_or_cleanly_refused(tmp_path: Path) -> None:
    plan = sum(len(kinds) for kinds in mutants.KINDS.values())
    cases = mutants.run_mutants(10 * (plan + 3), seed=2026, limit_s=10.0, work=tmp_path)
    bad = [c for c in cases if c.outcome in ("traceback", "hang", "silent")]
    assert not bad, "\n" + mutants.table(cases) + "\n" + "\n".join(
        f"{c.outcome}: {c.reader} {c.kind}: {c.detail}" for c in bad[:10])
    outcomes = {c.outcome for c in cases}
    assert "clean" in outcomes and "same" in outcomes  # the mutants reach both sides
    readers = {c.reader for c in cases}
    assert {"pcd-ascii", "pcd-binary", "pcd-binary_compressed", "ply-ascii", "ply-binary", "npz",
            "session-folder", "config", "scenario"} <= readers  # fmt: skip
    if importlib.util.find_spec("mcap_ros2") is not None:
        for reader in ("raw-mcap", "raw-db3"):
            raw = [c for c in cases if c.reader == reader]
            assert {c.kind for c in raw} == set(mutants.KINDS[reader]) and len(raw) >= 40


def test_the_classifier_flags_what_it_must() -> None:
    """The suite can fail: a lost point, a changed checksummed file, an escaped exception."""
    assert mutants.classify("pcd-binary", "count", "ok", (119, "a"), (120, "b")) == "silent"
    assert mutants.classify("ply-binary", "flip", "ok", (120, "a"), (120, "b")) == "changed"
    assert mutants.classify("npz", "flip", "ok", (120, "a"), (120, "b")) == "silent"
    assert mutants.classify("npz", "member-flip", "ok", (120, "a"), (120, "b")) == "changed"
    lost = (2, (("obs", "o"), (0, "p0"), (1, "p1"), ("truth", "t")))
    full = (3, (("obs", "o"), (0, "p0"), (1, "p1"), (2, "p2"), ("truth", "t")))
    assert mutants.classify("session-folder", "yaml", "ok", lost, full) == "silent"
    changed = (3, (("obs", "o"), (0, "p0"), (1, "XX"), (2, "p2"), ("truth", "t")))
    assert mutants.classify("session-folder", "file", "ok", changed, full) == "silent"
    refused = (3, (("obs", "o"), (0, "p0"), (1, "refused"), (2, "p2"), ("truth", "t")))
    assert mutants.classify("session-folder", "file", "ok", refused, full) == "clean"
    # a raw bag: its chunks and summary carry CRCs; a message rewritten with its CRCs made to
    # match is other data, unless its length changed; the settings YAML is the user's
    assert mutants.classify("raw-mcap", "record", "ok", changed, full) == "silent"
    assert mutants.classify("raw-mcap", "flip", "ok", changed, full) == "silent"
    assert mutants.classify("raw-mcap", "message-flip", "ok", changed, full) == "changed"
    assert mutants.classify("raw-mcap", "message-truncate", "ok", changed, full) == "silent"
    assert mutants.classify("raw-mcap", "yaml", "ok", lost, full) == "changed"
    assert mutants.classify("raw-mcap", "flip", "ok", refused, full) == "clean"
    # a sqlite3 bag has no CRC: bytes or a row edited in place are other data nothing could tell,
    # bytes or a message's data cut or extended are not, nor a row lost or repeated (the bag's
    # metadata table counts each topic's messages)
    for kind in ("flip", "message-flip", "row-type", "topic", "yaml"):
        assert mutants.classify("raw-db3", kind, "ok", changed, full) == "changed"
    for kind in ("truncate", "extend", "message-truncate", "message-extend", "row-delete",
                 "row-repeat"):
        assert mutants.classify("raw-db3", kind, "ok", changed, full) == "silent"
    assert mutants.classify("raw-db3", "row-delete", "ok", refused, full) == "clean"
    assert mutants.read_snapshot("no-such-reader", "x")[0] == "traceback"


def test_an_error_of_several_lines_counts_as_a_defect(
        monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    import deformap.cloud.io
    from deformap.errors import FileFormatError

    def read(path: str) -> None:
        raise FileFormatError(f"{path}: could not read: while parsing\n  in line 1")

    monkeypatch.setattr(deformap.cloud.io, "read_pcd", read)
    status, detail = mutants.read_snapshot("pcd-ascii", "x.pcd")
    assert status == "traceback" and "several lines" in detail


def test_a_hanging_reader_is_cut_at_the_limit(monkeypatch: pytest.MonkeyPatch,
                                              tmp_path: Path) -> None:  # fmt: skip
    monkeypatch.setattr(mutants, "read_snapshot", lambda reader, path: time.sleep(30))
    worker = mutants.Worker(limit_s=0.5)
    start = time.perf_counter()
    try:
        assert worker.read("pcd-ascii", tmp_path / "x.pcd")[0] == "hang"
    finally:
        worker.close()
    assert time.perf_counter() - start < 5
