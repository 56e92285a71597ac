"""Record a simulation: explore a simulated world as a live run does, and write what the world
returned (its observation and every press) as a session that ``deformap map`` reads back.

The session's ``source`` holds the scenario, the seed, the run configuration and the β of each poke
as estimated live (``live_betas``), so that mapping it offline can be checked against the live run.
The session writer (:func:`deformap.replay.write_session`) writes ``session.yaml`` last: a session
killed while it is written has no ``session.yaml`` and is refused when read.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from deformap import __version__
from deformap._config import config_to_dict
from deformap.errors import ConfigError
from deformap.explore import check_exploration_budget, explore
from deformap.replay import SESSION_FORMATS, GroundTruth, RecordingEnvironment, write_session
from deformap.run._config import RunConfig, run_generators
from deformap.run._folder import create_run_folder, default_run_folder, run_stem
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.world import SimulatedWorld, load_scenario

__all__ = ["RecordOutput", "record_simulation"]


@dataclass(frozen=True, kw_only=True)
class RecordOutput:
    """What :func:`record_simulation` wrote: the ``session.yaml`` (``session_file``) in its
    ``folder``, ``n_pokes``, the ``format`` and the β of each poke as estimated live."""

    session_file: Path
    folder: Path
    n_pokes: int
    format: str
    live_betas: list[float]


def record_simulation(config: RunConfig, out: Path | None = None, *, format: str = "folder",
                      hooks: RunHooks = NO_HOOKS) -> RecordOutput:
    """Explore ``config.scenario`` live and write what the world returned as a session in
    ``out`` (new or empty; default kind ``record``): cloud files (``format="folder"``) or a ROS 2
    bag (``"mcap"``, ``"sqlite3"``; extra ``ros``). An unknown format or scenario, or an ``out``
    not empty or not creatable raises :class:`ConfigError` before any work.
    """
    if format not in SESSION_FORMATS:
        raise ConfigError(f"--format must be one of {list(SESSION_FORMATS)}; got {format!r}")
    scenario = load_scenario(config.scenario)
    check_exploration_budget(config.exploration, scenario.workspace)  # before any folder or work
    folder = out or default_run_folder(run_stem(config.scenario), "record", config.seed)
    create_run_folder(folder, what="session")
    hooks.start(RunStart(kind="record", title=f"{config.scenario} seed {config.seed}",
                         folder=folder, total=config.exploration.max_pokes))  # fmt: skip
    hooks.stage("building the world")
    world_rng, explore_rng = run_generators(config.seed)
    world = SimulatedWorld(scenario, config=config.world, rng=world_rng)
    env = RecordingEnvironment(world)
    hooks.stage("exploring")
    result = explore(env, config.exploration, rng=explore_rng,
                     on_poke=lambda poke: hooks.poke(poke.record))  # fmt: skip
    xs, ys = world.workspace.grid(config.exploration.surface.grid_spacing_m)
    truth = GroundTruth(xs, ys, world.ground_truth_labels(xs, ys),
                        world.ground_truth_hardness(xs, ys))
    live_betas = [p.record.beta for p in result.pokes]
    source = {"recorded_by": f"deformap {__version__} record-sim", "scenario": config.scenario,
              "seed": config.seed, "live_betas": live_betas, "config": config_to_dict(config)}
    hooks.stage("writing the session")
    file = write_session(folder, workspace=world.workspace, observation=env.observation,
                         presses=env.presses, ground_truth=truth, source=source,
                         format=format)  # fmt: skip
    return RecordOutput(session_file=file, folder=folder, n_pokes=len(env.presses),
                        format=format, live_betas=live_betas)  # fmt: skip
