"""``deformap record-sim``, ``deformap map`` and ``deformap estimate``: recorded sessions."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from deformap import run
from deformap.cli._app import (
    JsonOption,
    VarianceMaxOption,
    app,
    check_positive_options,
    emit_json,
    fail,
    friendly_errors,
    out_console,
    warn,
)
from deformap.cli._explore import HELP_DEFAULTS, ConfigOption, modulus_summary
from deformap.cli._progress import modulus_text, progress, run_hooks
from deformap.errors import InvalidArgumentError

if TYPE_CHECKING:  # the CLI loads the estimator only when a command runs
    from deformap.explore import PokeRecord

__all__ = ["poke_row"]


def poke_row(p: PokeRecord) -> str:
    """One progress line of a recorded poke."""
    return (f"  poke {p.index + 1:>2}  contact ({p.contact_xy[0]:.3f}, {p.contact_xy[1]:.3f}) m"
            f"  β = {p.beta:.3f} ± {p.beta_std:.3f}{modulus_text(p)}"
            f"  max var {p.max_variance_after:.4f}")  # fmt: skip


@app.command("record-sim")
@friendly_errors
def record_sim_command(
    scenario: Annotated[str, typer.Option(
        "--scenario", "-s", help="Built-in scenario name or YAML file.")],
    out: Annotated[Path | None, typer.Option(
        help="New session folder (default runs/<scenario>-record-s<seed>-<time>).")] = None,
    format: Annotated[str, typer.Option(
        "--format", help="folder | mcap | sqlite3: a session; raw-mcap: the bag a robot "
        "records (robot.mcap, and live.json with the live run's pokes).")] = "folder",
    rig: Annotated[Path | None, typer.Option(
        help="raw-mcap: YAML of the recording rig (rates, per-axis force noise, stamp skew, "
             "force ramp or step, frame names; keys in docs/robot.md).")] = None,
    seed: Annotated[int | None, typer.Option(
        help="Seed of world noise and poke choice.",
        show_default=str(HELP_DEFAULTS["seed"]))] = None,
    pokes: Annotated[int | None, typer.Option(
        "--pokes", help="Most pokes to make.",
        show_default=str(HELP_DEFAULTS["exploration.max_pokes"]))] = None,
    config: ConfigOption = None,
    json_path: JsonOption = None,
) -> None:
    """Explore a simulated world; record what it returned as a session (see docs)."""
    overrides = run.RunOverrides(scenario=scenario, seed=seed, max_pokes=pokes)
    cfg = run.apply_overrides(run.load_run_config(config), overrides)
    shown = out_console(json_path)
    with progress(shown) as bar:
        output = run.record_simulation(cfg, out, format=format, rig=rig,
                                       hooks=run_hooks(bar, poke_row=poke_row))  # fmt: skip
    shown.print(f"wrote {output.session_file} ({output.n_pokes} pokes, {output.format} form)",
                highlight=False)  # fmt: skip
    if output.format == "raw-mcap":
        shown.print(f"map it with: deformap map {output.session_file}", highlight=False)
    emit_json(json_path, dataclasses.asdict(output))  # the paths as strings


@app.command("map")
@friendly_errors
def map_command(
    session: Annotated[Path, typer.Argument(
        metavar="SESSION", help="Session folder or its session.yaml, or a "
        "bag as a robot records it (.mcap, .db3 or rosbag2 folder).")],
    out: Annotated[Path | None, typer.Option(
        help="Result folder (default runs/<session>-map-s<seed>-<time>).")] = None,
    config: Annotated[Path | None, typer.Option(
        help="Run configuration YAML; default: the session's own.")] = None,
    seed: Annotated[int | None, typer.Option(
        help="Seed of the surface fit; default: the session's.")] = None,
    figures: Annotated[bool, typer.Option(help="Write map.png and poke-NN.png.")] = True,
    variance_max: VarianceMaxOption = None,
    rerun: Annotated[bool, typer.Option("--rerun", help="Also write run.rrd (extra `rerun`).")
                     ] = False,
    layout: Annotated[str, typer.Option(
        help="auto | session | raw: raw reads SESSION as a bag a robot recorded (camera, force "
             "sensor, /tf); auto tells them apart.")] = "auto",
    raw_config: Annotated[Path | None, typer.Option(
        help="Raw bag: settings YAML (default: deformap.yaml in a rosbag2 folder, NAME.deformap"
             ".yaml beside NAME.mcap; keys in docs/robot.md).")] = None,
    cloud_topic: Annotated[str | None, typer.Option(
        help="Raw bag: the organised PointCloud2 topic; default: the bag's one such topic.")
    ] = None,
    wrench_topic: Annotated[str | None, typer.Option(
        help="Raw bag: the WrenchStamped topic; default: the bag's one such topic.")] = None,
    world_frame: Annotated[str | None, typer.Option(
        help="Raw bag: the table's frame, z up; default: world, else the camera's root frame.")
    ] = None,
    tip_frame: Annotated[str | None, typer.Option(
        help="Raw bag: the frame at the tip's centre, z along the stick; default: found (the "
             "lowest frame on the force sensor's rigid body, z up).")] = None,
    force_frame: Annotated[str | None, typer.Option(
        help="Raw bag: the force sensor's frame; default: the wrench's header.frame_id.")
    ] = None,
    press_force: Annotated[float | None, typer.Option(
        help="Raw bag: the commanded force, N; default the run config's exploration.force_n.")
    ] = None,
    stamp_tolerance: Annotated[float | None, typer.Option(
        help="Largest time between a press and its frame or transform (raw bag, default 0.05), "
             "or a poke's stamp and its messages (bag-form session, default 0: exact), s.")
    ] = None,
    json_path: JsonOption = None,
) -> None:
    """Map a recorded session (or a robot's raw bag): its pokes, in order, through the live
    loop's mapper."""
    check_positive_options(press_force=press_force, stamp_tolerance=stamp_tolerance,
                           variance_max=variance_max)
    cfg = None if config is None else run.load_run_config(config)
    raw_settings = {"cloud_topic": cloud_topic, "wrench_topic": wrench_topic,
                    "world_frame": world_frame, "tip_frame": tip_frame,
                    "force_frame": force_frame, "force_n": press_force,
                    "stamp_tolerance_s": stamp_tolerance}  # fmt: skip
    shown = out_console(json_path)
    with progress(shown) as bar:
        output = run.map_recorded_session(
            session, out, config=cfg, seed=seed, figures=figures, variance_max=variance_max,
            hooks=run_hooks(bar, poke_row=poke_row), layout=layout,  # type: ignore[arg-type]
            raw_config=raw_config, raw_settings=raw_settings, rerun=rerun)
    report = output.report
    read_with = report["source"].get("found") if report.get("form") == "raw" else None
    for key, value in (read_with or {}).items():  # what the bag was read with, and why
        shown.print(f"  {key}: {value['value']} ({value['from']})", highlight=False)
    for line in report["warnings"]:
        warn(line)  # once: the log line of a skipped poke printed it as it happened
    regions = report["regions"]
    found = ("no poke usable" if regions is None
             else f"{len(regions['class_betas'])} region class(es)")
    scored = (f", accuracy {regions['accuracy']:.3f} against the ground truth"
              if regions is not None and "accuracy" in regions else "")
    shown.print(f"{report['n_pokes']} of {len(output.session)} pokes used, {found}{scored}; "
                f"wrote {output.folder / 'report.json'}", highlight=False)  # fmt: skip
    shown.print(f"modulus: {modulus_summary(report)}", highlight=False)
    emit_json(json_path, report)
    if regions is None:  # the report is written (nothing lost), but there is no map
        fail(f"no poke of the session {str(session)!r} was usable: expected at least one, got 0 "
             f"of {len(output.session)} (the warnings and report.json say why)")


def _three_numbers(option: str, values: tuple[str, str, str] | None, what: str
                   ) -> tuple[float, float, float]:
    """``values`` of a three-number option as floats; refused, naming the option, when absent,
    short (the parser took the next option's name as a value) or not numbers."""
    if values is None:
        raise InvalidArgumentError(f"{option} is required: three numbers, {what}; got none")
    given = [v for v in values if not v.startswith("--")]
    if len(given) < 3:
        raise InvalidArgumentError(f"{option} takes three numbers, {what}; got {len(given)}"
                                   f" ({' '.join(given) or 'none'}) before {values[len(given)]}")
    try:
        return (float(values[0]), float(values[1]), float(values[2]))
    except ValueError:
        raise InvalidArgumentError(f"{option} takes three numbers, {what}; got "
                                   f"{' '.join(values)}") from None


def _stiffness_line(report: dict[str, Any]) -> str:
    """One line on what the force–travel record gave: E with σ, rigid, or why none."""
    est = report["stiffness"]
    if est is None:
        return f"E: none from the record ({report['stiffness_error']})"
    if est["rigid"]:
        return f"rigid: stiffness above {est['stiffness_lower_n_per_m']:.4g} N/m"
    h = report["layer_thickness_m"]
    return (f"E = {est['modulus_pa'] / 1e3:.4g} ± {est['modulus_std_pa'] / 1e3:.2g} kPa, "
            f"k = {est['stiffness_n_per_m']:.4g} N/m (layer {h * 1e3:.1f} mm thick)")


@app.command("estimate", context_settings={"ignore_unknown_options": True,
                                           "allow_extra_args": True})  # fmt: skip
@friendly_errors
def estimate_command(
    ctx: typer.Context,
    before: Annotated[Path, typer.Option(
        "--before", help="Cloud of the undisturbed surface (PCD, PLY, NPZ).")],
    after: Annotated[Path, typer.Option("--after", help="Cloud while pressing.")],
    # --contact, --force, --tip-radius: required here, not by the parser, so that a value missing
    # from --contact (which then takes the next option's name as its third) is named below
    contact: Annotated[tuple[str, str, str] | None, typer.Option(
        "--contact", metavar="X Y Z", help="Tip centre X Y Z at the press, metres. [required]")
    ] = None,
    force: Annotated[tuple[str, str, str] | None, typer.Option(
        "--force", metavar="FX FY FZ", help="Force FX FY FZ on the surface, newtons. [required]")
    ] = None,
    tip_radius: Annotated[float | None, typer.Option(
        "--tip-radius", help="Radius of the spherical tip, metres. [required]")] = None,
    robot_hull: Annotated[Path | None, typer.Option(
        "--robot-hull", help="Cloud file of points whose hull covers stick and hand.")] = None,
    record: Annotated[Path | None, typer.Option(
        "--record", help="The press's force–travel record, a CSV with columns travel_m (or "
        "travel_mm) and force_n: adds its stiffness and E.")] = None,
    out: Annotated[Path | None, typer.Option(
        help="New folder for estimate.json, beta-curve.png, poke.png.")] = None,
    units: Annotated[str, typer.Option(help="Units of the cloud files: m | mm.")] = "m",
    config: Annotated[Path | None, typer.Option(
        help="Run configuration YAML (its exploration part).")] = None,
    seed: Annotated[int, typer.Option(help="Seed of the surface fit.")] = 0,
    json_path: Annotated[Path | None, typer.Option(
        "--json", help="Also write the result as JSON to this file (- for stdout; "
        "the default without --out).")] = None,
) -> None:
    """β of one poke from two clouds and the tactile contact (world frame, SI units); with its
    force–travel record also E."""
    tip_center = _three_numbers("--contact", contact, "the tip centre X Y Z in metres")
    force_n = _three_numbers("--force", force, "the force FX FY FZ in newtons")
    if tip_radius is None:
        raise InvalidArgumentError("--tip-radius is required: the tip's radius in metres; got none")
    if ctx.args:
        raise InvalidArgumentError(f"estimate takes no argument {ctx.args[0]!r}; got "
                                   f"{' '.join(ctx.args)} (see deformap estimate --help)")
    if json_path is None and out is None:  # the JSON alone on stdout, for pipes
        json_path = Path("-")
    output = run.estimate_one_poke(
        before=before, after=after, tip_center=tip_center, force=force_n, tip_radius_m=tip_radius,
        config=run.load_run_config(config), robot_hull=robot_hull, record=record, units=units,
        seed=seed, out=out)
    r = output.report
    shown = out_console(json_path)
    shown.print(f"β = {r['beta']:.3f} ± {r['beta_std']:.3f} ({r['n_roi_points']} ROI points)")
    if record is not None:
        shown.print(_stiffness_line(r))
    if output.folder is not None:
        shown.print(f"wrote {output.folder / 'estimate.json'}, beta-curve.png and poke.png")
    emit_json(json_path, r)
    sys.stdout.flush()
