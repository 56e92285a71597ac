"""``deformap explore`` and ``deformap config dump``."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from deformap import run
from deformap.cli._app import (
    JsonOption,
    VarianceMaxOption,
    app,
    check_positive_options,
    emit_json,
    err_console,
    friendly_errors,
    labelled,
    out_console,
)
from deformap.cli._progress import modulus_text, progress, run_hooks
from deformap.errors import ConfigError, DeformapError

if TYPE_CHECKING:  # the CLI loads the estimator only when a command runs
    from deformap.explore import PokeRecord

__all__ = ["ConfigOption", "config_app"]

config_app = typer.Typer(help="The run configuration (YAML).")
app.add_typer(config_app, name="config")

HELP_DEFAULTS: dict[str, str | int | float] = {
    "scenario": "heterogeneous-60-110-rigid", "seed": 0, "exploration.strategy": "planned",
    "exploration.threshold": 0.06, "exploration.max_pokes": 12, "exploration.field": "modulus",
}  # fmt: skip
"""The ``RunConfig()`` defaults ``--help`` shows, written out so as not to import the estimator."""

ConfigOption = Annotated[Path | None, typer.Option(
    help="Run configuration YAML (see `config dump`).")]


def poke_row(p: PokeRecord) -> str:
    """One progress line of a live poke."""
    return (f"  poke {p.index + 1:>2}  target ({p.target_xy[0]:.3f}, {p.target_xy[1]:.3f}) m"
            f"  force {p.force_n:.2f} N  β = {p.beta:.3f} ± {p.beta_std:.3f}" + modulus_text(p)
            + f"  max var {p.max_variance_after:.4f}"
            + (f"  plan: {p.planned_after} more" if p.planned_after is not None else "")
            + ("  boundary poke" if p.purpose == "boundary" else "")
            + f"  (compute {p.timings.compute_s:.2f} s,"
            f" world {p.timings.environment_s or 0.0:.2f} s)")


def modulus_summary(report: dict[str, Any]) -> str:
    """One line on the modulus field of a ``report.json``: the found regions' median E in kPa and
    how many pokes it holds."""
    field = report.get("modulus_field")
    if field is None:
        return "no poke has a modulus (no usable force–travel record)"
    regions = report.get("regions") or {}
    medians = regions.get("class_modulus_median_pa") or []
    shown = ", ".join("–" if m is None else f"{m / 1e3:.3g}" for m in medians)
    rigid = sum(bool(p["rigid"]) for p in field["pokes"] if p["used"])
    left = len(field["pokes"]) - field["n_used"]
    return (f"median E per region [kPa]: {shown or '–'}; from {field['n_used']} poke(s)"
            + (f", {rigid} rigid (at its detection bound)" if rigid else "")
            + (f", {left} left out (no usable record)" if left else ""))


def _summary(out: Console, report: dict[str, Any], folder: Path) -> None:
    reg = report["regions"]
    tau = "n/a (one region)" if reg["kendall_tau"] is None else f"{reg['kendall_tau']:.2f}"
    table = Table(title=f"{report['scenario']} (seed {report['seed']})", show_header=False)
    table.add_column()
    table.add_column(overflow="fold")  # the results folder in full, not cut with "…"
    table.add_row("pokes", f"{report['n_pokes']} (stopped by {report['stop_reason']})")
    name = "ln E" if report.get("field") == "modulus" else "β"
    table.add_row("map field", f"{report.get('field', 'beta')} (regions, targets and stop rule)")
    table.add_row(f"max {name} variance", f"{report['max_variance']:.4f} "
                  f"(T_h {report.get('threshold', float('nan')):.4g})")  # fmt: skip
    table.add_row("regions found / true", f"{reg['found']} / {reg['true']}")
    table.add_row("region accuracy", f"{reg['accuracy']:.3f}")
    table.add_row("mean IoU", f"{reg['mean_iou']:.3f}")
    table.add_row("Kendall τ (β vs softness)", tau)
    for key, what in (("order_regions", "found regions"), ("order_pokes", "pokes")):
        value = reg.get(key)
        table.add_row(f"order of the {what} (1: right)", "n/a" if value is None else f"{value:.2f}")
    table.add_row("modulus", modulus_summary(report))
    t = report["timings"]
    table.add_row("time", f"{t['total_s'] + t['world_build_s']:.1f} s in all, world build "
                  f"{t['world_build_s']:.1f} s, compute per poke "
                  f"{max(t['per_poke_compute_s'], default=0):.2f} s at most")
    table.add_row("results", str(folder))
    out.print(table)


@app.command("explore")
@friendly_errors
def explore_command(
    scenario: Annotated[str | None, typer.Option(
        "--scenario", "-s", help="Built-in scenario name or YAML file.",
        show_default=str(HELP_DEFAULTS["scenario"]))] = None,
    seed: Annotated[int | None, typer.Option(
        help="Seed of world noise and poke choice.",
        show_default=str(HELP_DEFAULTS["seed"]))] = None,
    out: Annotated[Path | None, typer.Option(
        help="Run folder (default runs/<scenario>-explore-s<seed>-<time>).")] = None,
    strategy: Annotated[str | None, typer.Option(
        help="How the next poke is chosen: `exploration.strategy` (a name it does not know is "
        "refused with the list of choices).",
        show_default=str(HELP_DEFAULTS["exploration.strategy"]))] = None,
    threshold: Annotated[float | None, typer.Option(
        help="T_h: stop when max var(β) is below it (then any boundary pokes); "
        "with --field modulus, read as the same fraction of its prior variance.",
        show_default=str(HELP_DEFAULTS["exploration.threshold"]))] = None,
    max_pokes: Annotated[int | None, typer.Option(
        help="Most pokes to make.", show_default=str(HELP_DEFAULTS["exploration.max_pokes"]))
    ] = None,
    field: Annotated[str | None, typer.Option(
        help="The field regions, targets and the stop rule run on: `exploration.field`, 'beta' "
        "or 'modulus' (from the force–travel records).",
        show_default=str(HELP_DEFAULTS["exploration.field"]))] = None,
    config: ConfigOption = None,
    resume: Annotated[Path | None, typer.Option(help="Continue the killed run in this folder.")
                      ] = None,
    rerun: Annotated[bool, typer.Option("--rerun", help="Also write run.rrd (extra `rerun`).")
                     ] = False,
    environment: Annotated[str | None, typer.Option(
        help="Explore your own Environment instead of a simulated world: package.module:factory "
        "(docs/robot.md).")] = None,
    env_arg: Annotated[list[str] | None, typer.Option(
        "--env-arg", help="key=value passed to the --environment factory (repeat).")] = None,
    variance_max: VarianceMaxOption = None,
    json_path: JsonOption = None,
) -> None:
    """Explore a simulated world (or your own Environment): poke until the map field is known,
    then cut it into regions."""
    check_positive_options(variance_max=variance_max)
    overrides = run.RunOverrides(scenario=scenario, seed=seed, strategy=strategy,
                                 threshold=threshold, max_pokes=max_pokes, field=field)
    if environment is not None or env_arg:
        _explore_environment(environment, env_arg or [], scenario, resume, rerun, config,
                             overrides, out, json_path, variance_max)
        return
    cfg = run.explore_run_config(config, overrides, resume)
    shown = out_console(json_path)
    if scenario is None and resume is None:  # say what runs instead of running it silently
        source = f"from --config {config}" if config is not None else "the default"
        shown.print(f"no --scenario or --environment: exploring the simulated scenario "
                    f"{cfg.scenario!r} ({source}; list them with `deformap scenarios`)",
                    highlight=False)  # fmt: skip
    with progress(shown) as bar:
        output = run.explore_scenario(cfg, resume or out, resume=resume is not None, rerun=rerun,
                                      hooks=run_hooks(bar, poke_row=poke_row),
                                      variance_max=variance_max)  # fmt: skip
    _summary(shown, output.report, output.folder)
    emit_json(json_path, output.report)


@config_app.command("dump")
@friendly_errors
def config_dump(out: Annotated[Path | None, typer.Option(
        help="Write to this file instead of stdout.")] = None) -> None:
    """Write the full default run configuration as YAML, each setting under a comment giving its
    description, unit and bounds (a file that ``explore --config`` reads back)."""
    text = run.config_yaml(run.RunConfig(), described=True)
    if out is None:
        sys.stdout.write(text)
        return
    from deformap.run._folder import write_text

    write_text(out, text)  # a failure is one line naming the file (deformap._files)
    out_console(None).print(f"wrote {out}")


def _explore_environment(environment: str | None, env_args: list[str], scenario: str | None,
                         resume: Path | None, rerun: bool, config: Path | None,
                         overrides: Any, out: Path | None, json_path: Path | None,
                         variance_max: float | None) -> None:
    """``explore --environment``: a user's Environment, no ground truth to score against."""
    if environment is None:
        raise ConfigError("--env-arg goes with --environment package.module:factory; got no "
                          "--environment")
    if scenario is not None:
        raise ConfigError("--environment runs without --scenario: the robot's world is its own")
    cfg = run.explore_run_config(config, overrides, resume)
    args = run.parse_env_args(env_args)
    shown = out_console(json_path)
    try:
        with progress(shown) as bar:
            report, folder = run.explore_environment(
                environment, args, cfg, resume or out, resume=resume is not None,
                hooks=run_hooks(bar, poke_row=poke_row), variance_max=variance_max,
                rerun=rerun)
    except DeformapError as exc:  # a KeyboardInterrupt in the robot's code: 130, as a shell's
        if getattr(exc, "exit_code", 2) != 130:
            raise
        err_console.print(labelled("error:", "bold red", str(exc)), soft_wrap=True)
        raise typer.Exit(130) from None
    regions = report["regions"]
    found = "no region map" if regions is None else f"{len(regions['class_betas'])} region(s)"
    shown.print(f"{report['n_pokes']} pokes (stopped by {report['stop_reason']}), {found}, "
                f"map field {report['field']}; {modulus_summary(report)}; wrote {folder}",
                highlight=False)  # fmt: skip
    emit_json(json_path, report)
