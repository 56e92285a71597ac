"""``deformap study hardness``, ``deformap study cluster-size``, ``deformap study behaviour`` and
``deformap reproduce``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from deformap import run
from deformap.cli._app import (
    JsonOption,
    app,
    cell,
    check_positive_options,
    emit_json,
    friendly_errors,
    out_console,
    table,
)
from deformap.cli._progress import progress, run_hooks
from deformap.errors import InvalidArgumentError

__all__ = ["study_app"]

STUDY_HARDNESSES_HELP = "30, 60, 110, 150, 250 and rigid"
"""``deformap.eval.DEFAULT_HARDNESSES`` as ``--help`` shows it, written out (a test compares)."""

study_app = typer.Typer(help="Studies on homogeneous simulated foams (the paper's Fig. 5, and "
                        "what a press reveals beyond its stiffness).")
app.add_typer(study_app, name="study")

CoarseOption = Annotated[bool, typer.Option(help="Coarse FEM mesh (quick look).")]
SeedOption = Annotated[int, typer.Option(help="Seed of the worlds' noise.")]


def _kpa(row: dict[str, Any], key: str = "modulus_pa") -> str:
    if key == "modulus_pa" and row.get("rigid"):
        return "rigid"
    value = row.get(key)
    return "–" if value is None else f"{value / 1e3:.2f}"


def _hardness(value: float | None) -> str:
    return "rigid" if value is None else f"{value:g}"


@study_app.command("hardness")
@friendly_errors
def study_hardness(
    out: Annotated[Path | None, typer.Option(help="New folder for hardness.png and hardness.json "
                                             "(default runs/hardness-study-s<seed>-<time>).")
                   ] = None,
    seed: SeedOption = 0,
    hardness: Annotated[list[float] | None, typer.Option(
        help="Foams in N (repeat); rigid is added.", show_default=STUDY_HARDNESSES_HELP)] = None,
    coarse: CoarseOption = False,
    camera: Annotated[str | None, typer.Option(
        help="Camera preset: primesense | kinect-v1 | realsense-d435 (default primesense; with "
        "--full, the matrix's only camera).")] = None,
    thickness: Annotated[float | None, typer.Option(
        help="Foam thickness in metres (default 0.05; with --full, the matrix's only thickness).")
    ] = None,
    force: Annotated[float | None, typer.Option(help="Press force in N (default 0.6).")] = None,
    physics: Annotated[str | None, typer.Option(
        help="World physics: linear-fem | stiffening-foam | stiffening-fem (`world.physics`; "
        "default linear-fem; with --full, the matrix's only physics).")] = None,
    full: Annotated[bool, typer.Option(
        help="The whole matrix: every camera preset × thickness 0.03, 0.05, 0.10 m × every "
        "physics; --camera, --thickness or --physics given pins that axis.")] = False,
    protocol: Annotated[list[str] | None, typer.Option(
        help="Contact protocol whose β is fitted (repeat): force/quadratic | force/linear | "
        "pinned/quadratic | pinned/linear (default force/quadratic and the paper's "
        "pinned/quadratic).")] = None,
    element_size: Annotated[float | None, typer.Option(
        help="The world's in-plane FEM element size in metres (default 0.0075, a quick look; "
        "with --full 0.00375, a mesh that resolves a stiff foam's contact, about 5 times the "
        "time of a press): how much of E's error is the world's mesh. Not with --coarse.")
    ] = None,
    json_path: JsonOption = None,
) -> None:
    """β and Young's modulus against hardness for each contact protocol (paper Fig. 5a)."""
    check_positive_options(element_size=element_size)
    shown = out_console(json_path)
    if full:  # an axis given on the command line pins it; the others span the matrix
        condition: dict[str, Any] = {
            "full": True, "cameras": None if camera is None else [camera],
            "thicknesses_m": None if thickness is None else [thickness],
            "physics_names": None if physics is None else [physics]}
    else:
        condition = {"camera": camera, "thickness_m": 0.05 if thickness is None else thickness,
                     "physics": physics or "linear-fem"}
    try:
        with progress(shown) as bar:
            output = run.run_hardness_study(
                out, seed=seed, hardness=hardness, coarse=coarse, force_n=force,
                protocols=protocol, element_size_m=element_size, hooks=run_hooks(bar), **condition)
    except InvalidArgumentError as exc:  # the run's refusal of the mesh, named as the option
        if getattr(exc, "field", None) != "element_size_m":
            raise
        raise InvalidArgumentError(f"--element-size {getattr(exc, 'detail', exc)}") from None
    (_print_summary if full else _print_single)(shown, output.study)
    shown.print(f"wrote {' and '.join(map(str, output.files))}", highlight=False)
    emit_json(json_path, output.study)


def _print_single(shown: Any, study: dict[str, Any]) -> None:
    """One condition's study: a row per protocol and foam, then what the checks found."""
    where = ", ".join(f"{study[k]}" for k in ("camera", "physics") if k in study)
    rows = [(r["protocol"], _hardness(r["hardness_n"]), "refused", *["–"] * 4,
             _kpa(r, "true_modulus_pa")) if r.get("refused")
            else (r["protocol"], _hardness(r["hardness_n"]), f"{r['beta']:.3f}",
                  f"{r['beta_std']:.3f}", f"{r['beta_estimate_std']:.3f}",
                  f"{r['fit_error_m'] * 1e3:.3f}", _kpa(r), _kpa(r, "true_modulus_pa"))
            for r in study["rows"]]  # fmt: skip
    shown.print(table(f"β and E against hardness{f' ({where})' if where else ''}",
                      ("protocol", "hardness [N]", "β", "β spread", "β uncertainty",
                       "fit error [mm]", "E [kPa]", "true E [kPa]"), rows, left=("protocol",)))
    for reason in dict.fromkeys(r["refused"] for r in study["rows"] if r.get("refused")):
        shown.print(f"  refused: {reason}", highlight=False)
    for name, ok in study["monotone"].items():
        rises = "strictly rises" if ok else "does NOT strictly rise"
        shown.print(f"  {name}: β {rises} as hardness falls", highlight=False)
    if study.get("modulus_monotone") is not None:
        rises = "strictly rises" if study["modulus_monotone"] else "does NOT strictly rise"
        shown.print(f"  force–travel: E {rises} with hardness (rigid read rigid)", highlight=False)
    if study.get("n_refused"):
        shown.print(f"  {study['n_refused']} foam(s) refused by the world, left out of "
                    "these checks", highlight=False)  # fmt: skip


def _yes(value: bool | None) -> str:
    return "–" if value is None else ("yes" if value else "NO")


def _print_summary(shown: Any, study: dict[str, Any]) -> None:
    """The full study's summary: one line per condition, then one per physics."""
    rows = [(e["camera"], f"{e['thickness_m']:g}", e["physics"],
             cell(e["modulus_median_abs_rel_error"], ".1%"), cell(e["modulus_within_2sigma"], ".1%"),
             _yes(e["modulus_monotone"]), _yes(e["beta_monotone"]),
             "–" if e["beta_claimed_std"] is None or e["beta_spread"] is None
             else f"{e['beta_claimed_std']:.3f} / {e['beta_spread']:.3f}", f"{e['n_refused']}")
            for e in study["summary"]]  # fmt: skip
    shown.print(table("E and β against hardness, per condition (force/quadratic rows)",
                      ("camera", "H [m]", "physics", "median |E err|", "E within 2σ",
                       "E monotone, rigid", "β monotone", "β σ claimed / spread", "refused"),
                      rows, left=("camera", "physics")))  # H: the foam's thickness
    overall = [(o["physics"], f"{o['n_presses']}", f"{o['n_unread']}",
                cell(o["modulus_median_abs_rel_error"], ".1%"),
                cell(o["modulus_within_2sigma"], ".1%"), _yes(o["modulus_monotone"]),
                _yes(o["beta_monotone"]), f"{o['n_refused']}") for o in study["overall"]]
    shown.print(table("over every condition, per physics",
                      ("physics", "presses", "unread", "median |E err|", "E within 2σ",
                       "E monotone everywhere", "β monotone everywhere", "refused"),
                      overall, left=("physics",), no_wrap=False))


@study_app.command("cluster-size")
@friendly_errors
def study_cluster_size(
    out: Annotated[Path | None, typer.Option(
        help="New folder for cluster-size.png and .json "
        "(default runs/cluster-size-study-s<seed>-<time>).")] = None,
    seed: SeedOption = 0,
    coarse: CoarseOption = False,
    json_path: JsonOption = None,
) -> None:
    """Fit error and β against cluster size 2×2 … 6×6 (paper Fig. 5b)."""
    shown = out_console(json_path)
    with progress(shown) as bar:
        output = run.run_cluster_size_study(out, seed=seed, coarse=coarse, hooks=run_hooks(bar))
    rows = [(f"{r['cluster_size']}", _hardness(r["hardness_n"]), f"{r['beta']:.3f}",
             f"{r['fit_error_m'] * 1e3:.3f}") for r in output.study["rows"]]
    shown.print(table("fit error against cluster size",
                      ("k×k", "hardness [N]", "β", "fit error [mm]"), rows))
    shown.print(f"wrote {' and '.join(map(str, output.files))}", highlight=False)
    emit_json(json_path, output.study)


@study_app.command("behaviour")
@friendly_errors
def study_behaviour(
    out: Annotated[Path | None, typer.Option(
        help="New folder for behaviour.png and behaviour.json "
        "(default runs/behaviour-study-s<seed>-<time>).")] = None,
    seed: SeedOption = 0,
    full: Annotated[bool, typer.Option(
        help="The whole matrix: elastic foams 30-250 N, viscoelastic (g∞ 0.5, 0.8 × τ 0.5, 2 s), "
        "plastic (yield 1, 3 kPa), anisotropic (ratio 1.5, 3) × every camera preset × "
        "thickness 0.03, 0.10 m; --camera or --thickness given pins that axis.")] = False,
    camera: Annotated[list[str] | None, typer.Option(
        help="Camera preset (repeat): primesense | kinect-v1 | realsense-d435 (default "
        "primesense; with --full every preset).")] = None,
    thickness: Annotated[list[float] | None, typer.Option(
        help="Foam thickness in metres (repeat; default 0.03, with --full 0.03 and 0.10).")
    ] = None,
    kind: Annotated[list[str] | None, typer.Option(
        help="Only these materials (repeat): elastic | viscoelastic | plastic | anisotropic.")
    ] = None,
    force: Annotated[float | None, typer.Option(help="Press force in N (default 0.6).")] = None,
    coarse: CoarseOption = False,
    json_path: JsonOption = None,
) -> None:
    """The behaviour class each press reads (held 12 s, unloaded) against the material's own: a
    confusion matrix."""
    shown = out_console(json_path)
    with progress(shown) as bar:
        output = run.run_behaviour_study(out, seed=seed, full=full, cameras=camera,
                                         thicknesses_m=thickness, kinds=kind, force_n=force,
                                         coarse=coarse, hooks=run_hooks(bar))  # fmt: skip
    study = output.study
    reads = list(next(iter(study["confusion"].values())))
    rows = [(truth, *(f"{counts[r]}" for r in reads), f"{sum(counts.values())}")
            for truth, counts in study["confusion"].items()]
    shown.print(table("behaviour read against the world's truth (presses)",
                      ("truth", *(f"read {r}" for r in reads), "presses"), rows,
                      left=("truth",)))
    for c in study["by_condition"]:
        shown.print(f"  {c['camera']}, {c['thickness_m']:g} m: {c['n_presses']} presses, "
                    f"right {cell(c['right'], '.1%')}, elastic flagged otherwise "
                    f"{cell(c['elastic_flagged'], '.1%')}", highlight=False)
    shown.print(f"  all: {study['n_presses']} presses, right {cell(study['right'], '.1%')}, "
                f"elastic flagged otherwise {cell(study['elastic_flagged'], '.1%')}, unknown "
                f"{cell(study['unknown'], '.1%')}", highlight=False)
    e = study["errors"]
    shown.print(f"  against the world's: relaxation within {e['relaxation']['tolerance']:g} "
                f"{e['relaxation']['within']}/{e['relaxation']['n']}, time constant within "
                f"{e['tau']['tolerance']:.0%} {e['tau']['within']}/{e['tau']['n']}, residual "
                f"dent within {e['residual_dent']['tolerance'] * 1e3:g} mm "
                f"{e['residual_dent']['within']}/{e['residual_dent']['n']}", highlight=False)
    shown.print(f"wrote {' and '.join(map(str, output.files))}", highlight=False)
    emit_json(json_path, study)


@app.command("reproduce")
@friendly_errors
def reproduce_command(
    out: Annotated[Path | None, typer.Option(
        help="New folder: one run per scenario, table.md, table.json "
        "(default runs/table-i-reproduce-s<seed>-<time>).")] = None,
    seed: Annotated[int, typer.Option(help="Seed of every run.")] = 0,
    strategy: Annotated[str | None, typer.Option(
        help="`exploration.strategy` of every run (default: the config's; a name it does not "
        "know is refused with the list of choices).")] = None,
    config: Annotated[Path | None, typer.Option(help="Run configuration YAML.")] = None,
    scenario: Annotated[list[str] | None, typer.Option(
        "--scenario", help="Only this scenario (repeat).")] = None,
    json_path: JsonOption = None,
) -> None:
    """All six scenarios of the paper's Table I, beside the paper's numbers."""
    base = run.apply_overrides(run.load_run_config(config),
                               run.RunOverrides(seed=seed, strategy=strategy))  # fmt: skip
    shown = out_console(json_path)

    def show(row: dict[str, Any]) -> None:
        tau = cell(row["kendall_tau"], ".2f")
        shown.print(f"  {row['scenario']:<28} pokes {row['pokes']:>2}  regions "
                    f"{row['regions_found']}/{row['regions_true']}  accuracy {row['accuracy']:.3f}"
                    f"  τ {tau}  {row['time_s']:.1f} s", highlight=False)

    with progress(shown) as bar:
        output = run.reproduce(out, base=base, scenarios=scenario, on_run=show,
                               hooks=run_hooks(bar, step_rows=False))  # fmt: skip
    shown.print(output.markdown)
    shown.print(f"wrote {output.folder / 'table.md'} and {output.folder / 'table.json'} "
                f"({len(output.table['rows'])} runs)", highlight=False)  # fmt: skip
    emit_json(json_path, output.table)
