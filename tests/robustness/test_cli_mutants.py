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

The generator, the guard and the judge are :mod:`deformap.testing.cli_mutants`'s, which
``benchmarks/robustness.py --cli-mutants N`` runs at a larger count (values generated beyond the
fixed pools); here five of the pools' values per option.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from deformap.cli import app
from deformap.testing import cli_mutants as cm

PER_OPTION = 5  # values drawn per option (seeded); every value class appears over the options


def test_every_option_of_every_command_refuses_hostile_values(tmp_path: Path) -> None:
    paths = cm.hostile_paths(tmp_path)
    mutants = cm.cli_mutants(paths, PER_OPTION, seed=20261125)
    assert len(mutants) >= 300  # every command with a guard, every option (about 75 options)
    assert {m.kind for m in mutants} == {"number", "string", "path"}  # the pools only
    runner = CliRunner()
    commands = dict(cm.commands(typer.main.get_command(app)))
    failures = []
    with cm.alarm_handler():
        for mutant in mutants:
            argv = cm.argv(mutant, commands[mutant.path], paths)
            problem = cm.judge(cm.invoke(runner, argv))
            if problem:
                failures.append(f"{' '.join(argv)[:160]}: {problem}")
    assert not failures, f"{len(failures)} of {len(mutants)} mutants:\n" + "\n".join(failures[:20])


def test_generated_values_are_seeded_and_of_every_class(tmp_path: Path) -> None:
    paths = cm.hostile_paths(tmp_path)
    first = cm.cli_mutants(paths, 30, seed=1)
    assert first == cm.cli_mutants(paths, 30, seed=1) != cm.cli_mutants(paths, 30, seed=2)
    assert {m.kind for m in first} >= {"number-gen", "string-gen", "path-gen"}
    sole = [m for m in first if m.option == "--json" and m.path == ("bench", "io")]
    assert sole and all(m.kind.startswith("path") for m in sole)  # a sole guard: destinations


def test_the_guards_alone_refuse_before_any_work(tmp_path: Path) -> None:
    # the guard must be what stops a mutant whose value happened to be valid
    paths = cm.hostile_paths(tmp_path)
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
    with cm.alarm_handler():
        for path, command in cm.commands(typer.main.get_command(app)):
            positional = cm.positional(command)
            names = [p.opts[0] for p in cm.options(command)]
            for param in cm.options(command):
                if param.bare_type() != "float":
                    continue
                for value in NON_FINITE:
                    cases += 1
                    out = tmp_path / f"out-{cases}"
                    argv = [*path, *[str(tmp_path / "no-session") for _ in positional],
                            param.opts[0], *([value] + ["0"] * (int(param.nargs) - 1))]
                    if "--out" in names:
                        argv += ["--out", str(out)]
                    result = cm.invoke(runner, argv)
                    problem = cm.judge(result)
                    if problem and problem.startswith("hang"):
                        failures.append(f"{' '.join(argv)}: {problem}")
                        continue
                    named = param.name in result.output or param.opts[0] in result.output
                    if problem is None and not named and "Usage:" not in result.output:
                        problem = f"refused without naming {param.opts[0]}: {result.output!r}"
                    if problem is None and out.exists():
                        problem = "left a folder"
                    if problem:
                        failures.append(f"{' '.join(argv)}: {problem}"[:300])
    assert cases >= 20
    assert not failures, f"{len(failures)} of {cases}:\n" + "\n".join(failures[:20])
