"""The standing mutant suite's alias bombs (every YAML a user gives: a session, a run
configuration, a scenario, a raw bag's settings) and ascii files cut inside their last number are
each refused in one line, within the per-case time limit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformap.testing import _mutators, mutants


def test_every_alias_bomb_and_cut_number_mutant_is_refused(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    new = {reader: tuple(k for k in kinds if k in ("alias", "cut-number"))
           for reader, kinds in _mutators.KINDS.items()}
    assert {r for r, kinds in new.items() if kinds} == {
        "pcd-ascii", "ply-ascii", "session", "config", "scenario", "raw-mcap", "raw-db3"}
    monkeypatch.setattr(_mutators, "KINDS", new)
    monkeypatch.setattr(mutants, "kinds_of", lambda reader: new.get(reader) or new.get(
        reader.split("-")[0], ()))
    cases = mutants.run_mutants(30, seed=7, limit_s=10.0, work=tmp_path)
    assert {(c.reader, c.kind) for c in cases} >= {
        ("pcd-ascii", "cut-number"), ("ply-ascii", "cut-number"), ("session-folder", "alias"),
        ("config", "alias"), ("scenario", "alias"), ("raw-mcap", "alias"), ("raw-db3", "alias")}
    bad = [c for c in cases if c.outcome != "clean"]
    assert not bad, "\n".join(f"{c.outcome}: {c.reader} {c.kind}: {c.detail}" for c in bad)
    alias = [c for c in cases if c.kind == "alias"]
    assert all("anchors and aliases" in c.detail for c in alias)


def test_an_accepted_alias_bomb_or_cut_number_counts_as_silent() -> None:
    same = (120, "a")
    assert mutants.classify("config", "alias", "ok", same, same) == "silent"
    assert mutants.classify("scenario", "alias", "ok", "x", "y") == "silent"
    assert mutants.classify("pcd-ascii", "cut-number", "ok", (120, "a"), (120, "b")) == "silent"
    assert mutants.classify("config", "alias", "clean", "refused", same) == "clean"


def test_the_mutators_make_what_they_say() -> None:
    rng = np.random.default_rng(0)
    text = _mutators._alias_edit("name: x\nblocks:\n  - color: red\n", rng)
    assert "&l0" in text and "*l0" in text
    cut = _mutators.FILE_MUTATORS["cut-number"](b"h\n1.25 2.5 3.125\n", rng)
    assert not cut.endswith(b"\n") and b"1.25 2.5 3.1" in cut and len(cut) < 15


@pytest.mark.parametrize("args", [
    ["explore", "--config", "{bomb}"],
    ["explore", "-s", "{bomb}"],
    ["record-sim", "-s", "{bomb}"],
    ["world", "show", "{bomb}"],
    ["bench", "worlds", "--set", "strategy=&a paper"],
])
def test_the_command_line_refuses_an_alias_bomb_before_any_work(tmp_path: Path,
                                                                 args: list[str]) -> None:
    import time

    from typer.testing import CliRunner

    from deformap.cli import app
    from deformap.testing import cli_mutants

    bomb = cli_mutants.hostile_paths(tmp_path)["alias-bomb"]
    out = tmp_path / "out"
    start = time.perf_counter()
    result = CliRunner().invoke(app, [*(a.replace("{bomb}", bomb) for a in args),
                                      "--out", str(out)])
    assert time.perf_counter() - start < 5.0
    assert result.exit_code == 2 and not out.exists(), result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and ("anchors and aliases" in errors[0]
                                 or "must be a scalar" in errors[0]), result.output
