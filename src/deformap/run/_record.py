"""Record a simulation: explore a simulated world as a live run does, and write what the world
returned (its observation and every press) as a session that ``deformap map`` reads back.

The session's ``source`` holds the scenario, the seed, the run configuration and the β of each poke
as estimated live (``live_betas``), so that mapping it offline can be checked against the live run.
The session writer (:func:`deformap.replay.write_session`) writes ``session.yaml`` last: a session
killed while it is written has no ``session.yaml`` and is refused when read.

``format="raw-mcap"`` writes instead what a robot's drivers record (``robot.mcap``:
:func:`deformap.replay.write_raw_mcap`, with the rig's rates, noise and frames of a
:class:`~deformap.replay.RigConfig`) and, beside it, ``live.json``: the scenario, the seed, the rig
and each poke as the live run estimated it, to compare ``deformap map robot.mcap`` with.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from deformap import __version__
from deformap._config import config_to_dict
from deformap.errors import ConfigError
from deformap.explore import check_exploration_budget, explore
from deformap.replay import (
    SESSION_FORMATS,
    GroundTruth,
    RecordingEnvironment,
    RigConfig,
    load_rig,
    write_raw_mcap,
    write_session,
)
from deformap.run._config import RunConfig, run_generators
from deformap.run._folder import (
    atomic_path,
    claim_run_folder,
    default_run_folder,
    run_stem,
    write_json,
)
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.world import SimulatedWorld, check_world_budget, load_scenario

__all__ = ["RECORD_FORMATS", "RecordOutput", "record_simulation"]

#: What ``record-sim`` writes: a session (folder or bag form), or a robot's own raw bag.
RECORD_FORMATS = (*SESSION_FORMATS, "raw-mcap")


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
                      hooks: RunHooks = NO_HOOKS,
                      rig: RigConfig | Path | None = None) -> RecordOutput:
    """Explore ``config.scenario`` live and write what the world returned as a session in
    ``out`` (new or empty; default kind ``record``): cloud files (``format="folder"``), a ROS 2
    bag (``"mcap"``, ``"sqlite3"``; extra ``ros``), or the raw bag a robot records
    (``"raw-mcap"``: ``robot.mcap`` and ``live.json``, recorded by ``rig``, a ``RigConfig`` or its
    YAML file, default ``RigConfig()``). An unknown format or scenario, a ``rig`` with another
    format, or an ``out`` not empty or not creatable raises :class:`ConfigError` before any work.
    """
    if format not in RECORD_FORMATS:
        raise ConfigError(f"--format must be one of {list(RECORD_FORMATS)}; got {format!r}")
    if rig is not None and format != "raw-mcap":
        raise ConfigError(f"a rig (--rig) describes a raw robot bag: it needs --format raw-mcap; "
                          f"got --format {format}")
    if isinstance(rig, Path):
        rig = load_rig(rig)
    scenario = load_scenario(config.scenario)
    check_exploration_budget(config.exploration, scenario.workspace)  # before any folder or work
    check_world_budget(config.world, scenario)
    folder = out or default_run_folder(run_stem(config.scenario), "record", config.seed)
    with claim_run_folder(folder, what="session"):
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
        if format == "raw-mcap":
            hooks.stage("writing the robot's bag")
            rig = rig or RigConfig()
            file = folder / "robot.mcap"
            with atomic_path(file) as tmp:
                write_raw_mcap(tmp, env.observation, env.presses, rig, seed=config.seed)
            write_json(folder / "live.json", {**source, "rig": config_to_dict(rig),
                                              "pokes": [_live_poke(p.record) for p in result.pokes]})
            return RecordOutput(session_file=file, folder=folder, n_pokes=len(env.presses),
                                format=format, live_betas=live_betas)  # fmt: skip
        hooks.stage("writing the session")
        file = write_session(folder, workspace=world.workspace, observation=env.observation,
                             presses=env.presses, ground_truth=truth, source=source,
                             format=format)  # fmt: skip
        return RecordOutput(session_file=file, folder=folder, n_pokes=len(env.presses),
                            format=format, live_betas=live_betas)  # fmt: skip


def _live_poke(record: Any) -> dict[str, Any]:
    """What the live run estimated of one poke: contact, β and the modulus when read."""
    stiffness = record.stiffness
    return {"index": record.index, "contact_xy": list(record.contact_xy), "beta": record.beta,
            "beta_std": record.beta_std,
            "rigid": None if stiffness is None else bool(stiffness.rigid),
            "modulus_pa": None if stiffness is None else stiffness.modulus_pa}
