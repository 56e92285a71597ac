"""The import table of docs/architecture.md, enforced on every module of the package.

The table is read from the document itself, so the document and the code cannot drift apart:
each package may import only the packages its row names, never another package's private module
or name, and no production module imports :mod:`deformap.testing`.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "deformap"
DOC = ROOT / "docs" / "architecture.md"


def _table() -> dict[str, set[str] | None]:
    """``{package: allowed imports}`` from the document's package table (``None``: anything)."""
    rows: dict[str, set[str] | None] = {}
    for line in DOC.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or not re.fullmatch(r"`deformap(\.[\w.]+)?`", cells[0]):
            continue
        allowed = cells[2]
        rows[cells[0].strip("`")] = (
            None if allowed.startswith("anything") else set(re.findall(r"`([\w.]+)`", allowed))
        )
    return rows


TABLE = _table()

#: The internals one package shares with another (``(importer, private module)``: why), the only
#: private modules a package may import from another; each must be in use.
ALLOWED_INTERNALS: dict[tuple[str, str], str] = {
    ("deformap.cli", "deformap.run._folder"): "a command's --json and --out files are written with "
    "the run folder's atomic writes (to_json, write_json, write_text)",
    ("deformap.eval", "deformap.explore._nugget"): "rescoring a stored run refits its β-field with "
    "the map's nugget as the mapper did (with_nugget)",
}


def _package(module: str) -> str:
    """The table row a module belongs to: the longest row name that is a prefix of it."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        name = ".".join(parts[:n])
        if name in TABLE and (name != "deformap" or module in ("deformap", "deformap.__main__")):
            return name
    raise AssertionError(f"{module} belongs to no package of docs/architecture.md")


def _module_name(path: Path) -> str:
    rel = path.relative_to(SRC.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _is_module(name: str) -> bool:
    """Whether ``name`` (``deformap.x.y``) is a module or package of the source tree."""
    base = SRC.parent.joinpath(*name.split("."))
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def _imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """``(line, module, names)`` of every deformap import in the file (in functions too)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    own = _module_name(path).split(".")
    is_pkg = path.name == "__init__.py"
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, []) for a in node.names if a.name.startswith("deformap")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = own if is_pkg else own[:-1]
                base = base[: len(base) - (node.level - 1)]
                module = ".".join([*base, *(node.module.split(".") if node.module else [])])
            else:
                module = node.module or ""
            if not module.startswith("deformap"):
                continue
            names = [a.name for a in node.names]
            # ``from deformap import run`` imports the subpackage ``deformap.run``
            subs = [n for n in names if _is_module(f"{module}.{n}")]
            out += [(node.lineno, f"{module}.{n}", []) for n in subs]
            rest = [n for n in names if n not in subs]
            if rest or not subs:
                out.append((node.lineno, module, rest))
    return out


MODULES = sorted(SRC.rglob("*.py"))


def test_the_document_has_a_row_for_every_package() -> None:
    assert len(TABLE) >= 10
    for path in MODULES:
        _package(_module_name(path))  # raises when a module has no row


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_imports_follow_the_table(path: Path) -> None:
    me = _module_name(path)
    mine = _package(me)
    allowed = TABLE[mine]
    problems = []
    for line, module, names in _imports(path):
        target = _package(module)
        if target == mine:
            continue
        where = f"{path.relative_to(ROOT)}:{line}"
        if target == "deformap.testing" and mine != "deformap.testing":
            problems.append(f"{where}: production code imports deformap.testing")
        if allowed is not None and target not in allowed:
            problems.append(f"{where}: {mine} may not import {target} ({module})")
        rest = module[len(target):].split(".")
        private = any(part.startswith("_") for part in rest if part)
        if private and (mine, module) not in ALLOWED_INTERNALS:
            problems.append(f"{where}: private module of another package ({module})")
        if any(n.startswith("_") and not n.endswith("__") for n in names):
            problems.append(f"{where}: private name of another package ({module}: {names})")
    assert not problems, "\n".join(problems)


def test_fitting_the_field_does_not_go_through_the_region_labelling() -> None:
    """The β-field's pokes (their nugget) need the region test's classes only: the field's modules
    import neither the cell labelling nor the place and seam rules."""
    explore = SRC / "explore"
    for name in ("_field.py", "_nugget.py", "_modulus.py", "_classes.py"):
        imported = {module for _, module, _ in _imports(explore / name)}
        assert not imported & {"deformap.explore._labels", "deformap.explore._places"}, name


def test_every_shared_internal_is_in_use_and_allowed_by_the_table() -> None:
    used = {(_package(_module_name(path)), module)
            for path in MODULES for _, module, _ in _imports(path)}
    for (importer, module), why in ALLOWED_INTERNALS.items():
        assert why, (importer, module)
        assert (importer, module) in used, f"{importer} no longer imports {module}: drop it"
        allowed = TABLE[importer]
        assert allowed is None or _package(module) in allowed, (importer, module)
