"""The command line's boundary, by seeded mutants: every option of every command (found from the
app itself, so a new command or option is covered without editing this file) given hostile values
— negative, zero, NaN, infinite, 400-digit, out-of-range and non-numeric numbers; empty, markup,
over-long and traversing strings; a FIFO, ``/dev/zero``, a directory, a path under a file — must
end with exit code 2 and one line naming what is wrong (or the command-line parser's usage box for
a value of the wrong type), never a traceback, never a hang.

So that no mutant runs real work, each invocation also carries a guard that any run refuses
before its work: ``--out`` naming an existing file (a run folder is checked before any world is
built), or, where the mutated option is ``--out`` or a command has none, ``--json`` naming an
existing directory (checked while parsing); where the mutated option is the command's only guard,
its values are only destinations no run may write to (a folder, a FIFO, a device, a path under a
file, an over-long name). A command with neither is left out. This suite found ``--json
/dev/zero`` replacing the device node with a JSON file (run as root) and ``config dump --out ""``
ending in a traceback.
"""

from __future__ import annotations

import os
import random
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from deformap.cli import app

NUMBERS = ("-1", "0", "nan", "inf", "-inf", "1e400", "9" * 400, "1e-320", "abc", "3.5", "")
STRINGS = ("[red]x[/red]", "x" * 300, "../../../../etc/passwd", "no-such-name", "é∂ƒ\u202e")
PER_OPTION = 5  # values drawn per option (seeded); every value class appears over the options
HANG_LIMIT_S = 60


def _commands(group: Any, path: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], Any]]:
    if hasattr(group, "commands"):
        for name, sub in sorted(group.commands.items()):
            yield from _commands(sub, (*path, name))
    else:
        yield path, group


def _options(command: Any) -> list[Any]:
    return [p for p in command.params
            if p.opts and p.opts[0].startswith("--") and not getattr(p, "is_flag", False)
            and p.opts[0] != "--help"]  # fmt: skip


def _paths(root: Path) -> dict[str, str]:
    a_file = root / "a-file.txt"
    a_file.write_text("not a run folder\n")
    a_dir = root / "a-dir"
    a_dir.mkdir()
    (a_dir / "inside.txt").write_text("x\n")
    fifo = root / "a-fifo"
    os.mkfifo(fifo)
    return {"file": str(a_file), "dir": str(a_dir), "fifo": str(fifo),
            "under-file": str(a_file / "sub"), "zero": "/dev/zero",
            "long": str(root / ("n" * 300))}  # fmt: skip


def _cases(paths: dict[str, str]) -> list[tuple[tuple[str, ...], str, int, str]]:
    rng = random.Random(20261125)
    pool = (*NUMBERS, *STRINGS, *paths.values())
    # where the mutated option is the command's only guard, only values no run may write to
    unwritable = tuple(paths[k] for k in ("dir", "fifo", "zero", "under-file", "long"))
    cases = []
    for path, command in _commands(typer.main.get_command(app)):
        names = [p.opts[0] for p in _options(command)]
        guards = {"--out", "--json"} & set(names)
        if not guards:
            continue
        for param in _options(command):
            sole_guard = guards == {param.opts[0]}
            values = rng.sample(unwritable if sole_guard else pool, PER_OPTION)
            cases.extend((path, param.opts[0], int(param.nargs), v) for v in values)
    return cases


def _argv(path: tuple[str, ...], option: str, nargs: int, value: str, names: list[str],
          positional: list[Any], paths: dict[str, str]) -> list[str]:
    argv = list(path)
    argv += [paths["dir"] for _ in positional]  # a folder that is no session or scenario
    argv += [option, *([value] + ["0"] * (nargs - 1))]
    if option != "--out" and "--out" in names:
        argv += ["--out", paths["file"]]
    elif option != "--json" and "--json" in names:
        argv += ["--json", paths["dir"]]
    return argv


def _timeout(signum: int, frame: Any) -> None:
    raise TimeoutError(f"no answer within {HANG_LIMIT_S} s")


def _invoke(runner: CliRunner, argv: list[str]) -> Any:
    """The command's result, or the TimeoutError of the alarm (the SIGALRM handler installed)."""
    signal.alarm(HANG_LIMIT_S)
    try:
        return runner.invoke(app, argv, env={"COLUMNS": "200"})
    except TimeoutError as error:
        return error
    finally:
        signal.alarm(0)


def test_every_option_of_every_command_refuses_hostile_values(tmp_path: Path) -> None:
    paths = _paths(tmp_path)
    cases = _cases(paths)
    assert len(cases) >= 300  # every command with a guard, every option (about 75 options)
    runner = CliRunner()
    commands = dict(_commands(typer.main.get_command(app)))
    failures = []
    previous = signal.signal(signal.SIGALRM, _timeout)
    try:
        for path, option, nargs, value in cases:
            command = commands[path]
            names = [p.opts[0] for p in _options(command)]
            positional = [p for p in command.params if not p.opts or
                          not p.opts[0].startswith("-")]  # fmt: skip
            argv = _argv(path, option, nargs, value, names, positional, paths)
            result = _invoke(runner, argv)
            if isinstance(result, TimeoutError):
                failures.append(f"{' '.join(argv)[:160]}: {result}")
                continue
            problem = _judge(result)
            if problem:
                failures.append(f"{' '.join(argv)[:160]}: {problem}")
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert not failures, f"{len(failures)} of {len(cases)} mutants:\n" + "\n".join(failures[:20])


def _judge(result: Any) -> str | None:
    """What is wrong with one mutant's ending, or None."""
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


def test_the_guards_alone_refuse_before_any_work(tmp_path: Path) -> None:
    # the guard must be what stops a mutant whose value happened to be valid
    paths = _paths(tmp_path)
    result = CliRunner().invoke(app, ["explore", "--out", paths["file"]])
    assert result.exit_code == 2 and "error:" in result.output
    result = CliRunner().invoke(app, ["bench", "io", "--json", paths["dir"]])
    assert result.exit_code == 2 and "--json" in result.output


@pytest.mark.parametrize("value", ["nan", "-1", "1e400"])
def test_a_bad_number_names_its_option(value: str, tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["explore", "--threshold", value, "--out",
                                      str(tmp_path / "run")])  # fmt: skip
    assert result.exit_code == 2
    assert "threshold" in result.output and not (tmp_path / "run").exists()


NON_FINITE = ("nan", "inf", "-inf", "1e400")


def test_every_number_option_refuses_non_finite_values_itself(tmp_path: Path) -> None:
    """Without a guard: a float option given NaN or an infinity must be refused naming that
    option (or by the parser), before any folder; accepted, the command would go on to its work
    and the alarm would say so. This catches what the guard above can mask (a value refused
    only after the folder check)."""
    runner = CliRunner()
    failures, cases = [], 0
    previous = signal.signal(signal.SIGALRM, _timeout)
    try:
        for path, command in _commands(typer.main.get_command(app)):
            positional = [p for p in command.params if not p.opts or
                          not p.opts[0].startswith("-")]  # fmt: skip
            names = [p.opts[0] for p in _options(command)]
            for param in _options(command):
                if param.bare_type() != "float":
                    continue
                for value in NON_FINITE:
                    cases += 1
                    out = tmp_path / f"out-{cases}"
                    argv = [*path, *[str(tmp_path / "no-session") for _ in positional],
                            param.opts[0], *([value] + ["0"] * (int(param.nargs) - 1))]
                    if "--out" in names:
                        argv += ["--out", str(out)]
                    result = _invoke(runner, argv)
                    if isinstance(result, TimeoutError):
                        failures.append(f"{' '.join(argv)}: {result}")
                        continue
                    problem = _judge(result)
                    named = param.name in result.output or param.opts[0] in result.output
                    if problem is None and not named and "Usage:" not in result.output:
                        problem = f"refused without naming {param.opts[0]}: {result.output!r}"
                    if problem is None and out.exists():
                        problem = "left a folder"
                    if problem:
                        failures.append(f"{' '.join(argv)}: {problem}"[:300])
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert cases >= 20
    assert not failures, f"{len(failures)} of {cases}:\n" + "\n".join(failures[:20])
