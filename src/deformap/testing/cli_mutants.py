"""Seeded hostile arguments for every option of every command, found from the Typer app itself,
each run under a guard that stops it before its work: a test helper.

Values come from fixed pools (bad numbers, strings and paths), then from seeded generators of the
same classes. The guard: ``--out`` naming an existing file, or, where the mutated option is
``--out`` or a command has none, ``--json`` naming an existing directory; an option that is its
command's only guard gets only :data:`UNWRITABLE` destinations; a command with neither is left
out. Each must end with exit code 2 and one ``error:`` line (or the parser's usage box): never a
traceback, never a hang (a SIGALRM after :data:`HANG_LIMIT_S`).
"""

from __future__ import annotations

import os
import random
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import typer
from typer.testing import CliRunner

from deformap.cli import app
from deformap.testing._mutators import alias_bomb
from deformap.testing.mutants import count_table

__all__ = ["ENDINGS", "HANG_LIMIT_S", "CliCase", "CliMutant", "alarm_handler", "argv",
           "cli_mutants", "cli_table", "commands", "hostile_paths", "invoke", "judge", "options",
           "positional", "run_cli"]

NUMBERS = ("-1", "0", "nan", "inf", "-inf", "1e400", "9" * 400, "1e-320", "abc", "3.5", "")
STRINGS = ("[red]x[/red]", "x" * 300, "../../../../etc/passwd", "no-such-name", "é∂ƒ\u202e")
HANG_LIMIT_S = 60
#: Destinations no run may write to: the values of an option that is its command's only guard.
UNWRITABLE = ("dir", "fifo", "zero", "under-file", "long")
#: Characters of generated strings: shell, markup, path and format characters, controls (no NUL:
#: no shell can pass one), right-to-left and zero-width marks, letters.
_ALPHABET = ("[]/\\:;'\"`$|&<>*?~%{}()#!=,.-_ \t\n\r\x1b\x7f\u202e\u200b\ufeffé∂ƒ日本"
             "abcXYZ0123456789")  # fmt: skip
_SPELLINGS = ("+inf", "-nan", "NaN", "Infinity", "1_000", "0x10", " 7", "7 ", "1e", "--1", "½",
              "٣", "1,5", "1.5.5", "0.0.0", "-0", "+0", "1e-400", "4.9e-324", "1.7976931348623157e309",
              "2**64", "18446744073709551617", "-9223372036854775809", "1d3", "∞")  # fmt: skip


def commands(group: Any, path: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], Any]]:
    """``(words, click command)`` of every command under ``group``, depth first."""
    if hasattr(group, "commands"):
        for name, sub in sorted(group.commands.items()):
            yield from commands(sub, (*path, name))
    else:
        yield path, group


def options(command: Any) -> list[Any]:
    """The command's ``--name VALUE`` options (no flags, no ``--help``)."""
    return [p for p in command.params
            if p.opts and p.opts[0].startswith("--") and not getattr(p, "is_flag", False)
            and p.opts[0] != "--help"]  # fmt: skip


def positional(command: Any) -> list[Any]:
    return [p for p in command.params if not p.opts or not p.opts[0].startswith("-")]


def hostile_paths(root: Path) -> dict[str, str]:
    """A file, a folder, a FIFO under ``root``; a path under the file, ``/dev/zero``, a
    300-character name, and a YAML file whose known keys hold a nested alias bomb (a run
    configuration's and a scenario's at once)."""
    a_file = root / "a-file.txt"
    a_file.write_text("not a run folder\n")
    bomb = root / "alias-bomb.yaml"
    bomb.write_text(f"name: {alias_bomb()}\nexploration:\n  strategy: {alias_bomb()}\n")
    a_dir = root / "a-dir"
    a_dir.mkdir()
    (a_dir / "inside.txt").write_text("x\n")
    fifo = root / "a-fifo"
    os.mkfifo(fifo)
    return {"file": str(a_file), "dir": str(a_dir), "fifo": str(fifo),
            "under-file": str(a_file / "sub"), "zero": "/dev/zero",
            "long": str(root / ("n" * 300)), "alias-bomb": str(bomb)}  # fmt: skip


@dataclass(frozen=True)
class CliMutant:
    """One hostile value for one option: ``kind`` is its class (number, string, path, or one of
    them generated: number-gen, string-gen, path-gen)."""

    path: tuple[str, ...]
    option: str
    nargs: int
    value: str
    kind: str


def _generated(rng: random.Random, paths: dict[str, str], sole_guard: bool) -> tuple[str, str]:
    """One generated value: ``(kind, value)``; only an unwritable destination for a sole guard."""
    choice = "path" if sole_guard else rng.choice(("number", "string", "path"))
    if choice == "number":
        form = rng.randrange(4)
        if form == 0:
            digits = rng.randrange(1, 18)
            value = f"{rng.choice('+-')}{rng.random() * 10:.{digits}f}e{rng.randint(-400, 400)}"
        elif form == 1:
            value = rng.choice("+-") + "".join(rng.choice("0123456789")
                                               for _ in range(rng.randint(1, 400)))  # fmt: skip
        elif form == 2:
            value = rng.choice(_SPELLINGS)
        else:
            value = str(rng.choice((-1, 1)) * 2 ** rng.randint(0, 128) + rng.randint(-1, 1))
        return "number-gen", value
    if choice == "string":
        value = "".join(rng.choice(_ALPHABET) for _ in range(rng.choice((0, 1, 5, 40, 300))))
        if rng.random() < 0.3:
            value = f"[{rng.choice(('bold', 'link=x', '/', 'red on blue', ''))}]{value}"
        return "string-gen", value
    base = rng.choice(UNWRITABLE)
    name = "".join(rng.choice("abcdef-_.é") for _ in range(rng.randint(1, 12)))
    variants = {
        "dir": (paths["dir"] + "/", paths["dir"] + "/.", paths["dir"] + "/../a-dir"),
        "fifo": (paths["fifo"], paths["fifo"] + "/" + name),
        "zero": ("/dev/zero", "/dev/zero/" + name, "/dev/null/" + name),
        "under-file": (paths["file"] + "/" + name, paths["file"] + "/" + name + "/" + name),
        "long": (str(Path(paths["dir"]) / ("n" * rng.randint(256, 5000))),
                 paths["dir"] + ("/" + "d" * 200) * rng.randint(20, 40)),
    }[base]
    return "path-gen", rng.choice(variants)


def cli_mutants(paths: dict[str, str], per_option: int, seed: int) -> list[CliMutant]:
    """``per_option`` seeded hostile values for every option of every command with a guard: the
    fixed pools first (drawn without repeats), then generated values."""
    rng = random.Random(seed)
    pool = ([("number", v) for v in NUMBERS] + [("string", v) for v in STRINGS]
            + [("path", v) for v in paths.values()])  # fmt: skip
    unwritable = [("path", paths[k]) for k in UNWRITABLE]
    cases: list[CliMutant] = []
    for path, command in commands(typer.main.get_command(app)):
        names = [p.opts[0] for p in options(command)]
        guards = {"--out", "--json"} & set(names)
        if not guards:
            continue
        for param in options(command):
            sole_guard = guards == {param.opts[0]}
            fixed = unwritable if sole_guard else pool
            values = rng.sample(fixed, min(per_option, len(fixed)))
            values += [_generated(rng, paths, sole_guard)
                       for _ in range(per_option - len(values))]  # fmt: skip
            cases.extend(CliMutant(path, param.opts[0], int(param.nargs), v, kind)
                         for kind, v in values)  # fmt: skip
    return cases


def argv(mutant: CliMutant, command: Any, paths: dict[str, str]) -> list[str]:
    """The command line: the command, a folder for each positional argument (no session or
    scenario), the mutated option, and the guard."""
    names = [p.opts[0] for p in options(command)]
    out = [*mutant.path, *[paths["dir"] for _ in positional(command)]]
    out += [mutant.option, *([mutant.value] + ["0"] * (mutant.nargs - 1))]
    if mutant.option != "--out" and "--out" in names:
        out += ["--out", paths["file"]]
    elif mutant.option != "--json" and "--json" in names:
        out += ["--json", paths["dir"]]
    return out


def _timeout(signum: int, frame: Any) -> None:
    raise TimeoutError(f"no answer within {HANG_LIMIT_S} s")


def invoke(runner: CliRunner, args: list[str]) -> Any:
    """The command's result, or the TimeoutError of the alarm (with the SIGALRM handler of
    :func:`alarm_handler` installed)."""
    signal.alarm(HANG_LIMIT_S)
    try:
        return runner.invoke(app, args, env={"COLUMNS": "200"})
    except TimeoutError as error:
        return error
    finally:
        signal.alarm(0)


@contextmanager
def alarm_handler() -> Iterator[None]:
    """Install the SIGALRM handler that turns an alarm into a TimeoutError; restore the old."""
    previous = signal.signal(signal.SIGALRM, _timeout)
    try:
        yield
    finally:
        signal.signal(signal.SIGALRM, previous)


def judge(result: Any) -> str | None:
    """What is wrong with one mutant's ending, or None."""
    if isinstance(result, TimeoutError):
        return f"hang: {result}"
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        return f"raised {type(result.exception).__name__}: {result.exception}"[:300]
    if "Traceback" in result.output:
        return "printed a traceback"
    if result.exit_code != 2:
        return f"exit code {result.exit_code} (expected 2): {result.output[-200:]!r}"
    lines = [line for line in result.output.splitlines() if line.strip()]
    if any(line.startswith("Usage:") for line in lines):  # the parser's box: a wrong type
        return None if any("Error" in line for line in lines) else "usage without an error"
    errors = [line for line in lines if line.startswith("error:")]
    if len(errors) != 1:
        return f"expected one 'error:' line, got {lines[-3:]!r}"
    return None


# ----------------------------------------------------------------------------- the run

#: How a mutant ended: one ``error:`` line that names the mutated option or its value
#: (``named``), one that names the guard's destination instead (``guard``: the run stopped at the
#: guard, which does not show that the value itself would have been refused), one that names
#: neither (``clean``); the parser's usage box (``usage``); a traceback, a hang, anything else.
ENDINGS = ("named", "guard", "clean", "usage", "traceback", "hang", "other")


@dataclass
class CliCase:
    """One mutant run: its value's kind, the command and option given it, its ending
    (:data:`ENDINGS`) and what it printed."""

    kind: str
    option: str
    ending: str
    detail: str


def _names(option: str) -> tuple[str, ...]:
    """How an error line may name ``option`` (``--max-pokes``): as given, bare, or as the
    setting it fills (``max_pokes``)."""
    bare = option.lstrip("-")
    return (option, f"`{bare}`", f"`{bare.replace('-', '_')}`", bare.replace("-", "_"))


def _ending(result: Any, problem: str | None, mutant: CliMutant, paths: dict[str, str]) -> str:
    if problem is None:
        if "Usage:" in result.output:
            return "usage"
        line = next(x for x in result.output.splitlines() if x.startswith("error:"))
        guard = (paths["file"], paths["dir"])
        value = mutant.value if mutant.value.strip() and mutant.value not in guard else None
        if any(name in line for name in _names(mutant.option)) or (value and value in line):
            return "named"
        return "guard" if any(g in line for g in guard) else "clean"
    if problem.startswith("hang"):
        return "hang"
    if problem.startswith(("raised", "printed a traceback")):
        return "traceback"
    return "other"


def run_cli(count: int, seed: int, work: Path) -> list[CliCase]:
    """At least ``count`` mutants, the same number for every option (fixed pools first)."""
    paths = hostile_paths(work)
    n_options = len(cli_mutants(paths, 1, seed))
    mutants = cli_mutants(paths, -(-count // n_options), seed)
    runner = CliRunner()
    all_commands = dict(commands(typer.main.get_command(app)))
    cases = []
    with alarm_handler():
        for mutant in mutants:
            args = argv(mutant, all_commands[mutant.path], paths)
            result = invoke(runner, args)
            problem = judge(result)
            cases.append(CliCase(mutant.kind, " ".join((*mutant.path, mutant.option)),
                                 _ending(result, problem, mutant, paths),
                                 f"{' '.join(args)[:160]}: {problem}"))  # fmt: skip
    return cases


def cli_table(cases: list[CliCase]) -> str:
    """A markdown table of command-line mutants: one row per value kind, the options given it
    and the count of each ending."""
    return count_table(
        ["value kind", "mutants", "options", "one line naming the option or value",
         "one line naming the guard", "one line naming neither", "usage errors (parser)",
         "tracebacks", "hangs", "other endings"],
        sorted(cases, key=lambda c: c.kind), "kind", "ending",
        ENDINGS, lambda mine: [str(len(mine)), str(len({c.option for c in mine}))])
