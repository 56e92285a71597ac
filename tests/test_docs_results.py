"""docs/results.md gives every table the command that gave it and the commit it was measured at,
and the README stays a user's guide that leaves the measurements to it."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = (ROOT / "docs" / "results.md").read_text(encoding="utf-8")
README = (ROOT / "README.md").read_text(encoding="utf-8")
RUN = re.compile(r"^\*\*Run:\*\* .*`[^`]+`.* commit `([0-9a-f]{7,40})`", flags=re.M)


def _tables(text: str) -> list[tuple[int, str]]:
    """(line number, text before it since the previous table) of each markdown table."""
    lines = text.split("\n")
    out, since = [], 0
    for i, line in enumerate(lines):
        starts = (line.startswith("|") and i + 1 < len(lines)
                  and re.match(r"^\|\s*:?-{3,}", lines[i + 1]) is not None)  # fmt: skip
        if starts:
            out.append((i + 1, "\n".join(lines[since:i])))
        if line.startswith("|"):
            since = i + 1
    return out


def test_every_table_has_its_run_line() -> None:
    tables = _tables(RESULTS)
    assert len(tables) >= 30  # the README's measurements moved here
    missing = [n for n, before in tables if not RUN.search(before)]
    assert missing == [], f"tables without a **Run:** line (command and commit) at lines {missing}"


def test_the_measurements_from_the_code_are_here() -> None:
    assert "\n## Measurements formerly in the code\n" in RESULTS


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_every_cited_commit_exists() -> None:
    def git(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)

    if git("rev-parse", "--is-shallow-repository").stdout.strip() != "false":
        pytest.skip("not a full git clone")
    commits = set(RUN.findall(RESULTS))
    missing = [c for c in sorted(commits) if git("cat-file", "-e", f"{c}^{{commit}}").returncode]
    assert missing == []


def test_the_readme_is_a_guide_of_about_400_lines() -> None:
    n = README.count("\n")
    assert 300 <= n <= 450, f"README.md has {n} lines; measurements belong in docs/results.md"
    assert "docs/results.md" in README
    # no results log: the README's tables are reference tables, none with a Run line
    assert not RUN.search(README)
