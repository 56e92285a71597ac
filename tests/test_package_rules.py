"""The package rules of issue 12 that a change of imports can break, read from the source.

Every ``import`` in ``src/deformap`` counts, also those inside functions (which ``sys.modules``
after an import would miss). The whole import table is ``docs/architecture.md``'s; these are the
rules about the bottom of the graph, ``deformap.testing`` and private names.
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"

# Being moved by another change of issue 12 (the application layer and the CLI package): they
# still import private names of other packages.
_PRIVATE_IMPORT_EXEMPT = {"deformap/cli.py", "deformap/eval/_experiment.py"}


@cache
def _imports() -> list[tuple[str, str, str, list[str]]]:
    """(file relative to src, its package, imported module, imported names) for every import of
    deformap in the source."""
    out = []
    for path in sorted((SRC / "deformap").rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        parts = rel.removesuffix(".py").split("/")
        package = parts[1] if len(parts) > 1 else parts[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), rel)):
            if isinstance(node, ast.Import):
                out += [(rel, package, alias.name, []) for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                out.append((rel, package, node.module, [a.name for a in node.names]))
    return [item for item in out if item[2].split(".")[0] == "deformap"]


def _target(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "deformap"


def _deps(package: str) -> set[str]:
    return {_target(m) for _, p, m, _ in _imports() if p == package} - {package}


def test_the_source_is_found() -> None:
    assert len(_imports()) > 100 and _deps("explore") >= {"gp", "msm", "environment"}


@pytest.mark.parametrize(
    ("package", "allowed"),
    [
        ("mechanics", {"_validation", "errors"}),
        ("cloud", {"_validation", "errors"}),
        ("gp", {"_validation", "errors"}),
        ("msm", {"_validation", "errors", "mechanics"}),
    ],
)
def test_the_bottom_of_the_graph_imports_only_what_it_may(package: str, allowed: set[str]) -> None:
    assert _deps(package) <= allowed, f"{package} imports {sorted(_deps(package) - allowed)}"


def test_the_world_never_imports_the_estimator() -> None:
    assert not _deps("world") & {"gp", "msm", "explore"}


def test_production_code_never_imports_the_testing_module() -> None:
    found = [f for f, p, m, _ in _imports() if _target(m) == "testing" and p != "testing"]
    assert not found, f"deformap.testing imported by {found}"


def test_no_private_name_of_another_package_is_imported() -> None:
    found = []
    for rel, package, module, names in _imports():
        parts = module.split(".")
        if len(parts) < 2 or parts[1] == package or rel in _PRIVATE_IMPORT_EXEMPT:
            continue
        private_module = any(p.startswith("_") for p in parts[2:])
        private_names = [n for n in names if n.startswith("_")]
        if private_module or private_names:
            found.append(f"{rel}: {module} {private_names or ''}")
    assert not found, "private cross-package imports:\n" + "\n".join(found)
