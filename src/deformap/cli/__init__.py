"""The ``deformap`` command: each command parses its options, calls one function of
:mod:`deformap.run` (or :mod:`deformap.eval` for the benchmarks) and renders the result.

``_app`` holds what they share; ``_explore``, ``_replay``, ``_world``, ``_studies`` and ``_bench``
register their command groups on import.
"""

from __future__ import annotations

from deformap.cli import _bench, _explore, _replay, _studies, _world  # noqa: F401 - registers
from deformap.cli._app import app

__all__ = ["app", "main"]


def main() -> None:
    """Console-script entry point."""
    app()
