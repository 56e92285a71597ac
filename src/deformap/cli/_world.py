"""``deformap scenarios`` and ``deformap world show``: the simulated world."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from deformap import run
from deformap.cli._app import app, console, friendly_errors
from deformap.cli._progress import progress, run_hooks

__all__ = ["world_app"]

world_app = typer.Typer(help="The simulated world: look at a scenario.", no_args_is_help=True)
app.add_typer(world_app, name="world")


@app.command("scenarios")
@friendly_errors
def scenarios_command() -> None:
    """List the built-in scenarios (the paper's Table I) with their regions."""
    table = Table("name", "regions", "description", title="built-in scenarios")
    for sc in run.scenario_summaries():
        table.add_row(sc.name, ", ".join(sc.regions), sc.description)
    console.print(table)


@world_app.command("show")
@friendly_errors
def world_show_command(
    name: Annotated[str, typer.Argument(help="Built-in scenario name or YAML file.")],
    out: Annotated[Path, typer.Option("--out", help="New folder for the PNGs.")],
    seed: Annotated[int, typer.Option(help="Seed of the camera and sensor noise.")] = 0,
    coarse: Annotated[bool, typer.Option(help="Use the coarse test mesh (fast).")] = False,
) -> None:
    """Write layout.png, rgb.png (the camera's colour view), cloud.png and dent.png of a scenario
    into OUT."""
    with progress(console) as bar:
        paths = run.show_scenario(name, out, seed=seed, coarse=coarse, hooks=run_hooks(bar))
    for path in paths:
        console.print(f"wrote {path}", highlight=False)
