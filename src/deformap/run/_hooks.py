"""Progress callbacks of the workflows: a run announces itself, its stages and each poke.

The workflows never print; a caller (the CLI's progress bars, a notebook, a test) passes
:class:`RunHooks` and renders what it is told. Every hook is optional.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from deformap.explore import PokeRecord

__all__ = ["RunHooks", "RunStart"]


@dataclass(frozen=True, kw_only=True)
class RunStart:
    """What a workflow is about to do (its ``kind``, a one-line ``title``, the results'
    ``folder``), told once the folder exists; ``total`` steps to come (``None``: unknown), of
    which ``done`` are done already (the pokes a resumed run takes from its journal)."""

    kind: str
    title: str
    folder: Path | None = None
    total: int | None = None
    done: int = 0


def _call(hook: Callable[[Any], None] | None, value: Any) -> None:
    if hook is not None:
        hook(value)


@dataclass(frozen=True, kw_only=True)
class RunHooks:
    """Optional callbacks: ``on_start`` once, ``on_stage`` per stage, ``on_step`` per step
    (a foam pressed, a scenario run), ``on_poke`` per poke; each method calls its own if given."""

    on_start: Callable[[RunStart], None] | None = None
    on_stage: Callable[[str], None] | None = None
    on_step: Callable[[str], None] | None = None
    on_poke: Callable[[PokeRecord], None] | None = None

    def start(self, start: RunStart) -> None:
        _call(self.on_start, start)

    def stage(self, text: str) -> None:
        _call(self.on_stage, text)

    def step(self, text: str) -> None:
        _call(self.on_step, text)

    def poke(self, poke: PokeRecord) -> None:
        _call(self.on_poke, poke)


NO_HOOKS = RunHooks()
"""Hooks that do nothing (the default of every workflow)."""
