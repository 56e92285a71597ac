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
    json_file: Annotated[str | None, typer.Option("--json", help="Also write the numbers here.")] = None,
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
