"""Names of a package imported from their modules on first use.

For packages whose modules pull in the simulated world or the whole estimator (slow to import),
which a command such as ``deformap --help`` never needs: the package lists, per private module,
the names it exports, and :func:`lazy_exports` gives it the module-level ``__getattr__`` and
``__dir__`` (PEP 562) that import a module when one of its names is first asked for.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, modules: Mapping[str, Sequence[str]], exported: Sequence[str],
                 namespace: dict[str, Any]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package`` whose ``modules`` (``{"_module": names}``) hold
    its ``exported`` names; a name is cached in the package's ``namespace`` once imported."""
    home = {name: module for module, names in modules.items() for name in names}

    def getattr_(name: str) -> Any:
        if name in home:
            value = getattr(importlib.import_module(f"{package}.{home[name]}"), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def dir_() -> list[str]:
        return sorted(set(namespace) | set(exported))

    return getattr_, dir_
