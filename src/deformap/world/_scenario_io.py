"""Scenario files (YAML) and the catalogue of built-in scenarios.

A file holds ``name``, ``blocks`` (each with ``name``, one of ``rect`` or ``polygon``, optional
``holes``, one of ``hardness_n``, ``youngs_modulus_pa`` or ``rigid: true``, optional
``thickness_m``, ``color``, ``appearance``, ``viscoelastic`` (``relaxed_ratio``, ``times_s``,
optional ``weights``), ``anisotropy`` (``ratio``, ``axis_deg``) and ``plastic``
(``yield_stress_pa``, ``hardening_pa``)) and optionally
``description``, ``workspace`` (``lower``, ``upper``) and ``table_appearance``; every key is
checked, and ``docs/scenarios.md`` lists them all with their defaults.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from deformap._config import dump_yaml, few, load_yaml
from deformap.environment import Workspace
from deformap.errors import ConfigError, DeformapError
from deformap.world._appearance import Appearance, appearance_from_dict
from deformap.world._materials import Orthotropic, Plastic, Viscoelastic
from deformap.world._polygon import rectangle
from deformap.world._scenario import Block, Scenario, builtin_scenarios

__all__ = ["list_scenarios", "load_scenario", "parse_scenario", "save_scenario"]

_SCENARIO_KEYS = {"name", "description", "workspace", "blocks", "table_appearance"}
_BLOCK_KEYS = {"name", "rect", "polygon", "holes", "hardness_n", "youngs_modulus_pa", "rigid",
               "thickness_m", "color", "appearance", "viscoelastic", "anisotropy", "plastic"}
_MATERIAL_KEYS = {"viscoelastic": {"relaxed_ratio", "times_s", "weights"},
                  "anisotropy": {"ratio", "axis_deg"},
                  "plastic": {"yield_stress_pa", "hardening_pa"}}
_WORKSPACE_KEYS = {"lower", "upper"}


def list_scenarios() -> list[str]:
    """Names of the built-in scenarios (the paper's Table I), in the paper's order."""
    return list(builtin_scenarios())


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A built-in scenario by name, or a scenario read from a YAML file.

    Raises
    ------
    ConfigError
        Unknown name (or missing file), or a file with an unknown key or a bad value.
    """
    catalogue, key = builtin_scenarios(), str(name_or_path)
    if key in catalogue:
        return catalogue[key]
    path = Path(key)
    try:
        is_file = path.is_file()
    except OSError as exc:  # a name too long, no permission: not a file we can read
        raise ConfigError(f"{path}: cannot read the scenario file: {exc.strerror or exc}") from None
    if not is_file:
        raise ConfigError(
            f"unknown scenario {key!r}: not a built-in name ({', '.join(catalogue)}) "
            "and not an existing YAML file")
    return parse_scenario(load_yaml(path, what="the scenario file"), source=str(path))


def save_scenario(scenario: Scenario, path: str | Path) -> None:
    """Write ``scenario`` as YAML that :func:`load_scenario` reads back to an equal scenario."""
    dump_yaml(scenario.to_dict(), path)


def _unknown(where: str, data: dict[str, Any], allowed: set[str]) -> None:
    extra = sorted(map(str, set(data) - allowed))
    if extra:
        raise ConfigError(f"{where}: unknown key(s) {few(extra)}; allowed: {sorted(allowed)}")


def _block(data: Any, where: str) -> Block:
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: a block must be a mapping; got {type(data).__name__}")
    _unknown(where, data, _BLOCK_KEYS)
    if ("rect" in data) == ("polygon" in data):
        raise ConfigError(f"{where}: give exactly one of `rect` or `polygon`")
    try:
        if "rect" in data:
            r = np.asarray(data["rect"], dtype=float)
            if r.shape != (4,) or not (r[2] > r[0] and r[3] > r[1]):
                raise ConfigError(
                    f"{where}: `rect` must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0; "
                    f"got {data['rect']!r}")
            poly = rectangle(*r)
        else:
            poly = np.asarray(data["polygon"], dtype=float)
        rigid = data.get("rigid", False)
        if not isinstance(rigid, bool):
            raise ConfigError(f"{where}: `rigid` must be true or false; got {rigid!r}")
        look = data.get("appearance")
        materials: dict[str, Any] = {}
        for key, cls in (("viscoelastic", Viscoelastic), ("anisotropy", Orthotropic),
                         ("plastic", Plastic)):
            if key in data:
                part = data[key]
                if not isinstance(part, dict):
                    raise ConfigError(f"{where}.{key}: must be a mapping with keys "
                                      f"{sorted(_MATERIAL_KEYS[key])}; got {type(part).__name__}")
                _unknown(f"{where}.{key}", part, _MATERIAL_KEYS[key])
                try:
                    materials[key] = cls(**part)
                except (TypeError, ValueError, DeformapError) as exc:
                    raise ConfigError(f"{where}.{key}: {exc}") from None
        return Block(
            name=data.get("name", ""), polygon=poly,
            holes=tuple(np.asarray(h, dtype=float) for h in data.get("holes", ())),
            thickness_m=data.get("thickness_m", 0.05),
            hardness_n=data.get("hardness_n"), youngs_modulus_pa=data.get("youngs_modulus_pa"),
            rigid=rigid, color=data.get("color", "#6b4f3a" if rigid else "#c8a165"),
            appearance=None if look is None else _appearance(look, f"{where}.appearance"),
            **materials)
    except ConfigError:
        raise
    except (TypeError, ValueError, DeformapError) as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _appearance(data: Any, where: str) -> Appearance:
    try:
        return appearance_from_dict(data, where)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def parse_scenario(data: Any, *, source: str = "<scenario>") -> Scenario:
    """Build a :class:`Scenario` from a parsed YAML mapping (see the module docstring)."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a scenario must be a mapping; got {type(data).__name__}")
    _unknown(source, data, _SCENARIO_KEYS)
    for key in ("name", "blocks"):
        if key not in data:
            raise ConfigError(f"{source}: missing required key `{key}`")
    if not isinstance(data["blocks"], list) or not data["blocks"]:
        raise ConfigError(f"{source}: `blocks` must be a non-empty list")
    blocks = tuple(_block(b, f"{source}: blocks[{i}]") for i, b in enumerate(data["blocks"]))
    ws = data.get("workspace", {"lower": [0.0, 0.0], "upper": [0.6, 0.4]})
    if not isinstance(ws, dict):
        raise ConfigError(f"{source}: `workspace` must be a mapping with `lower` and `upper`")
    _unknown(f"{source}: workspace", ws, _WORKSPACE_KEYS)
    table = data.get("table_appearance")
    table_look = None if table is None else _appearance(table, f"{source}: table_appearance")
    try:
        workspace = Workspace(lower=ws.get("lower", (0.0, 0.0)), upper=ws.get("upper", (0.6, 0.4)))
    except DeformapError as exc:
        raise ConfigError(f"{source}: workspace: {exc}") from None
    try:
        return Scenario(name=data["name"], blocks=blocks, workspace=workspace,
                        description=data.get("description", ""), table_appearance=table_look)
    except ConfigError:
        raise
    except DeformapError as exc:
        raise ConfigError(f"{source}: {exc}") from None
