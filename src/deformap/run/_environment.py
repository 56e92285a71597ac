"""Explore a user's own `Environment` (a real robot, or any world) named on the command line.

``deformap explore --environment package.module:factory --env-arg key=value …`` imports
``package.module`` (installed, or in the current folder), calls ``factory(**args)`` with each
value read as a YAML scalar, and explores what it returns as the simulated world is explored
(the report without the ground-truth metrics). Importing runs the module's code, as any import.
"""

from __future__ import annotations

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
from deformap.environment import Environment
from deformap.errors import ConfigError
from deformap.explore import Journal, check_exploration_budget, explore
from deformap.run._config import CONFIG_NAME, RunConfig, config_yaml, run_generators
from deformap.run._export import poke_writer, write_run_results
from deformap.run._folder import create_run_folder, default_run_folder, write_text
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.run._report import shared_report

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


def load_environment(spec: str, args: dict[str, Any]) -> Environment:
    """Import ``package.module:factory`` and return ``factory(**args)``, an Environment."""
    module_name, sep, attr = spec.partition(":")
    if not sep or not module_name or not attr or module_name.startswith("."):
        raise ConfigError(f"--environment must be package.module:factory (an absolute module "
                          f"name); got {spec!r}")
    if "" not in sys.path and str(Path.cwd()) not in sys.path:
        sys.path.append(str(Path.cwd()))  # a module beside the user, after the installed ones
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # the user's module: whatever it raises is one line here
        raise ConfigError(f"--environment {spec!r}: cannot import {module_name!r} "
                          f"({type(exc).__name__}: {exc})") from None
    factory = getattr(module, attr, None)
    if not callable(factory):
        raise ConfigError(f"--environment {spec!r}: {module_name!r} has no callable {attr!r}")
    try:
        env = factory(**args)
    except TypeError as exc:
        raise ConfigError(f"--environment {spec!r}: the --env-arg values do not fit {attr}(): "
                          f"{exc}") from None
    except Exception as exc:  # a robot that is offline, a driver that fails to start
        raise ConfigError(f"--environment {spec!r}: {attr}() failed "
                          f"({type(exc).__name__}: {exc})") from None
    if not isinstance(env, Environment):
        raise ConfigError(f"--environment {spec!r} must return an Environment (workspace, "
                          f"observe, press, release); got {type(env).__name__}")
    return env


def explore_environment(spec: str, env_args: dict[str, Any], config: RunConfig,
                        out: Path | None = None, *, figures: bool = True,
                        hooks: RunHooks = NO_HOOKS, variance_max: float | None = None,
                        ) -> tuple[dict[str, Any], Path]:
    """Explore the Environment ``spec`` returns (module docstring); ``(report, folder)``.

    The run folder is new or empty (default ``runs/<factory>-explore-s<seed>-<time>``), made
    after the environment is built, so that a spec that does not load leaves nothing behind;
    ``variance_max`` fixes the top of ``map.png``'s variance scale. ``config.world`` and
    ``config.scenario`` are not used.
    """
    if variance_max is not None:  # before any work
        check_positive("variance_max", variance_max)
    env = load_environment(spec, env_args)
    check_exploration_budget(config.exploration, env.workspace)
    folder = out or default_run_folder(spec.partition(":")[2], "explore", config.seed)
    create_run_folder(folder, what="output")
    write_text(folder / CONFIG_NAME, config_yaml(config))
    header = {"deformap": __version__, "config": config_to_dict(config), "environment": spec,
              "env_args": env_args}  # fmt: skip
    journal = Journal.create(folder, header)
    hooks.start(RunStart(kind="explore", title=f"{spec} seed {config.seed}", folder=folder,
                         total=config.exploration.max_pokes, done=0))  # fmt: skip
    _, explore_rng = run_generators(config.seed)

    hooks.stage("exploring")
    t0 = time.perf_counter()
    result = explore(env, config.exploration, rng=explore_rng, journal=journal,
                     on_poke=poke_writer(folder, figures=figures, hooks=hooks))
    report = {"deformap": __version__, "environment": spec, "env_args": env_args,
              "seed": config.seed, "config": config_to_dict(config),
              **shared_report(result, truth=None)}  # fmt: skip
    report["timings"]["wall_s"] = time.perf_counter() - t0
    write_run_results(folder, result, report, figures=figures, poke_figures=False,
                      title=f"{spec}: {len(result.pokes)} pokes", hooks=hooks,
                      variance_max=variance_max)
    return report, folder
