"""Every relative link in README.md and docs/*.md points to a file that exists, and every
``#anchor`` to a heading of that file (GitHub's anchor rule)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", flags=re.S | re.M)


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`([^`]*)`", r"\1", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    seen: dict[str, int] = {}
    out = set()
    for heading in re.findall(r"^#{1,6} +(.+?) *#*$", text, flags=re.M):
        base = _anchor(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def _links(path: Path) -> list[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    text = re.sub(r"`[^`\n]*`", "", text)  # code spans are not links
    return [a or b for a, b in LINK.findall(text)]


def _relative(target: str) -> bool:
    return not re.match(r"^[a-z][a-z0-9+.-]*:", target, flags=re.I)  # http:, mailto:, …


CASES = [(page, target) for page in PAGES for target in _links(page) if _relative(target)]


def test_the_pages_have_relative_links() -> None:
    # the README links the docs it names; without links this test would check nothing
    readme = [t for p, t in CASES if p.name == "README.md"]
    assert "docs/results.md" in readme and "docs/robot.md" in readme


@pytest.mark.parametrize(("page", "target"), CASES,
                         ids=[f"{p.relative_to(ROOT)}->{t}" for p, t in CASES])  # fmt: skip
def test_a_relative_link_resolves(page: Path, target: str) -> None:
    file_part, _, anchor = target.partition("#")
    dest = (page.parent / file_part).resolve() if file_part else page
    assert dest.exists(), f"{page.relative_to(ROOT)} links to {target}, which does not exist"
    assert dest.is_relative_to(ROOT), f"{page.relative_to(ROOT)} links out of the repository"
    if anchor and dest.suffix == ".md":
        assert anchor in _anchors(dest), (
            f"{page.relative_to(ROOT)} links to #{anchor}, no heading of {dest.name} has it"
        )


def test_the_anchor_rule_matches_githubs() -> None:
    assert _anchor("The run folder") == "the-run-folder"
    assert (
        _anchor("β's scale: rigid at β = 0, no stiff end") == "βs-scale-rigid-at-β--0-no-stiff-end"
    )
    assert _anchor("Throughput of `bench worlds`, local and on Dask") == (
        "throughput-of-bench-worlds-local-and-on-dask"
    )
