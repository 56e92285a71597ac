"""What every command shares: the ``deformap`` app, its consoles, one-line errors, ``--json``,
and the progress display of a run.

Every command turns a :class:`~deformap.errors.DeformapError` into one line on stderr and exit
code 2: a user sees what to fix, never a traceback.

``--json FILE`` means the same in every command that has it: also write the command's result as
JSON to ``FILE`` (written atomically); ``-`` writes it to stdout, and the tables and progress then
go to stderr so that stdout is the JSON alone.
"""

from __future__ import annotations

import contextlib
import logging
import sys
from collections.abc import Callable, Iterator
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TextColumn,
    TimeElapsedColumn,
)

from deformap import __version__, run
from deformap.errors import ConfigError, DeformapError

if TYPE_CHECKING:  # the CLI loads the estimator only when a command runs
    from deformap.explore import PokeRecord

__all__ = [
    "JsonOption",
    "app",
    "console",
    "emit_json",
    "err_console",
    "friendly_errors",
    "out_console",
    "progress",
    "run_hooks",
]

console = Console()
err_console = Console(stderr=True)

app = typer.Typer(
    name="deformap",
    help="Map how deformable a surface is, region by region, from a few robot pokes.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

JsonOption = Annotated[
    Path | None,
    typer.Option("--json", help="Also write the result as JSON to this file (- for stdout)."),
]

F = TypeVar("F", bound=Callable[..., Any])


def friendly_errors(func: F) -> F:
    """Turn a DeformapError into a one-line message and exit code 2."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except DeformapError as exc:
            err_console.print(f"[bold red]error:[/] {exc}", highlight=False, soft_wrap=True)
            raise typer.Exit(code=2) from None

    return wrapper  # type: ignore[return-value]


def _to_stdout(json_path: Path | None) -> bool:
    return json_path is not None and str(json_path) == "-"


def out_console(json_path: Path | None) -> Console:
    """Where a command renders: stdout, or stderr when ``--json -`` takes stdout."""
    return err_console if _to_stdout(json_path) else console


def modulus_text(p: PokeRecord) -> str:
    """The poke's Young's modulus for a progress line ("" without a force–travel estimate)."""
    s = p.stiffness
    if s is None:
        return ""
    if s.rigid or s.modulus_pa is None:
        return "  rigid"
    return f"  E = {s.modulus_pa / 1e3:.1f} ± {(s.modulus_std_pa or 0.0) / 1e3:.1f} kPa"


def emit_json(json_path: Path | None, data: Any) -> None:
    """Write ``data`` as JSON where ``--json`` says (nothing when it was not given)."""
    if json_path is None:
        return
    if _to_stdout(json_path):
        sys.stdout.write(run.to_json(data, indent=None) + "\n")  # one line, for pipes
        return
    try:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        run.write_json(json_path, data)
    except OSError as exc:
        raise ConfigError(f"cannot write --json {str(json_path)!r}: {exc.strerror or exc}") from None
    out_console(json_path).print(f"wrote {json_path}", highlight=False)


@contextlib.contextmanager
def progress(out: Console, description: str = "working") -> Iterator[Progress]:
    """A transient progress display on ``out`` with one task (spinner, bar, count, time)."""
    columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
               MofNCompleteColumn(), TimeElapsedColumn())  # fmt: skip
    with Progress(*columns, console=out, transient=True) as bar:
        bar.add_task(description, total=None)
        yield bar


def run_hooks(
    bar: Progress,
    *,
    poke_row: Callable[[PokeRecord], str] | None = None,
    step_rows: bool = True,
) -> run.RunHooks:
    """Hooks that drive ``bar``'s task and print, above it, a header line, one row per poke
    (with ``poke_row``) and one per step (with ``step_rows``)."""
    task = bar.task_ids[0]

    def start(event: run.RunStart) -> None:
        where = "" if event.folder is None else f" → {event.folder}"
        bar.console.print(f"[bold]deformap {event.kind}[/] {event.title}{where}", highlight=False)
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


def _version_callback(value: bool) -> None:
    if value:
        console.print(f"deformap {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version_callback, is_eager=True, help="Print the version."
        ),
    ] = False,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log progress details.")] = False,
) -> None:
    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
