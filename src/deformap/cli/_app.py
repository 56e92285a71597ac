"""What every command shares: the ``deformap`` app, its consoles, one-line errors and ``--json``.

Every command turns a :class:`~deformap.errors.DeformapError` (and an :class:`OSError`: a full
disk, a read-only folder) into one line on stderr and exit code 2: a user sees what to fix, never
a traceback. ``--json FILE`` means the same in every
command that has it: also write the command's result as JSON to ``FILE`` (atomically); ``-``
writes it to stdout, and the tables and progress then go to stderr.
"""

from __future__ import annotations

import inspect
import logging
import os
import sys
import tempfile
from collections.abc import Callable, Sequence
from functools import wraps
from pathlib import Path
from typing import Annotated, Any, NoReturn, TypeVar

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text
from typer.core import TyperGroup

from deformap import __version__
from deformap._files import check_destination, os_error_cause
from deformap.errors import ConfigError, DeformapError, InvalidArgumentError

__all__ = [
    "JsonOption", "VarianceMaxOption", "app", "cell", "check_positive_options", "console",
    "emit_json", "err_console", "fail", "friendly_errors", "labelled", "out_console", "table",
    "warn",
]

PIPE_WIDTH = 400
"""Columns of a console on a file or pipe, where rich would assume 80 and wrap: wide enough that
every row deformap prints stays one line for ``grep`` and ``cut`` (``COLUMNS`` still wins)."""


def _console(*, stderr: bool) -> Console:
    """A console on stdout or stderr, :data:`PIPE_WIDTH` wide on a file or pipe; markup off, as
    file and scenario names are the user's text, where brackets are characters."""
    stream = sys.stderr if stderr else sys.stdout
    piped = not (hasattr(stream, "isatty") and stream.isatty())
    width = PIPE_WIDTH if piped and not os.environ.get("COLUMNS") else None
    return Console(stderr=stderr, markup=False, highlight=False, width=width)


console = _console(stderr=False)
err_console = _console(stderr=True)


def labelled(label: str, style: str, text: str) -> Text:
    """``label`` in ``style``, a space, then ``text`` as it is (no markup)."""
    return Text.assemble((label, style), " ", text)


def cell(value: Any, spec: str) -> str:
    """``value`` formatted by ``spec``; ``–`` for None."""
    return "–" if value is None else format(value, spec)


def table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]], *,
          left: Sequence[str] = (), no_wrap: bool = True) -> Table:
    """A table of ``rows``: the ``left`` columns (names, ``no_wrap``) left, the others right."""
    out = Table(title=title)
    for col in columns:
        if col in left:
            out.add_column(col, no_wrap=no_wrap)
        else:
            out.add_column(col, justify="right")
    for row in rows:
        out.add_row(*row)
    return out


def fail(message: str) -> NoReturn:
    """Print ``error: message`` on stderr and exit with code 2."""
    err_console.print(labelled("error:", "bold red", message), soft_wrap=True)
    raise typer.Exit(code=2)


def _reflowed(text: str | None) -> str | None:
    """``text`` with each paragraph's line breaks made spaces (rich then wraps it to the
    terminal) and its square brackets literal ("[required]", "x [m]" are words, not styles)."""
    if not text:
        return text
    paragraphs = inspect.cleandoc(text).split("\n\n")
    return escape("\n\n".join(p if p.startswith("\b") else " ".join(p.split("\n"))
                                for p in paragraphs))  # fmt: skip


def _reflow_help(command: Any) -> None:
    """Reflow the help of a click ``command``, its parameters and every subcommand."""
    command.help = _reflowed(command.help)
    for param in command.params:
        if hasattr(param, "help"):  # options and typer's arguments; click's arguments have none
            param.help = _reflowed(param.help)
    for sub in getattr(command, "commands", {}).values():
        _reflow_help(sub)


class _ReflowingGroup(TyperGroup):
    """The root group, whose commands' help is reflowed once all are registered: rich keeps a
    docstring's hard line breaks and reads its brackets as styles."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        _reflow_help(self)


app = typer.Typer(
    name="deformap", cls=_ReflowingGroup, no_args_is_help=True, add_completion=False,
    help="Map how deformable a surface is, region by region, from a few robot pokes.",
    pretty_exceptions_enable=False,
    rich_markup_mode="rich",  # _ReflowingGroup escapes square brackets for rich markup
)  # fmt: skip


def _json_target(value: Path | None) -> Path | None:
    """``--json`` checked at parse time: a file that can be created (its folder exists or can be
    made, and it is no folder), so that a long run does not fail only when it is done."""
    if value is None or str(value) == "-":
        return value
    try:
        check_destination(value)  # a FIFO, device, socket or folder is never written over
        parent = value.parent
        while not parent.exists() and parent != parent.parent:  # the nearest folder that exists
            parent = parent.parent
        problem = f"{str(parent)!r} is not a folder" if not parent.is_dir() else None
        if problem is None:
            with tempfile.TemporaryFile(dir=parent):  # what the folder's file system will take
                pass
    except OSError as exc:
        problem = exc.strerror or str(exc)
    except InvalidArgumentError as exc:
        problem = str(exc)
    if problem is not None:
        fail(f"--json must name a file that can be written; got {str(value)!r}: {problem}")
    return value


def check_positive_options(**numbers: float | None) -> None:
    """Refuse, naming its option (``press_force`` → ``--press-force``), a number given that is not
    finite and > 0 (NaN too), before the command does anything."""
    for name, value in numbers.items():
        if value is not None and not 0.0 < value < float("inf"):
            option = "--" + name.replace("_", "-")
            raise InvalidArgumentError(f"{option} must be a finite number > 0; got {value}")


VarianceMaxOption = Annotated[float | None, typer.Option(
    help="Top of map.png's variance colour scale, the same in every run drawn with it so that "
    "runs compare (default: each map's own largest variance).")]
JsonOption = Annotated[Path | None, typer.Option(
    "--json", help="Also write the result as JSON to this file (- for stdout).",
    callback=_json_target)]

F = TypeVar("F", bound=Callable[..., Any])


def friendly_errors(func: F) -> F:
    """Turn a DeformapError, or an OSError that none stood for (a write the machine refused in
    code outside deformap's write path), into a one-line message and exit code 2; refuse a
    negative ``--seed`` (every command that has one) before the command runs."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            seed = kwargs.get("seed")
            if isinstance(seed, int) and seed < 0:  # numpy's generators take seeds >= 0
                raise InvalidArgumentError(f"`--seed` must be an integer >= 0; got {seed}")
            return func(*args, **kwargs)
        except DeformapError as exc:
            fail(str(exc))
        except OSError as exc:  # what the machine refused outside deformap's own write path
            fail(os_error_line(exc))

    return wrapper  # type: ignore[return-value]


def os_error_line(error: OSError) -> str:
    """One line for an :class:`OSError` no deformap error stood for: the file it names (both, for
    a rename) and the cause."""
    names = [str(n) for n in (error.filename, error.filename2) if n is not None]
    where = " → ".join(repr(n) for n in names)
    return f"{where}: {os_error_cause(error)}" if where else os_error_cause(error)


def _to_stdout(json_path: Path | None) -> bool:
    return json_path is not None and str(json_path) == "-"


def out_console(json_path: Path | None) -> Console:
    """Where a command renders: stdout, or stderr when ``--json -`` takes stdout."""
    return err_console if _to_stdout(json_path) else console


def emit_json(json_path: Path | None, data: Any) -> None:
    """Write ``data`` as JSON where ``--json`` says (nothing when it was not given)."""
    if json_path is None:
        return
    from deformap.run._folder import to_json, write_json

    if _to_stdout(json_path):
        sys.stdout.write(to_json(data, indent=None) + "\n")  # one line, for pipes
        return
    try:
        json_path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot write --json {str(json_path)!r}: {os_error_cause(exc)}") from None
    write_json(json_path, data)  # a failure is one line naming the file (deformap._files)
    out_console(json_path).print(f"wrote {json_path}", highlight=False)


def _version_callback(value: bool) -> None:
    if value:
        console.print(f"deformap {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[bool, typer.Option("--version", callback=_version_callback, is_eager=True,
                                          help="Print the version.")] = False,
    verbose: Annotated[bool, typer.Option("--verbose", "-v",
                                          help="Log deformap's progress details.")] = False,
) -> None:
    configure_logging(verbose)


def configure_logging(verbose: bool) -> None:
    """deformap's warnings always, its INFO lines with ``verbose``; other libraries' log lines at
    WARNING and above, their Python warnings only with ``verbose`` (advice to their programmer,
    not to the user). One handler on the root logger prints each line once."""
    root = logging.getLogger()
    for handler in [h for h in root.handlers if isinstance(h, _ConsoleHandler)]:
        root.removeHandler(handler)
    root.addHandler(_ConsoleHandler())
    if root.level == logging.NOTSET or root.level > logging.WARNING:
        root.setLevel(logging.WARNING)
    logging.getLogger("deformap").setLevel(logging.INFO if verbose else logging.WARNING)
    logging.captureWarnings(True)
    logging.getLogger("py.warnings").setLevel(logging.WARNING if verbose else logging.CRITICAL)


_SHOWN: set[str] = set()  # the warning lines printed so far, which warn() does not repeat
_LEVEL_STYLES = {"error": "bold red", "warning": "yellow", "info": "dim", "debug": "dim"}


class _ConsoleHandler(logging.Handler):
    """Log lines on stderr as ``warning: message``, without deformap's module names; another
    library's lines name it (``warning (scipy): …``)."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            message = record.getMessage()
            level = record.levelname.lower()
            top = "python" if record.name == "py.warnings" else record.name.split(".")[0]
            label = f"{level}:" if top in ("deformap", "root") else f"{level} ({top}):"
            if record.levelno >= logging.WARNING:
                _SHOWN.add(message)
            err_console.print(labelled(label, _LEVEL_STYLES.get(level, ""), message),
                              soft_wrap=True)
        except Exception:  # logging's own contract: a handler never raises
            self.handleError(record)


def warn(message: str) -> None:
    """Print ``warning: message`` on stderr, unless a log line printed it already."""
    if message not in _SHOWN:
        _SHOWN.add(message)
        err_console.print(labelled("warning:", "yellow", message), soft_wrap=True)
