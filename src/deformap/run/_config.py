"""The run's configuration: one :class:`RunConfig`, read from YAML, changed by overrides, checked
against the folder of a run that is resumed, or taken from the session a recording holds. A run's
randomness derives from its seed alone (:func:`run_generators`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from deformap._config import config_from_dict, described_yaml, dump_yaml, load_yaml
from deformap._validation import check_int, check_settings, setting
from deformap.cloud.io import path_kind
from deformap.errors import ConfigError
from deformap.explore import ExplorationConfig
from deformap.replay import RecordedSession
from deformap.run._robot import RobotConfig
from deformap.world import WorldConfig

__all__ = [
    "CONFIG_NAME", "RunConfig", "RunOverrides", "apply_overrides", "config_yaml",
    "explore_run_config", "load_run_config", "resume_run_config", "run_generators",
    "session_run_config",
]

CONFIG_NAME = "config.yaml"
"""The effective configuration in every run folder (written before anything else)."""


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """The whole configuration of a run: which world, which seed, and every component's settings.

    Parameters
    ----------
    scenario : str
        The simulated scenario explored, a built-in name or a scenario YAML file.
        ``deformap scenarios`` lists the built-in names.
    seed : int
        Seed of the run's generators (:func:`run_generators`); a run is reproduced by its seed.
    world : WorldConfig
        The simulated world's physics, camera and layout settings.
    exploration : ExplorationConfig
        The mapper's and the exploration loop's settings.
    robot : RobotConfig
        How ``explore --environment`` guards a user's robot.
    """

    scenario: str = "heterogeneous-60-110-rigid"
    seed: int = setting(0, ge=0)
    world: WorldConfig = field(default_factory=WorldConfig)
    exploration: ExplorationConfig = field(default_factory=ExplorationConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class RunOverrides:
    """Settings given on the command line, each replacing ``RunConfig``'s field of its name (the
    last four ``ExplorationConfig``'s, which validates them); ``None`` keeps the configuration's
    own."""

    scenario: str | None = None
    seed: int | None = None
    strategy: str | None = None
    threshold: float | None = None
    max_pokes: int | None = None
    field: str | None = None

    def given(self) -> dict[str, Any]:
        """The overrides that were given, by field name."""
        return {f.name: v for f in dataclasses.fields(self) if (v := getattr(self, f.name)) is not None}


def load_run_config(path: str | Path | None) -> RunConfig:
    """Read a run configuration from YAML (missing keys keep their defaults); ``None``: defaults.
    A file that cannot be read, or an unknown key or bad value (named by its dotted path), raises
    :class:`ConfigError`."""
    if path is None:
        return RunConfig()
    return config_from_dict(RunConfig, load_yaml(path), where=Path(path).name)


def config_yaml(config: RunConfig, *, described: bool = False) -> str:
    """``config`` as the YAML of ``config.yaml`` (every field, in definition order); with
    ``described``, each setting under a comment giving its description, unit and bounds."""
    return described_yaml(config) if described else dump_yaml(config)


def apply_overrides(config: RunConfig, overrides: RunOverrides) -> RunConfig:
    """``config`` with the given overrides; every changed dataclass validates itself again."""
    given = overrides.given()
    top: dict[str, Any] = {k: given.pop(k) for k in ("scenario", "seed") if k in given}
    if given:
        top["exploration"] = dataclasses.replace(config.exploration, **given)
    return dataclasses.replace(config, **top) if top else config


def resume_run_config(folder: Path, overrides: RunOverrides | None = None) -> RunConfig:
    """The configuration of the run in ``folder``, read from its ``config.yaml``; overrides only
    when they repeat the run's own settings, since a resumed run is the run that was killed
    (:class:`ConfigError` otherwise, or without ``config.yaml``)."""
    if path_kind(folder / CONFIG_NAME) != "file":  # a run writes it before anything else
        raise ConfigError(f"cannot resume {str(folder)!r}: it holds no {CONFIG_NAME}, so no run "
                          "started there; start one without --resume")
    config = load_run_config(folder / CONFIG_NAME)
    overrides = overrides or RunOverrides()
    changed = apply_overrides(config, overrides)
    if changed != config:
        names = ", ".join(sorted(overrides.given()))
        raise ConfigError(
            f"cannot resume {str(folder)!r} with different settings ({names}); drop those options")
    return config


def explore_run_config(config: Path | None, overrides: RunOverrides,
                       resume: Path | None = None) -> RunConfig:
    """The configuration of ``deformap explore``: the resumed run's own (``resume``; not with
    ``config``), else the file ``config`` (or the defaults) with ``overrides`` applied."""
    if resume is None:
        return apply_overrides(load_run_config(config), overrides)
    if config is not None:
        raise ConfigError("--resume reads the run's own config.yaml; do not pass --config too")
    return resume_run_config(resume, overrides)


def session_run_config(session: RecordedSession, config: RunConfig | None = None,
                       seed: int | None = None) -> RunConfig:
    """The configuration to map ``session`` with: ``config``, else the one it was recorded with
    (``source.config``), else the defaults; the seed ``seed``, else ``source.seed``, else the
    configuration's. A malformed recorded one raises :class:`ConfigError` naming its place."""
    if config is None:
        recorded = session.source.get("config")
        where = f"{session.path}/session.yaml source.config"
        config = RunConfig() if recorded is None else config_from_dict(RunConfig, recorded, where=where)
    if seed is None:
        seed = session.source.get("seed", config.seed)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ConfigError(f"{session.path}/session.yaml: `source.seed` must be an integer "
                              f">= 0; got {seed!r} (or pass --seed)")
    return dataclasses.replace(config, seed=seed)


def run_generators(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """The world's and the exploration's generators of a run with ``seed``, derived alike by
    every workflow, so that a session mapped offline fits the surface as the live run did."""
    world_seq, explore_seq = np.random.SeedSequence(check_int("seed", seed, minimum=0)).spawn(2)
    return np.random.default_rng(world_seq), np.random.default_rng(explore_seq)
