"""Explore a user's own `Environment` (a real robot, or any world) named on the command line.

``deformap explore --environment package.module:factory --env-arg key=value …`` imports
``package.module`` (installed, or in the current folder), calls ``factory(**args)`` with each
value read as a YAML scalar, and explores what it returns as the simulated world is explored
(the report without the ground-truth metrics), each call to the robot guarded
(:mod:`deformap.run._robot`). Importing runs the module's code, as any import.
"""

from __future__ import annotations

import contextlib
import importlib
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from deformap import __version__
from deformap._config import config_to_dict
from deformap._validation import check_positive
from deformap.errors import ConfigError
from deformap.explore import (
    JOURNAL_NAME,
    Journal,
    PokeRecord,
    check_exploration_budget,
    explore,
    read_journal,
)
from deformap.run._config import CONFIG_NAME, RunConfig, config_yaml, run_generators
from deformap.run._explore import resume_hint_on_failure, resume_journal
from deformap.run._export import poke_writer, write_run_results
from deformap.run._folder import claim_run_folder, default_run_folder, write_text
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.run._report import shared_report
from deformap.run._robot import GuardedEnvironment, RobotConfig, RobotFault

__all__ = ["explore_environment", "load_environment", "parse_env_args"]


def parse_env_args(pairs: Sequence[str]) -> dict[str, Any]:
    """``["key=value", …]`` as keyword arguments, each value a YAML scalar."""
    args: dict[str, Any] = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        if not sep or not key.isidentifier():
            raise ConfigError(f"--env-arg must be key=value with a Python name as key; got {pair!r}")
        if key in args:
            raise ConfigError(f"--env-arg {key!r} is given twice")
        try:
            value = yaml.safe_load(text) if text else ""
        except yaml.YAMLError:
            value = text
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"--env-arg {key!r} must be finite; got {text!r}")
        args[key] = value if isinstance(value, (str, int, float, bool)) or value is None else text
    return args


def load_environment(spec: str, args: dict[str, Any],
                     config: RobotConfig | None = None) -> GuardedEnvironment:
    """Import ``package.module:factory`` and build ``factory(**args)``, guarded by ``config``
    (:mod:`deformap.run._robot`); what does not load is a :class:`ConfigError`."""
    module_name, sep, attr = spec.partition(":")
    if not sep or not module_name or not attr or module_name.startswith("."):
        raise ConfigError(f"--environment must be package.module:factory (an absolute module "
                          f"name); got {spec!r}")
    if "" not in sys.path and str(Path.cwd()) not in sys.path:
        sys.path.append(str(Path.cwd()))  # a module beside the user, after the installed ones
    try:
        module = importlib.import_module(module_name)
    except (Exception, SystemExit) as exc:  # the user's module: whatever it raises is one line
        raise ConfigError(f"--environment {spec!r}: cannot import {module_name!r} "
                          f"({type(exc).__name__}: {exc})") from None
    factory = getattr(module, attr, None)
    if not callable(factory):
        raise ConfigError(f"--environment {spec!r}: {module_name!r} has no callable {attr!r}")
    env = GuardedEnvironment(spec, config or RobotConfig())
    env.build(factory, args)
    return env


def explore_environment(spec: str, env_args: dict[str, Any], config: RunConfig,
                        out: Path | None = None, *, resume: bool = False, figures: bool = True,
                        hooks: RunHooks = NO_HOOKS, variance_max: float | None = None,
                        rerun: bool = False) -> tuple[dict[str, Any], Path]:
    """Explore the Environment ``spec`` returns (module docstring); ``(report, folder)``.

    The run folder is new or empty (default ``runs/<factory>-explore-s<seed>-<time>``), made
    after the environment is built, so that a spec that does not load leaves nothing behind; with
    ``resume`` it is the folder of a run stopped there, whose journal must name the same
    ``spec``, ``env_args`` and configuration (but ``config.robot``), checked before the robot is
    built. ``variance_max`` fixes the top of ``map.png``'s variance scale. ``config.world`` and
    ``config.scenario`` are not used; ``rerun`` also writes ``run.rrd``. A robot that fails
    raises :class:`RobotFault` naming the call, with every finished poke in the journal.
    """
    if variance_max is not None:  # before any work
        check_positive("variance_max", variance_max)
    if resume and out is None:
        raise ConfigError("`out` must name the run folder to resume; got None")
    header = {"deformap": __version__, "config": config_to_dict(config), "environment": spec,
              "env_args": env_args}  # fmt: skip
    done: list[PokeRecord] = []
    again = " and the same --environment and --env-arg"
    with contextlib.ExitStack() as held:
        if resume:
            assert out is not None
            held.enter_context(claim_run_folder(out, resume=True))
            held.enter_context(resume_hint_on_failure(out, again))
            journal, done = resume_journal(out, config, header)
        env = load_environment(spec, env_args, config.robot)
        check_exploration_budget(config.exploration, env.workspace)
        folder = out or default_run_folder(spec.partition(":")[2], "explore", config.seed)
        if not resume:
            held.enter_context(claim_run_folder(folder, what="output", resume_hint=True))
            held.enter_context(resume_hint_on_failure(folder, again))
        write_text(folder / CONFIG_NAME, config_yaml(config))  # on resume, restores a removed copy
        if not resume:
            journal = Journal.create(folder, header)
        hooks.start(RunStart(kind="explore", title=f"{spec} seed {config.seed}", folder=folder,
                             total=config.exploration.max_pokes, done=len(done)))  # fmt: skip
        _, explore_rng = run_generators(config.seed)

        hooks.stage("exploring")
        t0 = time.perf_counter()
        try:
            result = explore(env, config.exploration, rng=explore_rng, journal=journal, done=done,
                             on_poke=poke_writer(folder, figures=figures, hooks=hooks))
        except RobotFault as exc:
            kept = len(read_journal(folder / JOURNAL_NAME).pokes)
            raise RobotFault(f"{exc}; {kept} poke(s) kept in the journal: continue with "
                             f"`deformap explore --resume {folder}`{again}", exc.error) from None
        report = {"deformap": __version__, "environment": spec, "env_args": env_args,
                  "seed": config.seed, "config": config_to_dict(config),
                  **shared_report(result, truth=None)}  # fmt: skip
        report["timings"]["wall_s"] = time.perf_counter() - t0
        write_run_results(folder, result, report, figures=figures, poke_figures=False,
                          title=f"{spec}: {len(result.pokes)} pokes", hooks=hooks,
                          variance_max=variance_max)
        if rerun:
            from deformap.run._figures import write_rerun

            write_rerun(folder / "run.rrd", result)
    return report, folder
