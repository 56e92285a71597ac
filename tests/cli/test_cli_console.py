"""The console a user reads (issue 15, item 6): piped output whole, -v without other libraries'
INFO lines, no library warnings, explore says what it runs, --help shows the defaults, and
estimate names a value missing from --contact."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import deformap
from deformap.cli import _app, _explore, app

runner = CliRunner()
SRC = str(Path(deformap.__file__).resolve().parents[1])


def test_piped_output_is_not_wrapped_at_80_columns() -> None:
    # a subprocess whose stdout is a pipe: a 150-character row comes back as one line
    code = (f"import sys; sys.path.insert(0, {SRC!r}); from deformap.cli._app import console; "
            "console.print('x' * 150 + ' /a/very/long/results/folder/' + 'y' * 60)")
    env = {k: v for k, v in os.environ.items() if k != "COLUMNS"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=True)  # fmt: skip
    assert out.stdout.splitlines() == ["x" * 150 + " /a/very/long/results/folder/" + "y" * 60]
    assert _app.PIPE_WIDTH >= 200


def test_verbose_shows_deformaps_info_but_not_other_libraries(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    root = logging.getLogger()
    monkeypatch.setattr(root, "handlers", [])  # as in a fresh process: basicConfig configures
    monkeypatch.setattr(root, "level", logging.WARNING)
    try:
        _app.configure_logging(verbose=True)
        assert logging.getLogger("deformap.explore._loop").isEnabledFor(logging.INFO)
        assert not logging.getLogger("matplotlib.font_manager").isEnabledFor(logging.INFO)
        assert not logging.getLogger("numba").isEnabledFor(logging.INFO)
        _app.configure_logging(verbose=False)
        assert not logging.getLogger("deformap.run").isEnabledFor(logging.INFO)
        assert logging.getLogger("deformap.run").isEnabledFor(logging.WARNING)
    finally:
        logging.captureWarnings(False)
        logging.getLogger("deformap").setLevel(logging.NOTSET)
        logging.getLogger("py.warnings").setLevel(logging.NOTSET)


def test_library_warnings_do_not_reach_the_user() -> None:
    # scipy's SparseEfficiencyWarning, raised from inside a command, in a fresh process
    code = f"""
import sys, warnings
sys.path.insert(0, {SRC!r})
from scipy.sparse import SparseEfficiencyWarning
def loud(*a, **k):
    warnings.warn("Changing the sparsity structure is expensive", SparseEfficiencyWarning)
    print("ran")
from deformap.cli._app import app as a
@a.command("loud")
def _loud():
    loud()
a(["loud"], standalone_mode=False)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "ran"
    assert "SparseEfficiencyWarning" not in out.stderr and "sparsity" not in out.stderr
    # with -v it is a log line naming where it came from, not a raw warning
    out = subprocess.run([sys.executable, "-c", code.replace('["loud"]', '["-v", "loud"]')],
                         capture_output=True, text=True, check=True)  # fmt: skip
    assert "warning (python):" in out.stderr and "SparseEfficiencyWarning" in out.stderr


def test_a_warning_is_printed_once_without_a_module_path() -> None:
    # a command logs a warning as it happens, then lists it again at the end (as `map` does
    # with a skipped poke): stderr holds it once, labelled, with no internal module name
    code = f"""
import logging, sys
sys.path.insert(0, {SRC!r})
from deformap.cli._app import app as a, warn
@a.command("twice")
def _twice():
    logging.getLogger("deformap.replay._offline").warning("poke %d skipped: %s", 2, "no dent")
    warn("poke 2 skipped: no dent")
    warn("poke 3 skipped: no dent")
a(["twice"], standalone_mode=False)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    lines = out.stderr.splitlines()
    assert lines == ["warning: poke 2 skipped: no dent", "warning: poke 3 skipped: no dent"]
    assert "deformap.replay" not in out.stderr and "WARNING" not in out.stderr


def test_help_text_reflows_and_keeps_its_brackets() -> None:
    # a docstring's hard line break is not kept (rich rewraps to the terminal), and "[required]"
    # in an option's help is text, not a style
    wide = runner.invoke(app, ["--help"], env={"COLUMNS": "200"})
    assert ("poke until the map field is known, then cut it into regions."
            in wide.output)  # fmt: skip
    narrow = runner.invoke(app, ["--help"], env={"COLUMNS": "70"})
    for line in narrow.output.splitlines():
        assert len(line) <= 70
    result = runner.invoke(app, ["estimate", "--help"], env={"COLUMNS": "200"})
    assert "Tip centre X Y Z at the press, metres. [required]" in result.output


def test_explore_without_a_scenario_says_what_it_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    from deformap import run

    class Stop(Exception):
        pass

    def stop(*args: Any, **kwargs: Any) -> Any:
        raise Stop

    monkeypatch.setattr(run, "explore_scenario", stop)
    result = runner.invoke(app, ["explore", "--max-pokes", "1"])
    assert isinstance(result.exception, Stop)
    assert ("no --scenario or --environment: exploring the simulated scenario "
            "'heterogeneous-60-110-rigid' (the default;") in result.output.replace("\n", " ")
    result = runner.invoke(app, ["explore", "-s", "homogeneous-60", "--max-pokes", "1"])
    assert isinstance(result.exception, Stop) and "no --scenario" not in result.output


def test_explore_help_shows_the_configurations_defaults() -> None:
    from deformap.run import RunConfig

    config = RunConfig()
    expected = {"scenario": config.scenario, "seed": config.seed,
                "exploration.strategy": config.exploration.strategy,
                "exploration.threshold": config.exploration.threshold,
                "exploration.max_pokes": config.exploration.max_pokes,
                "exploration.field": config.exploration.field}  # fmt: skip
    assert expected == _explore.HELP_DEFAULTS
    result = runner.invoke(app, ["explore", "--help"], env={"COLUMNS": "200"})
    for value in expected.values():
        assert f"[default: ({value})]" in result.output, (value, result.output)


@pytest.mark.parametrize(
    ("args", "message"),
    [(["--contact", "1", "2", "--force", "0", "0", "-1"],
      "--contact takes three numbers, the tip centre X Y Z in metres; got 2 (1 2) before --force"),
     (["--contact", "1", "2", "3", "--force", "0", "-1", "--tip-radius", "0.01"],
      "--force takes three numbers, the force FX FY FZ in newtons; got 2 (0 -1) before "
      "--tip-radius"),
     (["--force", "0", "0", "-1"], "--contact is required: three numbers"),
     (["--contact", "1", "2", "x", "--force", "0", "0", "-1"],
      "--contact takes three numbers, the tip centre X Y Z in metres; got 1 2 x"),
     (["--contact", "1", "2", "3", "--force", "0", "0", "-1", "--bogus"],
      "estimate takes no argument '--bogus'")],
)  # fmt: skip
def test_estimate_names_a_value_missing_from_contact(tmp_path: Path, args: list[str],
                                                     message: str) -> None:
    base = ["estimate", "--before", str(tmp_path / "a.pcd"), "--after", str(tmp_path / "b.pcd")]
    extra = [] if "--tip-radius" in args else ["--tip-radius", "0.01"]
    result = runner.invoke(app, [*base, *extra, *args], env={"COLUMNS": "300"})
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert "Traceback" not in result.output


def test_no_warning_filter_is_left_changed_by_configuring() -> None:
    before = list(warnings.filters)
    try:
        _app.configure_logging(verbose=False)
        assert list(warnings.filters) == before
    finally:
        logging.captureWarnings(False)
        logging.getLogger("deformap").setLevel(logging.NOTSET)
        logging.getLogger("py.warnings").setLevel(logging.NOTSET)


def test_study_and_record_help_show_their_defaults() -> None:
    from deformap.cli import _studies
    from deformap.eval import DEFAULT_HARDNESSES

    foams = ", ".join(f"{h:g}" for h in DEFAULT_HARDNESSES if h is not None)
    assert _studies.STUDY_HARDNESSES_HELP == f"{foams} and rigid" and None in DEFAULT_HARDNESSES
    result = runner.invoke(app, ["study", "hardness", "--help"], env={"COLUMNS": "200"})
    assert f"[default: ({foams} and rigid)]" in result.output
    result = runner.invoke(app, ["record-sim", "--help"], env={"COLUMNS": "200"})
    assert "[default: (0)]" in result.output and "[default: (12)]" in result.output


def test_explore_variance_max_reaches_the_run_and_a_bad_one_is_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from deformap import run

    seen: dict[str, Any] = {}

    class Stop(Exception):
        pass

    def stop(*args: Any, **kwargs: Any) -> Any:
        seen.update(kwargs)
        raise Stop

    monkeypatch.setattr(run, "explore_scenario", stop)
    result = runner.invoke(app, ["explore", "-s", "homogeneous-60", "--variance-max", "0.5"])
    assert isinstance(result.exception, Stop) and seen["variance_max"] == 0.5
    for bad in ("0", "-1", "nan"):
        result = runner.invoke(app, ["explore", "-s", "homogeneous-60", "--variance-max", bad])
        assert result.exit_code == 2
        assert f"--variance-max must be a finite number > 0; got {float(bad)}" in result.output
