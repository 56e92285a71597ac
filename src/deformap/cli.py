"""The ``deformap`` command.

Every sub-command turns a :class:`~deformap.errors.DeformapError` into one line on stderr and exit
code 2: a user sees what to fix, never a traceback.
"""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Annotated, Any, TypeVar

import numpy as np
import typer
from rich.console import Console

from deformap import __version__
from deformap.errors import ConfigError, DeformapError

__all__ = ["app", "main"]

console = Console()
err_console = Console(stderr=True)

app = typer.Typer(
    name="deformap",
    help="Map how deformable a surface is, region by region, from a few robot pokes.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
bench_app = typer.Typer(
    help="Speed and memory benchmarks (tables with a baseline measured in the same run)."
)
app.add_typer(bench_app, name="bench")

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


# ---- exploration commands ----
config_app = typer.Typer(help="The run configuration (YAML).")
app.add_typer(config_app, name="config")


def _default_out(scenario: str, seed: int) -> Path:
    stem = Path(scenario).stem if scenario.endswith((".yaml", ".yml")) else scenario
    return Path("runs") / f"{stem}-s{seed}-{time.strftime('%Y%m%d-%H%M%S')}"


def _progress_row(poke: Any) -> None:
    r = poke.record
    t = r.timings
    console.print(
        f"  poke {r.index + 1:>2}  target ({r.target_xy[0]:.3f}, {r.target_xy[1]:.3f}) m"
        f"  force {r.force_n:.2f} N  β = {r.beta:.3f} ± {r.beta_std:.3f}"
        f"  max var {r.max_variance_after:.4f}"
        + (f"  plan: {r.planned_after} more" if r.planned_after is not None else "")
        + ("  boundary poke" if r.purpose == "boundary" else "")
        + f"  [dim](compute {t.compute_s:.2f} s, world {t.environment_s or 0.0:.2f} s)[/]",
        highlight=False,
    )


def _summary(report: dict[str, Any], folder: Path) -> None:
    from rich.table import Table

    reg = report["regions"]
    tau = "n/a (one region)" if reg["kendall_tau"] is None else f"{reg['kendall_tau']:.2f}"
    table = Table(title=f"{report['scenario']} (seed {report['seed']})", show_header=False)
    table.add_row("pokes", f"{report['n_pokes']} (stopped by {report['stop_reason']})")
    table.add_row("max β variance", f"{report['max_variance']:.4f}")
    table.add_row("regions found / true", f"{reg['found']} / {reg['true']}")
    table.add_row("region accuracy", f"{reg['accuracy']:.3f}")
    table.add_row("mean IoU", f"{reg['mean_iou']:.3f}")
    table.add_row("Kendall τ (β vs softness)", tau)
    t = report["timings"]
    table.add_row(
        "time",
        f"{t['total_s'] + t['world_build_s']:.1f} s in all, world build "
        f"{t['world_build_s']:.1f} s, compute per poke "
        f"{max(t['per_poke_compute_s'], default=0):.2f} s at most",
    )
    table.add_row("results", str(folder))
    console.print(table)


@app.command("explore")
@friendly_errors
def explore_command(
    scenario: Annotated[
        str | None, typer.Option("--scenario", "-s", help="Built-in scenario name or YAML file.")
    ] = None,
    seed: Annotated[int | None, typer.Option(help="Seed of world noise and poke choice.")] = None,
    out: Annotated[
        Path | None, typer.Option(help="Run folder (default runs/<scenario>-s<seed>-<time>).")
    ] = None,
    strategy: Annotated[
        str | None, typer.Option(help="paper | max-variance | min-max-variance | planned.")
    ] = None,
    threshold: Annotated[
        float | None,
        typer.Option(help="T_h: stop when max var(β) is below it (then any boundary pokes)."),
    ] = None,
    max_pokes: Annotated[int | None, typer.Option(help="Most pokes to make.")] = None,
    config: Annotated[
        Path | None, typer.Option(help="Run configuration YAML (see `config dump`).")
    ] = None,
    resume: Annotated[
        Path | None, typer.Option(help="Continue the killed run in this folder.")
    ] = None,
    rerun: Annotated[
        bool, typer.Option("--rerun", help="Also write run.rrd (extra `rerun`).")
    ] = False,
) -> None:
    """Explore a simulated world: poke until the β-field is known, then cut it into regions."""
    import dataclasses

    from deformap.cloud.io._common import path_kind
    from deformap.eval import RunConfig, load_run_config, run_experiment

    if resume is not None:
        if config is not None:
            raise ConfigError("--resume reads the run's own config.yaml; do not pass --config too")
        if path_kind(resume / "config.yaml") != "file":  # a run writes it before anything else
            raise ConfigError(
                f"cannot resume {str(resume)!r}: it holds no config.yaml, so no run started "
                "there; start one without --resume"
            )
        cfg = load_run_config(resume / "config.yaml")
        folder = resume
    else:
        cfg = load_run_config(config)
    overrides: dict[str, Any] = {}
    if scenario is not None:
        overrides["scenario"] = scenario
    if seed is not None:
        overrides["seed"] = seed
    explore_over: dict[str, Any] = {
        k: v
        for k, v in {"strategy": strategy, "threshold": threshold, "max_pokes": max_pokes}.items()
        if v is not None
    }
    if explore_over:
        overrides["exploration"] = dataclasses.replace(cfg.exploration, **explore_over)
    if resume is not None and overrides:
        changed = sorted(overrides)
        if dataclasses.replace(cfg, **overrides) != cfg:
            raise ConfigError(
                f"cannot resume {str(resume)!r} with different settings ({', '.join(changed)}); "
                "drop those options"
            )
    cfg = dataclasses.replace(cfg, **overrides) if overrides else cfg
    if not isinstance(cfg, RunConfig):  # pragma: no cover - replace keeps the type
        raise ConfigError("internal: bad configuration")
    if resume is None:
        folder = out if out is not None else _default_out(cfg.scenario, cfg.seed)
    console.print(
        f"[bold]deformap explore[/] {cfg.scenario} seed {cfg.seed} → {folder}", highlight=False
    )
    output = run_experiment(
        cfg,
        folder,
        resume=resume is not None,
        on_poke=_progress_row,
        rerun=rerun,
    )
    _summary(output.report, folder)


@config_app.command("dump")
@friendly_errors
def config_dump(
    out: Annotated[Path | None, typer.Option(help="Write to this file instead of stdout.")] = None,
) -> None:
    """Write the full default run configuration as YAML."""
    from deformap._config import dump_yaml
    from deformap.eval import RunConfig

    text = dump_yaml(RunConfig(), out)
    if out is None:
        sys.stdout.write(text)
    else:
        console.print(f"wrote {out}")


@bench_app.command("speed")
@friendly_errors
def bench_speed(
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Also write the table as JSON.")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the synthetic data.")] = 0,
    quick: Annotated[bool, typer.Option(help="Smaller sizes (a smoke run).")] = False,
) -> None:
    """Surface GP (exact vs grid) and the β sweep (batched vs per-β loop), same run."""
    import json

    from rich.table import Table

    from deformap.eval._bench_gp import bench_surface_gp
    from deformap.eval._bench_msm import bench_beta_sweep

    rng = np.random.default_rng(seed)
    sizes = (1000, 2000) if quick else (3000, 6000, 12000)
    gp_rows = bench_surface_gp(sizes, rng=rng)
    sweep = bench_beta_sweep(n_particles_side=20 if quick else 40, rng=rng)
    table = Table(title="surface GP → mean and std on the 120×80 grid (σw 4 cm, σn 2 mm)")
    for col in ("points", "exact \\[s]", "grid \\[s]", "speed-up", "max |Δmean| [µm]", "max Δstd [%]"):
        table.add_column(col, justify="right")
    for row in gp_rows:
        table.add_row(
            str(row["n_points"]),
            f"{row['exact_s']:.3f}",
            f"{row['grid_s']:.3f}",
            f"{row['speedup']:.0f}×",
            f"{row['max_mean_dev_m'] * 1e6:.2f}",
            f"{row['max_rel_std_dev'] * 100:.3f}",
        )
    console.print(table)
    table = Table(title="β estimation (converged, 3×3 clusters)")
    for col in ("β values", "particles", "batched \\[s]", "per-β loop \\[s]", "speed-up"):
        table.add_column(col, justify="right")
    table.add_row(
        str(sweep["n_beta"]),
        str(sweep["n_particles"]),
        f"{sweep['batched_s']:.3f}",
        f"{sweep['loop_s']:.3f}",
        f"{sweep['speedup']:.1f}×",
    )
    console.print(table)
    if json_path is not None:
        json_path.write_text(json.dumps({"surface_gp": gp_rows, "beta_sweep": sweep}, indent=2))
        console.print(f"wrote {json_path}")


study_app = typer.Typer(help="Studies on homogeneous simulated foams (the paper's Fig. 5).")
app.add_typer(study_app, name="study")


def _study_foams(seed: int, hardness: list[float] | None, coarse: bool) -> Any:
    from deformap.eval import DEFAULT_HARDNESSES, collect_presses
    from deformap.world import WorldConfig

    foams = DEFAULT_HARDNESSES if not hardness else (*hardness, None)
    world_config = WorldConfig.coarse() if coarse else WorldConfig()
    return collect_presses(
        foams,
        world_config=world_config,
        rng=np.random.default_rng(seed),
        progress=lambda msg: console.print(f"  {msg}", highlight=False),
    )


@study_app.command("hardness")
@friendly_errors
def study_hardness(
    out: Annotated[Path, typer.Option(help="Folder for hardness.png and hardness.json.")] = Path(
        "runs/study-hardness"
    ),
    seed: Annotated[int, typer.Option(help="Seed of the worlds' noise.")] = 0,
    hardness: Annotated[
        list[float] | None, typer.Option(help="Foams in N (repeat); rigid is added.")
    ] = None,
    coarse: Annotated[bool, typer.Option(help="Coarse FEM mesh (quick look).")] = False,
) -> None:
    """β against hardness for each contact protocol (paper Fig. 5a)."""
    import json

    from rich.table import Table

    from deformap.eval import hardness_study
    from deformap.viz import plot_hardness_study

    out.mkdir(parents=True, exist_ok=True)
    study = hardness_study(_study_foams(seed, hardness, coarse))
    (out / "hardness.json").write_text(json.dumps(study, indent=2))
    plot_hardness_study(study, path=out / "hardness.png")
    table = Table(title="β against hardness")
    for col in ("protocol", "hardness [N]", "β", "β spread", "β uncertainty", "fit error \\[mm]"):
        table.add_column(col, justify="right")
    for r in study["rows"]:
        h = "rigid" if r["hardness_n"] is None else f"{r['hardness_n']:g}"
        table.add_row(
            r["protocol"],
            h,
            f"{r['beta']:.3f}",
            f"{r['beta_std']:.3f}",
            f"{r['beta_estimate_std']:.3f}",
            f"{r['fit_error_m'] * 1e3:.3f}",
        )
    console.print(table)
    for name, ok in study["monotone"].items():
        console.print(
            f"  {name}: β {'strictly rises' if ok else 'does NOT strictly rise'} as hardness falls",
            highlight=False,
        )
    console.print(f"wrote {out / 'hardness.json'} and {out / 'hardness.png'}")


@study_app.command("cluster-size")
@friendly_errors
def study_cluster_size(
    out: Annotated[Path, typer.Option(help="Folder for cluster-size.png and .json.")] = Path(
        "runs/study-cluster-size"
    ),
    seed: Annotated[int, typer.Option(help="Seed of the worlds' noise.")] = 0,
    coarse: Annotated[bool, typer.Option(help="Coarse FEM mesh (quick look).")] = False,
) -> None:
    """Fit error and β against cluster size 2×2 … 6×6 (paper Fig. 5b)."""
    import json

    from rich.table import Table

    from deformap.eval import cluster_size_study
    from deformap.viz import plot_cluster_size_study

    out.mkdir(parents=True, exist_ok=True)
    study = cluster_size_study(_study_foams(seed, [60.0, 110.0, 150.0], coarse))
    (out / "cluster-size.json").write_text(json.dumps(study, indent=2))
    plot_cluster_size_study(study, path=out / "cluster-size.png")
    table = Table(title="fit error against cluster size")
    for col in ("k×k", "hardness [N]", "β", "fit error \\[mm]"):
        table.add_column(col, justify="right")
    for r in study["rows"]:
        h = "rigid" if r["hardness_n"] is None else f"{r['hardness_n']:g}"
        table.add_row(
            f"{r['cluster_size']}", h, f"{r['beta']:.3f}", f"{r['fit_error_m'] * 1e3:.3f}"
        )
    console.print(table)
    console.print(f"wrote {out / 'cluster-size.json'} and {out / 'cluster-size.png'}")


@app.command("reproduce")
@friendly_errors
def reproduce_command(
    out: Annotated[
        Path, typer.Option(help="Folder: one run per scenario, table.md, table.json.")
    ] = Path("runs/reproduce"),
    seed: Annotated[int, typer.Option(help="Seed of every run.")] = 0,
    strategy: Annotated[
        str | None,
        typer.Option(help="paper | max-variance | min-max-variance | planned (default: the config's)."),
    ] = None,
    config: Annotated[Path | None, typer.Option(help="Run configuration YAML.")] = None,
) -> None:
    """All six scenarios of the paper's Table I, beside the paper's numbers."""
    import dataclasses

    from deformap.eval import load_run_config, reproduce

    base = load_run_config(config)
    exploration = base.exploration
    if strategy is not None:
        exploration = dataclasses.replace(exploration, strategy=strategy)  # type: ignore[arg-type]
    base = dataclasses.replace(base, seed=seed, exploration=exploration)

    def show(row: dict[str, Any]) -> None:
        tau = "–" if row["kendall_tau"] is None else f"{row['kendall_tau']:.2f}"
        console.print(
            f"  {row['scenario']:<28} pokes {row['pokes']:>2}  regions {row['regions_found']}/"
            f"{row['regions_true']}  accuracy {row['accuracy']:.3f}  τ {tau}  {row['time_s']:.1f} s",
            highlight=False,
        )

    result = reproduce(out, base=base, on_run=show)
    console.print((out / "table.md").read_text())
    console.print(f"wrote {out / 'table.md'} and {out / 'table.json'} ({len(result['rows'])} runs)")


@bench_app.command("io")
@friendly_errors
def bench_io_command(
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Also write the table as JSON.")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the synthetic cloud.")] = 0,
) -> None:
    """Reading a 300,000-point binary PCD and one PointCloud2 message of that size."""
    import json

    from rich.table import Table

    from deformap.eval._bench_io import bench_io

    row = bench_io(n_points=300_000, rng=np.random.default_rng(seed))
    table = Table(title="reading 300,000 points (best of repeats; goal < 0.5 s each)")
    table.add_column("what")
    table.add_column("seconds", justify="right")
    for key, value in row.items():
        if isinstance(value, float) and key != "goal_s":
            table.add_row(key, f"{value:.4f}")
    console.print(table)
    if json_path is not None:
        json_path.write_text(json.dumps(row, indent=2))
        console.print(f"wrote {json_path}")


def _memory_table(title: str, rows: list[dict[str, Any]], size_label: str) -> Any:
    from rich.table import Table

    table = Table(title=title)
    for col in (size_label, "path", "traced [MiB]", "RSS+ [MiB]", "time \\[s]", "baseline [MiB]",
                "vs baseline"):  # fmt: skip
        table.add_column(col, justify="right")
    by_key = {(r["case"], r["size"]): r for r in rows}
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
        table.add_row(f"{r['size']:,}", r["case"].split("-", 1)[1], f"{r['traced_peak_mib']:.1f}",
                      added, f"{r['seconds']:.2f}", base_text, ratio)  # fmt: skip
    return table


@bench_app.command("memory")
@friendly_errors
def bench_memory_command(
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Also write the rows as JSON.")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the synthetic data.")] = 0,
    quick: Annotated[bool, typer.Option(help="Smaller sizes (a smoke run).")] = False,
) -> None:
    """Peak memory: surface GP (grid vs exact) and one β estimation (batched vs per-β loop)."""
    import json

    from deformap.eval._bench_memory import bench_memory

    sizes, exact_max, side = ((500, 2000), 2000, 12) if quick else ((3000, 12000), 3000, 40)
    result = bench_memory(gp_sizes=sizes, exact_max_points=exact_max, beta_side=side, seed=seed)
    dense = ", ".join(f"{n:,}: {n * n * 8 / 2**20:,.0f} MiB" for n in sizes if n > exact_max)
    note = f"; exact's N×N covariance alone at {dense}" if dense else ""
    console.print(_memory_table(f"peak memory, surface GP → mean and std on the 120×80 grid{note}",
                                result["surface_gp"], "points"))  # fmt: skip
    console.print(_memory_table("peak memory, one β estimation (converged, 3×3 clusters)",
                                result["beta_estimation"], "side"))  # fmt: skip
    console.print("traced: numpy + Python (tracemalloc); RSS+: resident set rise, all libraries; "
                  "one fresh process per row; baseline: the same size", style="dim")
    if json_path is not None:
        json_path.write_text(json.dumps(result, indent=2))
        console.print(f"wrote {json_path}")


def main() -> None:
    """Console-script entry point."""
    app()




# ---- world commands ----
world_app = typer.Typer(help="The simulated world: look at a scenario.", no_args_is_help=True)
app.add_typer(world_app, name="world")


@app.command("scenarios")
@friendly_errors
def scenarios_command() -> None:
    """List the built-in scenarios (the paper's Table I) with their regions."""
    from rich.table import Table

    from deformap.world import list_scenarios, load_scenario

    table = Table(title="built-in scenarios")
    for col in ("name", "regions", "description"):
        table.add_column(col)
    for name in list_scenarios():
        sc = load_scenario(name)
        regions = ", ".join("rigid" if b.rigid else f"{b.hardness:.0f} N" for b in sc.blocks)
        table.add_row(name, regions, sc.description)
    console.print(table)


@world_app.command("show")
@friendly_errors
def world_show_command(
    name: Annotated[str, typer.Argument(help="Built-in scenario name or YAML file.")],
    out: Annotated[str, typer.Option("--out", help="Folder for the PNGs.")],
    seed: Annotated[int, typer.Option(help="Seed of the camera and sensor noise.")] = 0,
    coarse: Annotated[bool, typer.Option(help="Use the coarse test mesh (fast).")] = False,
) -> None:
    """Write layout.png, cloud.png and dent.png of a scenario into OUT."""
    from pathlib import Path

    import numpy as np

    from deformap.viz import show_world
    from deformap.world import SimulatedWorld, WorldConfig, load_scenario

    config = WorldConfig.coarse() if coarse else WorldConfig()
    world = SimulatedWorld(load_scenario(name), config=config, rng=np.random.default_rng(seed))
    for path in show_world(world, Path(out)):
        console.print(f"wrote {path}")


@bench_app.command("world")
@friendly_errors
def bench_world_command(
    json_file: Annotated[
        str | None, typer.Option("--json", help="Also write the numbers here.")
    ] = None,
    scenario: Annotated[str, typer.Option(help="Scenario name or YAML file.")] = (
        "heterogeneous-60-110-rigid"
    ),
    seed: Annotated[int, typer.Option(help="Seed of the noise.")] = 0,
    coarse: Annotated[bool, typer.Option(help="Coarse test mesh instead of the default.")] = False,
) -> None:
    """Time world construction (with factorisation), one press and one observation."""
    import json
    from pathlib import Path

    import numpy as np
    from rich.table import Table

    from deformap.eval._bench_world import bench_world
    from deformap.world import WorldConfig

    config = WorldConfig.coarse() if coarse else WorldConfig()
    result = bench_world(scenario=scenario, rng=np.random.default_rng(seed), config=config)
    goals = {"construction_s": 20.0, "press_s": 1.0, "observe_s": 0.5}
    table = Table(title=f"simulated world: {result['scenario']}")
    for col in ("measure", "value", "goal"):
        table.add_column(col)
    for key, value in result.items():
        if key == "scenario":
            continue
        text = f"{value:.4g}" if isinstance(value, float) else str(value)
        goal = f"≤ {goals[key]:g} s" if key in goals else ""
        table.add_row(key, text, goal)
    console.print(table)
    if json_file:
        Path(json_file).parent.mkdir(parents=True, exist_ok=True)
        Path(json_file).write_text(json.dumps(result, indent=2))
        console.print(f"wrote {json_file}")


# ---- replay commands ----
def _session_config(config: Any, session: Any) -> Any:
    """The run configuration for a session: --config, else the one it was recorded with."""
    from deformap._config import config_from_dict
    from deformap.eval import RunConfig, load_run_config

    if config is not None:
        return load_run_config(config)
    recorded = session.source.get("config")
    if recorded is None:
        return RunConfig()
    return config_from_dict(RunConfig, recorded, where=f"{session.path}/session.yaml source.config")


def _replay_progress(poke: Any) -> None:
    r = poke.record
    console.print(
        f"  poke {r.index + 1:>2}  "
        f"contact ({r.contact_xy[0]:.3f}, {r.contact_xy[1]:.3f}) m"
        f"  β = {r.beta:.3f} ± {r.beta_std:.3f}  max var {r.max_variance_after:.4f}",
        highlight=False,
    )


def _new_folder(out: Any, what: str) -> Any:
    """Create the empty ``--out`` folder now, so that one that cannot be made fails before the work."""
    from pathlib import Path

    from deformap.cloud.io._common import path_kind
    from deformap.errors import ConfigError

    folder = Path(out)
    kind = path_kind(folder)
    if kind != "missing" and (kind != "dir" or any(folder.iterdir())):
        raise ConfigError(
            f"{what} folder {str(folder)!r} exists and is not empty; choose another --out"
        )
    _make_folder(folder, what)
    return folder


def _make_folder(folder: Path, what: str) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(
            f"cannot create {what} folder {str(folder)!r} (--out): {exc.strerror or exc}"
        ) from None


@app.command("record-sim")
@friendly_errors
def record_sim_command(
    scenario: Annotated[
        str, typer.Option("--scenario", "-s", help="Built-in scenario name or YAML file.")
    ],
    out: Annotated[str, typer.Option("--out", help="New session folder.")],
    format: Annotated[str, typer.Option("--format", help="folder | mcap | sqlite3.")] = "folder",
    seed: Annotated[int | None, typer.Option(help="Seed of world noise and poke choice.")] = None,
    pokes: Annotated[int | None, typer.Option("--pokes", help="Most pokes to make.")] = None,
    config: Annotated[
        str | None, typer.Option(help="Run configuration YAML (see `config dump`).")
    ] = None,
) -> None:
    """Explore a simulated world; record what it returned as a session (see docs)."""
    import dataclasses

    from deformap import __version__
    from deformap._config import config_to_dict
    from deformap.errors import ConfigError
    from deformap.eval import load_run_config
    from deformap.eval._experiment import run_generators
    from deformap.explore import explore
    from deformap.replay import SESSION_FORMATS, GroundTruth, RecordingEnvironment, write_session
    from deformap.world import SimulatedWorld, load_scenario

    if format not in SESSION_FORMATS:
        raise ConfigError(f"--format must be one of {list(SESSION_FORMATS)}; got {format!r}")
    cfg = load_run_config(config)
    folder = _new_folder(out, "session")
    cfg = dataclasses.replace(cfg, scenario=scenario, seed=cfg.seed if seed is None else seed)
    if pokes is not None:
        cfg = dataclasses.replace(
            cfg, exploration=dataclasses.replace(cfg.exploration, max_pokes=pokes)
        )
    console.print(
        f"[bold]deformap record-sim[/] {cfg.scenario} seed {cfg.seed} → {folder}", highlight=False
    )
    world_rng, explore_rng = run_generators(cfg.seed)
    world = SimulatedWorld(load_scenario(cfg.scenario), config=cfg.world, rng=world_rng)
    env = RecordingEnvironment(world)
    result = explore(env, cfg.exploration, rng=explore_rng, on_poke=_replay_progress)
    xs, ys = world.workspace.grid(cfg.exploration.surface.grid_spacing_m)
    truth = GroundTruth(
        xs, ys, world.ground_truth_labels(xs, ys), world.ground_truth_hardness(xs, ys)
    )
    source = {
        "recorded_by": f"deformap {__version__} record-sim",
        "scenario": cfg.scenario,
        "seed": cfg.seed,
        "live_betas": [p.record.beta for p in result.pokes],
        "config": config_to_dict(cfg),
    }
    file = write_session(
        folder,
        workspace=world.workspace,
        observation=env.observation,
        presses=env.presses,
        ground_truth=truth,
        source=source,
        format=format,
    )
    console.print(f"wrote {file} ({len(env.presses)} pokes, {format} form)")


@app.command("map")
@friendly_errors
def map_command(
    session_path: Annotated[
        str, typer.Argument(metavar="SESSION", help="Session folder or its session.yaml.")
    ],
    out: Annotated[
        str | None, typer.Option(help="Result folder (default runs/<session>-map-<time>).")
    ] = None,
    config: Annotated[
        str | None, typer.Option(help="Run configuration YAML; default: the session's own.")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(help="Seed of the surface fit; default: the session's.")
    ] = None,
    figures: Annotated[bool, typer.Option(help="Write map.png and poke-NN.png.")] = True,
) -> None:
    """Map a recorded session: its pokes, in order, through the live loop's mapper."""
    import dataclasses
    import json
    import time
    from pathlib import Path

    from deformap import __version__
    from deformap._config import config_to_dict, dump_yaml
    from deformap.errors import ConfigError
    from deformap.eval._experiment import (
        _json_default,
        map_report,
        run_generators,
        write_map_figures,
    )
    from deformap.replay import load_session, map_session

    session = load_session(session_path)
    cfg = _session_config(config, session)
    if seed is None:
        seed = session.source.get("seed", cfg.seed)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ConfigError(
                f"{session.path}/session.yaml: `source.seed` must be an integer >= 0; got "
                f"{seed!r} (or pass --seed)"
            )
    cfg = dataclasses.replace(cfg, seed=seed)
    stem = session.path.name or "session"
    folder = _new_folder(
        out or Path("runs") / f"{stem}-map-{time.strftime('%Y%m%d-%H%M%S')}", "result"
    )
    console.print(
        f"[bold]deformap map[/] {session.path} ({len(session)} pokes, {session.form} form) "
        f"→ {folder}",
        highlight=False,
    )
    _, explore_rng = run_generators(cfg.seed)
    replay = map_session(session, cfg.exploration, rng=explore_rng, on_poke=_replay_progress)
    dump_yaml(cfg, folder / "config.yaml")
    report = {"deformap": __version__, "session": str(session.path), "form": session.form,
              "source": {k: v for k, v in session.source.items() if k != "config"},
              "seed": cfg.seed, "config": config_to_dict(cfg),
              **map_report(replay.result, truth=session.ground_truth),
              "skipped": replay.skipped, "warnings": replay.warnings}  # fmt: skip
    (folder / "report.json").write_text(json.dumps(report, indent=2, default=_json_default))
    if figures:
        write_map_figures(folder, replay.result, truth=session.ground_truth,
                          threshold=cfg.exploration.threshold,
                          title=f"{stem}: {len(replay.result.pokes)} pokes")  # fmt: skip
    for line in replay.warnings:
        err_console.print(f"[yellow]warning:[/] {line}", highlight=False, soft_wrap=True)
    used = len(replay.result.pokes)
    regions = report["regions"]
    found = (
        "no poke usable" if regions is None else f"{len(regions['class_betas'])} region class(es)"
    )
    scored = ""
    if regions is not None and "accuracy" in regions:
        scored = f", accuracy {regions['accuracy']:.3f} against the ground truth"
    console.print(
        f"{used} of {len(session)} pokes used, {found}{scored}; wrote {folder / 'report.json'}",
        highlight=False,
    )


@app.command("estimate")
@friendly_errors
def estimate_command(
    before: Annotated[
        str, typer.Option("--before", help="Cloud of the undisturbed surface (PCD, PLY, NPZ).")
    ],
    after: Annotated[str, typer.Option("--after", help="Cloud while pressing.")],
    contact: Annotated[
        tuple[float, float, float],
        typer.Option("--contact", help="Tip centre X Y Z at the press, metres."),
    ],
    force: Annotated[
        tuple[float, float, float],
        typer.Option("--force", help="Force FX FY FZ on the surface, newtons."),
    ],
    tip_radius: Annotated[
        float, typer.Option("--tip-radius", help="Radius of the spherical tip, metres.")
    ],
    robot_hull: Annotated[
        str | None,
        typer.Option("--robot-hull", help="Cloud file of points whose hull covers stick and hand."),
    ] = None,
    out: Annotated[
        str | None, typer.Option(help="Folder for estimate.json, beta-curve.png, poke.png.")
    ] = None,
    units: Annotated[str, typer.Option(help="Units of the cloud files: m | mm.")] = "m",
    config: Annotated[
        str | None, typer.Option(help="Run configuration YAML (its exploration part).")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the surface fit.")] = 0,
) -> None:
    """β of one poke from two clouds and the tactile contact (world frame, SI units)."""
    import json
    from pathlib import Path

    import numpy as np

    from deformap.cloud.io import read_cloud
    from deformap.environment import TactileContact
    from deformap.errors import InvalidArgumentError
    from deformap.eval import load_run_config
    from deformap.replay import estimate_poke

    try:
        touch = TactileContact(tip_center=np.array(contact), force=np.array(force),
                               tip_radius_m=tip_radius)  # fmt: skip
    except InvalidArgumentError as exc:
        raise InvalidArgumentError(f"--contact/--force/--tip-radius: {exc}") from None
    hull = None if robot_hull is None else read_cloud(robot_hull, units=units).points
    cfg = load_run_config(config)
    clouds = read_cloud(before, units=units), read_cloud(after, units=units)
    if out is not None:
        _make_folder(Path(out), "result")
    poke = estimate_poke(*clouds, touch, cfg.exploration, rng=np.random.default_rng(seed),
                         robot_points=hull)  # fmt: skip
    r = poke.record.to_dict()
    result = {"before": str(before), "after": str(after), "beta": r["beta"],
              "beta_std": r["beta_std"], "contact_point": touch.contact_point.tolist(),
              **{k: r[k] for k in ("contact", "force_n", "betas", "errors", "converged",
                                   "iterations", "n_roi_points", "timings")}}  # fmt: skip
    if out is None:  # the JSON alone on stdout, for pipes
        sys.stdout.write(json.dumps(result) + "\n")
        return
    console.print(f"β = {r['beta']:.3f} ± {r['beta_std']:.3f} ({r['n_roi_points']} ROI points)")
    folder = Path(out)
    (folder / "estimate.json").write_text(json.dumps(result, indent=2))
    _estimate_figures(folder, poke)
    console.print(f"wrote {folder / 'estimate.json'}, beta-curve.png and poke.png")


def _estimate_figures(folder: Any, poke: Any) -> None:
    import numpy as np

    from deformap.viz import plot_error_curve, plot_poke

    r, dent = poke.record, poke.dent
    assert dent is not None  # estimate_poke processes the press here
    betas, errors = np.asarray(r.betas), np.asarray(r.errors)
    plot_error_curve(betas, errors, r.beta, r.beta_std, path=folder / "beta-curve.png")
    plot_poke(roi_xs=dent.roi_xs, roi_ys=dent.roi_ys, rest_z=dent.rest_z,
              deformed_z=dent.deformed_z, roi_points=dent.roi_points, tactile=dent.tactile,
              betas=betas, errors=errors, beta=r.beta, beta_std=r.beta_std,
              title="one poke", path=folder / "poke.png")  # fmt: skip


if __name__ == "__main__":  # pragma: no cover
    main()
