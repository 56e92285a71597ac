"""Docstrings and comments in ``src/deformap`` state contracts, not history: no module refers to
an issue number or to a section of the README (those go stale; measurements live in
``docs/results.md``)."""

from __future__ import annotations

import io
import re
import tokenize
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "deformap"

#: "issue 13", "Issue 5's", "issues 3 and 5", "issue #16", anywhere in a module.
ISSUE = re.compile(r"\bissues? #?\d", re.IGNORECASE)
#: A tracker reference in a comment: "(#12)", "see #12" (not a colour such as "#6b4f3a").
HASH_NUMBER = re.compile(r"(?<![\w&#])#\d+\b(?![0-9a-fA-F])")
#: A place in the README: `README, "Many worlds"`, `README ("Results", ...)`, `README "x"`,
#: `(... ; README)`, or the benchmarks' README as the source of a figure.
README_PLACE = re.compile(r"README(?:,|\)|\s*\(|\s+[\"“])|benchmarks/README")


def _modules() -> list[Path]:
    return sorted(SRC.rglob("*.py"))


def _offences(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    found = [(n, line) for n, line in enumerate(text.splitlines(), 1)
             if ISSUE.search(line) or README_PLACE.search(line)]
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type == tokenize.COMMENT and HASH_NUMBER.search(token.string[1:]):
            found.append((token.start[0], token.string))
    rel = path.relative_to(SRC.parent)
    return [f"{rel}:{n}: {line.strip()}" for n, line in sorted(set(found))]


def test_the_patterns_catch_what_they_are_meant_to() -> None:
    for bad in ('the scale used before issue 13', 'Issue 5\'s budget', '(README, "Many worlds")',
                'the README ("Results", Table I)', 'README "Many worlds"', '(``benchmarks/README.md``)',
                '(which a tip stretches; README)'):
        assert ISSUE.search(bad) or README_PLACE.search(bad), bad
    for fine in ("see the README for a quick start", "tissue 3", '_RIGID_COLOR = "#6b4f3a"'):
        assert not (ISSUE.search(fine) or README_PLACE.search(fine)), fine
    assert HASH_NUMBER.search(" fixed in (#12)") and not HASH_NUMBER.search(" colour #6b4f3a")


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(SRC)))
def test_no_module_refers_to_an_issue_or_a_readme_section(path: Path) -> None:
    offences = _offences(path)
    assert offences == [], "history or README places in src (move them to docs/results.md):\n" + (
        "\n".join(offences))
