"""The progress display of a run on the command line: a transient bar, one line per poke or step."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

from rich import progress as bars
from rich.console import Console

from deformap import run
from deformap.cli._app import labelled

if TYPE_CHECKING:  # the CLI loads the estimator only when a command runs
    from deformap.explore import PokeRecord

__all__ = ["modulus_text", "progress", "run_hooks"]


def modulus_text(p: PokeRecord) -> str:
    """The poke's Young's modulus for a progress line ("" without a force–travel estimate)."""
    s = p.stiffness
    if s is None:
        return ""
    if s.rigid or s.modulus_pa is None:
        return "  rigid"
    return f"  E = {s.modulus_pa / 1e3:.1f} ± {(s.modulus_std_pa or 0.0) / 1e3:.1f} kPa"


@contextlib.contextmanager
def progress(out: Console, description: str = "working") -> Iterator[bars.Progress]:
    """A transient progress display on ``out`` with one task (spinner, bar, count, time)."""
    columns = (bars.SpinnerColumn(), bars.TextColumn("{task.description}", markup=False),
               bars.BarColumn(), bars.MofNCompleteColumn(), bars.TimeElapsedColumn())
    with bars.Progress(*columns, console=out, transient=True) as bar:
        bar.add_task(description, total=None)
        yield bar


def run_hooks(bar: bars.Progress, *, poke_row: Callable[[PokeRecord], str] | None = None,
              step_rows: bool = True) -> run.RunHooks:
    """Hooks that drive ``bar``'s task and print, above it, a header line, one row per poke
    (with ``poke_row``) and one per step (with ``step_rows``)."""
    task = bar.task_ids[0]

    def start(event: run.RunStart) -> None:
        where = "" if event.folder is None else f" → {event.folder}"
        bar.console.print(labelled(f"deformap {event.kind}", "bold", f"{event.title}{where}"))
        bar.update(task, total=event.total, completed=event.done, description=event.kind)

    def poke(event: PokeRecord) -> None:
        if poke_row is not None:
            bar.console.print(poke_row(event), highlight=False)
        bar.advance(task)

    def stage(text: str) -> None:
        bar.update(task, description=text)

    def step(text: str) -> None:
        if step_rows:
            bar.console.print(f"  {text}", highlight=False)
        bar.advance(task)

    return run.RunHooks(on_start=start, on_stage=stage, on_step=step, on_poke=poke)
