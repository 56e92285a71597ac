"""``deformap bench speed | world | io | memory``: tables with a baseline measured in the same run;
``deformap bench worlds``: strategies and fields over many random worlds."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.table import Table

from deformap import eval as evaluation
from deformap.cli._app import (
    JsonOption,
    app,
    cell,
    emit_json,
    friendly_errors,
    out_console,
    table,
)
from deformap.cli._progress import progress, run_hooks

__all__ = ["bench_app"]

bench_app = typer.Typer(
    help="Speed and memory benchmarks (tables with a baseline measured in the same run)."
)
app.add_typer(bench_app, name="bench")

SeedOption = Annotated[int, typer.Option(help="Seed of the synthetic data.")]
QuickOption = Annotated[bool, typer.Option(help="Smaller sizes (a smoke run).")]


@bench_app.command("speed")
@friendly_errors
def bench_speed(json_path: JsonOption = None, seed: SeedOption = 0, quick: QuickOption = False) -> None:
    """Surface GP (exact vs grid) and the β sweep (batched vs per-β loop), same run."""
    rng = np.random.default_rng(seed)
    shown = out_console(json_path)
    with progress(shown, "timing the surface GP and the β sweep"):
        gp_rows = evaluation.bench_surface_gp((1000, 2000) if quick else (3000, 6000, 12000), rng=rng)
        sweep = evaluation.bench_beta_sweep(n_particles_side=20 if quick else 40, rng=rng)
    shown.print(table(
        "surface GP → mean and std on the 120×80 grid (σw 4 cm, σn 2 mm)",
        ("points", "exact [s]", "grid [s]", "speed-up", "max |Δmean| [µm]", "max Δstd [%]"),
        [(str(r["n_points"]), f"{r['exact_s']:.3f}", f"{r['grid_s']:.3f}", f"{r['speedup']:.0f}×",
          f"{r['max_mean_dev_m'] * 1e6:.2f}", f"{r['max_rel_std_dev'] * 100:.3f}") for r in gp_rows],
    ))  # fmt: skip
    shown.print(table(
        "β estimation (converged, 3×3 clusters)",
        ("β values", "particles", "batched [s]", "per-β loop [s]", "speed-up"),
        [(str(sweep["n_beta"]), str(sweep["n_particles"]), f"{sweep['batched_s']:.3f}",
          f"{sweep['loop_s']:.3f}", f"{sweep['speedup']:.1f}×")],
    ))  # fmt: skip
    emit_json(json_path, {"surface_gp": gp_rows, "beta_sweep": sweep})


@bench_app.command("world")
@friendly_errors
def bench_world_command(
    json_path: JsonOption = None,
    scenario: Annotated[str, typer.Option(help="Scenario name or YAML file.")] = (
        "heterogeneous-60-110-rigid"
    ),
    seed: Annotated[int, typer.Option(help="Seed of the noise.")] = 0,
    coarse: Annotated[bool, typer.Option(help="Coarse test mesh instead of the default.")] = False,
) -> None:
    """Time world construction (with factorisation), one press, one observation and one poke's
    compute (with its force–travel record, and camera-only beside it)."""
    from deformap.world import WorldConfig  # the whole simulated world: only when benchmarked

    shown = out_console(json_path)
    with progress(shown, "building and pressing the world"):
        config = WorldConfig.coarse() if coarse else WorldConfig()
        result = evaluation.bench_world(scenario=scenario, rng=np.random.default_rng(seed),
                                        config=config)  # fmt: skip
    goals = {"construction_s": 20.0, "press_s": 1.0, "observe_s": 0.5, "poke_compute_s": 1.0,
             "poke_compute_camera_only_s": 1.0}
    rows = [(key, f"{value:.4g}" if isinstance(value, float)
             else "n/a (not the linear FEM)" if value is None else str(value),
             f"≤ {goals[key]:g} s" if key in goals
             else "baseline of press_s" if key == "press_load_by_load_s" else "")
            for key, value in result.items() if key != "scenario"]  # fmt: skip
    shown.print(table(f"simulated world: {result['scenario']}", ("measure", "value", "goal"), rows))
    emit_json(json_path, result)


@bench_app.command("io")
@friendly_errors
def bench_io_command(
    json_path: JsonOption = None,
    seed: Annotated[int, typer.Option(help="Seed of the synthetic cloud.")] = 0,
) -> None:
    """Reading a 300,000-point binary PCD and one PointCloud2 message of that size."""
    shown = out_console(json_path)
    with progress(shown, "reading 300,000 points"):
        row = evaluation.bench_io(n_points=300_000, rng=np.random.default_rng(seed))
    rows = [(key, f"{value:.4f}") for key, value in row.items()
            if isinstance(value, float) and key != "goal_s"]  # fmt: skip
    shown.print(table("reading 300,000 points (best of repeats; goal < 0.5 s each)",
                       ("what", "seconds"), rows))  # fmt: skip
    emit_json(json_path, row)


def _memory_table(title: str, rows: list[dict[str, Any]], size_label: str) -> Table:
    by_key = {(r["case"], r["size"]): r for r in rows}
    cells = []
    for r in rows:
        base = by_key.get((r["baseline"], r["size"]))
        if r["baseline"] is None:
            base_text, ratio = "–", "(baseline)"
        elif base is None:
            base_text, ratio = f"{r['baseline'].split('-', 1)[1]} not run", ""
        else:
            base_text = f"{base['traced_peak_mib']:.1f}"
            x = base["traced_peak_mib"] / r["traced_peak_mib"]
            ratio = f"{x:.1f}× less" if x >= 1 else f"{1 / x:.1f}× more"
        added = "n/a" if r["rss_added_mib"] is None else f"{r['rss_added_mib']:.1f}"
        cells.append((f"{r['size']:,}", r["case"].split("-", 1)[1], f"{r['traced_peak_mib']:.1f}",
                      added, f"{r['seconds']:.2f}", base_text, ratio))  # fmt: skip
    return table(title, (size_label, "path", "traced [MiB]", "RSS+ [MiB]", "time [s]",
                          "baseline [MiB]", "vs baseline"), cells)  # fmt: skip


@bench_app.command("memory")
@friendly_errors
def bench_memory_command(json_path: JsonOption = None, seed: SeedOption = 0,
                         quick: QuickOption = False) -> None:  # fmt: skip
    """Peak memory: surface GP (grid vs exact) and one β estimation (batched vs per-β loop)."""
    sizes, exact_max, side = ((500, 2000), 2000, 12) if quick else ((3000, 12000), 3000, 40)
    shown = out_console(json_path)
    with progress(shown, "measuring peak memory, one process per case"):
        result = evaluation.bench_memory(gp_sizes=sizes, exact_max_points=exact_max,
                                         beta_side=side, seed=seed)  # fmt: skip
    dense = ", ".join(f"{n:,}: {n * n * 8 / 2**20:,.0f} MiB" for n in sizes if n > exact_max)
    note = f"; exact's N×N covariance alone at {dense}" if dense else ""
    shown.print(_memory_table(f"peak memory, surface GP → mean and std on the 120×80 grid{note}",
                              result["surface_gp"], "points"))  # fmt: skip
    shown.print(_memory_table("peak memory, one β estimation (converged, 3×3 clusters)",
                              result["beta_estimation"], "side"))  # fmt: skip
    shown.print("traced: numpy + Python (tracemalloc); RSS+: resident set rise, all libraries; "
                "one fresh process per row; baseline: the same size", style="dim")
    emit_json(json_path, result)


def _names(values: list[str] | None) -> tuple[str, ...] | None:
    """Names given as repeated options, each possibly a comma-separated list."""
    if not values:
        return None
    return tuple(n.strip() for v in values for n in v.split(",") if n.strip())


NamesOption = Annotated[list[str] | None, typer.Option(
    help="Comma-separated (or repeated); default: all.", show_default=False)]
SetOption = Annotated[list[str] | None, typer.Option(
    "--set", metavar="KEY=VALUE",
    help="An exploration setting for every world, as in a config file's exploration section "
         "(dotted key, YAML value: --set merge_seams=false --set beta_field.signal_std=0.25); "
         "repeatable.", show_default=False)]


@bench_app.command("worlds")
@friendly_errors
def bench_worlds_command(
    worlds: Annotated[int, typer.Option(help="How many random worlds.")] = 100,
    seed: Annotated[int, typer.Option(help="Seed of the worlds (world i is drawn from "
                                           "(seed, i) alone).")] = 0,
    families: NamesOption = None,
    strategies: NamesOption = None,
    fields: NamesOption = None,
    physics: Annotated[list[str] | None, typer.Option(
        help="World physics drawn from (linear-fem, stiffening-foam, stiffening-fem); "
             "default: all.",
        show_default=False)] = None,
    appearances: Annotated[list[str] | None, typer.Option(
        "--appearance", "--appearances",
        help="Appearance families painting every world (plain, informative, textured, shared, "
             "split, misleading); each but plain mapped twice, blind and with the appearance "
             "prior; comma-separated (or repeated); default: plain.",
        show_default=False)] = None,
    cuts: Annotated[list[str] | None, typer.Option(
        "--cuts", "--cut",
        help="Region labels (exploration.region_labels), each scored on the same pokes; "
             "comma-separated (or repeated); default: all.", show_default=False)] = None,
    max_pokes: Annotated[int, typer.Option(help="Pokes per world and combination.")] = 12,
    assignments: SetOption = None,
    coarse: Annotated[bool, typer.Option(
        help="The coarse test mesh and camera: a third of the cost, a smoke run only (its 2 cm "
             "mesh reads E far off).")] = False,
    workers: Annotated[int, typer.Option(help="Processes of the local pool.")] = 1,
    scheduler: Annotated[str | None, typer.Option(
        help="A dask.distributed scheduler's address (tcp://host:8786) instead of the pool.")
    ] = None,
    out: Annotated[Path | None, typer.Option(
        help="The folder (new, or this benchmark's own to resume).")] = None,
    json_path: JsonOption = None,
) -> None:
    """Map many seeded random worlds with every strategy × field; accuracy after every poke,
    curves per layout family (or per appearance family, blind beside the prior) and the pokes a
    good map takes (resumes in its --out)."""
    from deformap import run

    given: dict[str, Any] = {"families": _names(families), "strategies": _names(strategies),
                             "fields": _names(fields), "physics": _names(physics),
                             "cuts": _names(cuts), "appearances": _names(appearances)}
    exploration = run.exploration_with(run.parse_assignments(assignments or ()))
    config = run.WorldsBenchConfig(
        worlds=worlds, seed=seed, max_pokes=max_pokes, exploration=exploration, coarse=coarse,
        workers=workers, scheduler=scheduler, **{k: v for k, v in given.items() if v is not None})
    shown = out_console(json_path)
    with progress(shown) as bar:
        output = run.bench_worlds(config, out, hooks=run_hooks(bar))
    _show_worlds_summary(shown, output, config.worlds, config.max_pokes, json_path)


def _show_worlds_summary(shown: Any, output: Any, worlds: int, max_pokes: int,
                         json_path: Path | None) -> None:
    summary = output.summary
    rows = [(name + (" (best)" if name == summary["best"] else ""), str(s["worlds"]),
             cell(s["median_pokes_to_accuracy_0.9"], "g"),
             cell(s.get("mean_pokes_to_accuracy_0.9"), ".1f"),
             cell(s["median_pokes_to_stay_0.9"], "g"), cell(s["share_reaching_0.9"], ".0%"),
             cell(s["final_accuracy_median"], ".3f"), cell(s["modulus_error_median"], ".2f"))
            for name, s in summary["strategies"].items()]  # fmt: skip
    shown.print(table(
        f"{len(rows)} combinations over {worlds} worlds, {max_pokes} pokes "
        f"(a world never at 0.9 counts {max_pokes + 1}; best: fewest mean pokes)",
        ("strategy/field/cut", "worlds", "median pokes to 0.9", "mean", "to stay", "reach 0.9",
         "final accuracy", "E error"),
        rows))  # fmt: skip
    _show_paired(shown, summary)
    shown.print(f"{output.computed} worlds computed in {output.seconds:.0f} s → {output.folder}",
                highlight=False)
    emit_json(json_path, summary)


def _show_paired(shown: Any, summary: dict[str, Any]) -> None:
    """The appearance families, where one was mapped blind beside the prior: one row per family ×
    combination."""
    from deformap.eval import paired_cells

    families = summary.get("appearance", {})
    if not any(e["blind"] for per in families.values() for e in per.values()):
        return
    rows = [(family, name, *paired_cells(e)) for family, per in families.items()
            for name, e in per.items()]
    shown.print(table(
        "appearance: blind / prior on the same worlds and presses (difference: prior − blind, "
        "mean over worlds, 95 % t interval)",
        ("appearance", "strategy/field/cut", "worlds", "median pokes to 0.9", "mean",
         "difference", "final accuracy", "right count"), rows))  # fmt: skip


@bench_app.command("rescore")
@friendly_errors
def bench_rescore_command(
    source: Annotated[Path, typer.Argument(help="A `bench worlds` folder whose worlds stored "
                                                "their pokes.", show_default=False)],
    out: Annotated[Path, typer.Option(help="The new folder for the rescored benchmark.",
                                      show_default=False)],
    cuts: Annotated[list[str] | None, typer.Option(
        "--cuts", "--cut", help="Region labels to score; comma-separated (or repeated); "
                                "default: the source's.", show_default=False)] = None,
    assignments: Annotated[list[str] | None, typer.Option(
        "--set", metavar="KEY=VALUE",
        help="A region rule to score under instead of the source's (merge_seams or "
             "split_by_place, e.g. --set merge_seams=false); repeatable.",
        show_default=False)] = None,
    json_path: JsonOption = None,
) -> None:
    """Score a worlds benchmark's pokes again under other cuts or region rules, without pressing
    again (seconds a world)."""
    from deformap import run

    shown = out_console(json_path)
    with progress(shown) as bar:
        output = run.rescore_worlds(source, out, cuts=_names(cuts),
                                    changes=run.parse_assignments(assignments or ()),
                                    hooks=run_hooks(bar))  # fmt: skip
    settings = output.summary["settings"]
    _show_worlds_summary(shown, output, settings["worlds"], settings["max_pokes"], json_path)
