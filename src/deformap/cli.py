"""The ``deformap`` command.

Every sub-command turns a :class:`~deformap.errors.DeformapError` into one line on stderr and exit
code 2: a user sees what to fix, never a traceback.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from functools import wraps
from typing import Annotated, Any, TypeVar

import typer
from rich.console import Console

from deformap import __version__
from deformap.errors import DeformapError

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
bench_app = typer.Typer(help="Speed benchmarks (tables with a baseline measured in the same run).")
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
        typer.Option("--version", callback=_version_callback, is_eager=True, help="Print the version."),
    ] = False,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log progress details.")] = False,
) -> None:
    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )


def main() -> None:
    """Console-script entry point."""
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())


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

    from deformap.world import SimulatedWorld, WorldConfig, load_scenario
    from deformap.world._show import show_world

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
        "heterogeneous-60-110-rigid"),
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
        f"  poke {r['index'] + 1:>2}  "
        f"contact ({r['contact_xy'][0]:.3f}, {r['contact_xy'][1]:.3f}) m"
        f"  β = {r['beta']:.3f} ± {r['beta_std']:.3f}  max var {r['max_variance_after']:.4f}",
        highlight=False,
    )


def _new_folder(out: Any, what: str) -> Any:
    from pathlib import Path

    from deformap.errors import ConfigError

    folder = Path(out)
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise ConfigError(
            f"{what} folder {str(folder)!r} exists and is not empty; choose another --out"
        )
    return folder


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
    folder = _new_folder(out, "session")
    cfg = load_run_config(config)
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
        "live_betas": [p.record["beta"] for p in result.pokes],
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
    folder.mkdir(parents=True, exist_ok=True)
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
    poke = estimate_poke(*clouds, touch, cfg.exploration, rng=np.random.default_rng(seed),
                         robot_points=hull)  # fmt: skip
    r = poke.record
    result = {"before": str(before), "after": str(after), "beta": r["beta"],
              "beta_std": r["beta_std"], "contact_point": touch.contact_point.tolist(),
              **{k: r[k] for k in ("contact", "force_n", "betas", "errors", "converged",
                                   "iterations", "n_roi_points", "timings")}}  # fmt: skip
    if out is None:  # the JSON alone on stdout, for pipes
        sys.stdout.write(json.dumps(result) + "\n")
        return
    console.print(f"β = {r['beta']:.3f} ± {r['beta_std']:.3f} ({r['n_roi_points']} ROI points)")
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "estimate.json").write_text(json.dumps(result, indent=2))
    _estimate_figures(folder, poke)
    console.print(f"wrote {folder / 'estimate.json'}, beta-curve.png and poke.png")


def _estimate_figures(folder: Any, poke: Any) -> None:
    import numpy as np

    from deformap.viz import plot_beta_curve, plot_poke
    from deformap.viz._figures import plt

    r = poke.record
    betas, errors = np.asarray(r["betas"]), np.asarray(r["errors"])
    fig, ax = plt.subplots(figsize=(5.0, 3.6), constrained_layout=True)
    plot_beta_curve(ax, betas, errors, r["beta"], r["beta_std"])
    ax.set_title("shape-matching error E(β)")
    fig.savefig(folder / "beta-curve.png", dpi=110)
    plt.close(fig)
    plot_poke(folder / "poke.png", roi_xs=poke.roi_xs, roi_ys=poke.roi_ys, rest_z=poke.rest_z,
              deformed_z=poke.deformed_z, roi_points=poke.roi_points, tactile=poke.tactile,
              betas=betas, errors=errors, beta=r["beta"], beta_std=r["beta_std"],
              title="one poke")  # fmt: skip
