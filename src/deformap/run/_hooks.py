"""Progress callbacks of the workflows: a run announces itself, its stages and each poke.

The workflows never print; a caller (the CLI's progress bars, a notebook, a test) passes
:class:`RunHooks` and renders what it is told. Every hook is optional.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from deformap.explore import PokeRecord

__all__ = ["RunHooks", "RunStart"]


@dataclass(frozen=True, kw_only=True)
class RunStart:
    """What a workflow is about to do, told once its folder exists and before the work.

    Attributes
    ----------
    kind : str
        ``"explore"``, ``"record"``, ``"map"``, ``"study"``, ``"reproduce"`` or ``"world"``.
    title : str
        One line on what runs (scenario and seed, or session and form).
    folder : Path or None
        Where the results go (``None`` when nothing is written).
    total : int or None
        Steps to come (pokes at most, foams, scenarios), ``None`` when unknown.
    done : int
        Steps already done (pokes a resumed run takes from its journal).
    """

    kind: str
    title: str
    folder: Path | None = None
    total: int | None = None
    done: int = 0


@dataclass(frozen=True, kw_only=True)
class RunHooks:
    """Optional callbacks: ``on_start`` once, ``on_stage`` per stage, ``on_step`` per step
    (a foam pressed, a scenario run), ``on_poke`` per poke."""

    on_start: Callable[[RunStart], None] | None = None
    on_stage: Callable[[str], None] | None = None
    on_step: Callable[[str], None] | None = None
    on_poke: Callable[[PokeRecord], None] | None = None

    def start(self, start: RunStart) -> None:
        """Call ``on_start`` if given."""
        if self.on_start is not None:
            self.on_start(start)

    def stage(self, text: str) -> None:
        """Call ``on_stage`` if given."""
        if self.on_stage is not None:
            self.on_stage(text)

    def step(self, text: str) -> None:
        """Call ``on_step`` if given."""
        if self.on_step is not None:
            self.on_step(text)

    def poke(self, poke: PokeRecord) -> None:
        """Call ``on_poke`` if given."""
        if self.on_poke is not None:
            self.on_poke(poke)


NO_HOOKS = RunHooks()
"""Hooks that do nothing (the default of every workflow)."""
