"""What ``deformap bench worlds`` runs: its axes and one exploration configuration.

An experiment varies the exploration through :class:`~deformap.explore.ExplorationConfig`
itself: ``--set key=value`` (dotted keys into it, values read as YAML scalars) goes through the
same reader as a YAML configuration file (:func:`deformap._config.config_from_dict`), so a new
exploration setting is benchmarked, checked and recorded in ``bench.json`` without a change here.
``bench.json`` records the settings that differ from the defaults, by their dotted keys.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from deformap._config import config_from_dict, config_to_dict, parse_yaml
from deformap._validation import SettingError, check_settings, setting
from deformap.errors import ConfigError
from deformap.eval import WorldTask, choices
from deformap.explore import ExplorationConfig
from deformap.world import APPEARANCE_FAMILIES, LAYOUT_FAMILIES, PHYSICS

__all__ = ["WorldsBenchConfig", "exploration_changes", "exploration_with", "parse_assignments"]

#: Exploration settings a benchmark sets itself, and the option that sets each.
_AXES = {"strategy": "--strategies", "field": "--fields", "region_labels": "--cuts",
         "max_pokes": "--max-pokes", "boundary_pokes": "--max-pokes",
         "force_n": "none: each world draws its own", "appearance": "--appearance"}


def parse_assignments(items: Iterable[str]) -> dict[str, Any]:
    """``key=value`` strings (``--set``) as ``{dotted key: value}``, each value read as a YAML
    scalar (``false``, ``0.25``, ``null``, ``nearest``).

    Raises
    ------
    ConfigError
        An item without ``=``, an empty key, a key given twice, or a value that is not a scalar.
    """
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError(f"--set must be key=value (a dotted exploration setting); got "
                              f"{item!r}")
        if key in out:
            raise ConfigError(f"--set {key} is given twice")
        try:
            value = parse_yaml(text, where=f"--set {key}") if text.strip() else None
        except ConfigError:
            value = {}  # refused below, in the same words
        if isinstance(value, dict | list):
            raise ConfigError(f"--set {key}: the value must be a scalar (a number, true/false, "
                              f"null or a name); got {text!r}")
        out[key] = value
    return out


#: Schemes of ``dask.distributed`` addresses a client reaches over a network (a bare
#: ``host:port`` is ``tcp``); ``inproc`` names a scheduler inside the calling process.
_SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")


def _check_address(address: str) -> None:
    """A scheduler's address as ``[scheme://]host[:port]``, checked for its form only (whether a
    scheduler answers there is :func:`deformap.run._worlds_engines.check_scheduler`'s)."""
    scheme, sep, location = address.partition("://")
    if not sep:
        scheme, location = "tcp", address
    host, colon, port = location.rpartition(":") if ":" in location else (location, "", "")
    if not address.strip() or any(c.isspace() for c in address):
        why = "an empty value" if not address.strip() else "blanks"
        raise SettingError("scheduler", f"must be a Dask scheduler's address (tcp://host:8786); "
                                        f"got {why}: {address!r}")
    if scheme == "inproc":
        raise SettingError("scheduler", f"must be a scheduler reachable over the network "
                                        f"({', '.join(s + '://' for s in _SCHEDULER_SCHEMES)}); "
                                        f"an inproc:// address names one inside this process; "
                                        f"got {address!r}")
    if scheme not in _SCHEDULER_SCHEMES:
        raise SettingError("scheduler", f"must start with one of "
                                        f"{', '.join(s + '://' for s in _SCHEDULER_SCHEMES)} "
                                        f"(or be host:port); got {address!r}")
    if not host.strip("[]") or (colon and not (port.isdigit() and 0 < int(port) < 65536)):
        raise SettingError("scheduler", f"must name a host and a port from 1 to 65535 "
                                        f"(tcp://host:8786); got {address!r}")


def _flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            out.update(_flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def exploration_with(changes: Mapping[str, Any]) -> ExplorationConfig:
    """The default :class:`ExplorationConfig` with ``changes`` (``{dotted key: value}``), read
    as a YAML configuration's ``exploration`` section would be.

    Raises
    ------
    ConfigError
        A key is unknown or a value is refused (one line naming ``exploration.<key>``).
    """
    data = config_to_dict(ExplorationConfig())
    for key, value in changes.items():
        *path, last = key.split(".")
        node = data
        for part in path:
            if not isinstance(node.get(part), dict):
                raise ConfigError(f"`exploration.{key}`: `exploration.{part}` is no group of "
                                  f"settings")
            node = node[part]
        if last not in node:
            known = sorted(node)
            raise ConfigError(f"`exploration.{key}` is no setting; known keys there are "
                              f"{known}")
        node[last] = value
    return config_from_dict(ExplorationConfig, data, where="exploration")


def exploration_changes(config: ExplorationConfig) -> dict[str, Any]:
    """The settings of ``config`` that differ from the defaults, by dotted key (plain data; the
    inverse of :func:`exploration_with`)."""
    default = _flatten(config_to_dict(ExplorationConfig()))
    return {k: v for k, v in _flatten(config_to_dict(config)).items() if default.get(k) != v}


@dataclass(frozen=True, kw_only=True)
class WorldsBenchConfig:
    """What ``deformap bench worlds`` runs (``worlds``, ``workers`` and ``scheduler`` do not
    change a world's result, so a run may resume with more worlds or on another engine).

    Parameters
    ----------
    worlds : int
        How many worlds (indices 0 .. worlds − 1 of the seed).
    seed : int
    families : tuple of str
        Layout families, taken in turn (:data:`deformap.world.LAYOUT_FAMILIES`).
    physics : tuple of str
        The world physics each world's is drawn from (:data:`deformap.world.PHYSICS`).
    appearances : tuple of str
        Appearance families (:data:`deformap.world.APPEARANCE_FAMILIES`), each painting every
        world; a painted one mapped blind and with the prior (:meth:`arms`).
    strategies, fields : tuple of str
        ``ExplorationConfig.strategy`` and ``field`` values, every pair mapped on every world.
    cuts : tuple of str
        ``ExplorationConfig.region_labels`` values, each scored on the same pokes.
    max_pokes : int
        Pokes per world and combination.
    exploration : ExplorationConfig
        Every other exploration setting (:func:`exploration_with`); the ones the axes above and
        each world set (strategy, field, region_labels, max_pokes, boundary_pokes, force_n,
        appearance) must keep their defaults.
    coarse : bool
        The test mesh and camera (:meth:`deformap.world.WorldConfig.coarse`, about a third of a
        default world's cost) instead of the default world: a smoke run, whose 2 cm mesh reads
        E far off.
    workers : int
        Processes of the local pool.
    scheduler : str or None
        A ``dask.distributed`` scheduler's address (``tcp://host:8786``) instead of the pool.
    """

    worlds: int = setting(100, ge=1, le=1_000_000)
    seed: int = setting(0, ge=0)
    families: tuple[str, ...] = LAYOUT_FAMILIES
    physics: tuple[str, ...] = PHYSICS
    # one look everywhere: each world mapped once per combination
    appearances: tuple[str, ...] = ("plain",)
    # every choice ExplorationConfig has, so a strategy or field added there is benchmarked too
    strategies: tuple[str, ...] = choices("strategy")
    fields: tuple[str, ...] = choices("field")
    cuts: tuple[str, ...] = choices("region_labels")
    # every poke is a press and a β sweep per combination, hence fewer than a run's
    max_pokes: int = setting(12, limit="pokes")
    exploration: ExplorationConfig = field(default_factory=ExplorationConfig)
    coarse: bool = False
    workers: int = setting(1, ge=1, le=1024)
    scheduler: str | None = None

    def __post_init__(self) -> None:
        check_settings(self)
        if self.scheduler is not None:
            _check_address(self.scheduler)
        for name, given, allowed in (("families", self.families, LAYOUT_FAMILIES),
                                     ("physics", self.physics, PHYSICS),
                                     ("appearances", self.appearances, APPEARANCE_FAMILIES),
                                     ("strategies", self.strategies, choices("strategy")),
                                     ("fields", self.fields, choices("field")),
                                     ("cuts", self.cuts, choices("region_labels"))):
            unknown = [g for g in given if g not in allowed]
            repeated = sorted({g for g in given if given.count(g) > 1})
            if not given or unknown or repeated:
                why = ("none" if not given else f"{unknown} (unknown)" if unknown
                       else f"{repeated} more than once")
                raise SettingError(name, f"must be distinct names from {list(allowed)}; got "
                                         f"{why}")
        changed = exploration_changes(self.exploration)
        for key, option in _AXES.items():
            if key in changed:
                raise SettingError(f"exploration.{key}", f"is the benchmark's to set (option: "
                                                         f"{option}); leave it at its default")

    def result_settings(self) -> dict[str, Any]:
        """The settings a world's result depends on (``bench.json``; resuming compares them)."""
        return {"seed": self.seed, "families": list(self.families),
                "physics": list(self.physics), "appearances": list(self.appearances),
                "strategies": list(self.strategies),
                "fields": list(self.fields), "cuts": list(self.cuts),
                "max_pokes": self.max_pokes,
                "exploration": exploration_changes(self.exploration), "coarse": self.coarse}

    def combinations(self) -> list[tuple[str, str, str]]:
        return [(s, f, c) for s in self.strategies for f in self.fields for c in self.cuts]

    def arms(self) -> tuple[tuple[str, str], ...]:
        """``(appearance family, ExplorationConfig.appearance)`` of each mapping of a world
        (:meth:`deformap.eval.WorldTask.arms`)."""
        return self.task(0).arms()

    def task(self, index: int) -> WorldTask:
        """The task of world ``index``."""
        return WorldTask(seed=self.seed, index=index, families=self.families,
                         physics=self.physics, appearances=self.appearances,
                         strategies=self.strategies, fields=self.fields,
                         cuts=self.cuts, max_pokes=self.max_pokes, coarse=self.coarse,
                         exploration=self.exploration)
