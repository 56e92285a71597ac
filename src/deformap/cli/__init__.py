"""The ``deformap`` command: one module per command group, each command parsing its options,
calling one function of :mod:`deformap.run` (or :mod:`deformap.eval` for the benchmarks) and
rendering the result.

``_app`` holds what they share (the app, consoles, one-line errors, ``--json``, progress);
``_explore`` (explore, config), ``_replay`` (record-sim, map, estimate), ``_world`` (scenarios,
world show), ``_studies`` (study, reproduce) and ``_bench`` (bench) register their commands on
import.
"""

from __future__ import annotations

from deformap.cli import _bench, _explore, _replay, _studies, _world  # noqa: F401 - registers
from deformap.cli._app import app

__all__ = ["app", "main"]


def main() -> None:
    """Console-script entry point."""
    app()
