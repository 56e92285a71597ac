"""Every field of every settings class is checked, from Python and from YAML alike.

The cases are generated from the classes themselves (each field's annotation and the bounds
declared beside it), so a field added later is covered without a new line here, and a field
whose class forgot to call ``check_settings`` fails.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from types import UnionType
from typing import Any, Literal, get_args, get_origin

import pytest

from deformap._config import config_from_dict, config_to_dict, dump_yaml, load_yaml
from deformap._validation import SettingError
from deformap.errors import ConfigError, InvalidArgumentError
from deformap.explore import (
    BetaFieldConfig,
    ExplorationConfig,
    ModulusFieldConfig,
    SurfaceGPConfig,
    TouchGPConfig,
)
from deformap.msm import ShapeMatchingConfig
from deformap.run import RobotConfig, RunConfig
from deformap.stiffness import StiffnessConfig
from deformap.world import CameraConfig, WorldConfig

_BOUNDS = "deformap.bounds"

#: Each settings class and where it sits in a run's YAML (``config.<path>.<field>``).
SECTIONS: dict[type, str] = {
    ExplorationConfig: "exploration",
    SurfaceGPConfig: "exploration.surface",
    TouchGPConfig: "exploration.touch",
    BetaFieldConfig: "exploration.beta_field",
    ModulusFieldConfig: "exploration.modulus_field",
    ShapeMatchingConfig: "exploration.shape_matching",
    StiffnessConfig: "exploration.stiffness",
    WorldConfig: "world",
    CameraConfig: "world.camera",
    RobotConfig: "robot",
}


def _bad_values(hint: Any, bounds: dict[str, Any]) -> list[Any]:
    """Values the annotation or a declared bound refuses (plain data, as YAML would give)."""
    origin = get_origin(hint)
    if origin in (typing.Union, UnionType):
        (inner,) = [a for a in get_args(hint) if a is not type(None)]
        return _bad_values(inner, bounds)
    if origin is Literal:
        return [str(get_args(hint)[0]) + "x", 3]
    if origin is tuple:
        args = get_args(hint)
        good = [1.0] * len(args)
        return [good[:-1], [*good, 1.0], ["x"] * len(args)]
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return [3]
    if hint is bool:
        return ["yes", 1]
    if hint is str:
        return [3]
    out: list[Any] = ["x"]
    if hint is int:
        out.append(2.5)
    if hint is float and bounds.get("finite", True):
        out.append(math.nan)
    for key in ("gt", "lt"):
        if key in bounds:
            out.append(bounds[key])
    if "ge" in bounds:
        out.append(bounds["ge"] - max(1.0, abs(bounds["ge"])) * (1 if hint is int else 1e-3))
    if "le" in bounds:
        out.append(bounds["le"] + max(1.0, abs(bounds["le"])) * (1 if hint is int else 1e-3))
    return out


def _cases() -> list[Any]:
    cases = []
    for cls, section in SECTIONS.items():
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            bounds = dict(f.metadata.get(_BOUNDS, {}))
            for value in _bad_values(hints[f.name], bounds):
                cases.append(pytest.param(cls, section, f.name, value,
                                          id=f"{section}.{f.name}={value!r}"))
    return cases


def _nested(path: str, value: Any) -> dict[str, Any]:
    head, _, rest = path.partition(".")
    return {head: _nested(rest, value) if rest else value}


@pytest.mark.parametrize(("cls", "section", "name", "value"), _cases())
def test_a_bad_value_is_refused_from_python_and_from_yaml_naming_the_field(
    cls: type, section: str, name: str, value: Any
) -> None:
    python_value = tuple(value) if isinstance(value, list) else value
    with pytest.raises(SettingError) as from_python:
        cls(**{name: python_value})
    assert from_python.value.field == name
    with pytest.raises(ConfigError) as from_yaml:
        config_from_dict(RunConfig, _nested(f"{section}.{name}", value))
    message = str(from_yaml.value)
    assert message.startswith(f"`config.{section}.{name}` "), message
    if f"{section}.{name}" in SECTIONS.values():  # a section: YAML must give it as a mapping
        assert message.endswith("must be a mapping of settings; got 3")
    else:
        assert message.endswith(from_python.value.detail)


@pytest.mark.parametrize(("name", "value"), [("scenario", 3), ("seed", 1.5), ("seed", -1),
                                             ("world", 3), ("exploration", "planned")])
def test_the_run_config_checks_its_own_fields(name: str, value: Any) -> None:
    with pytest.raises(InvalidArgumentError, match=f"`{name}`"):
        RunConfig(**{name: value})
    with pytest.raises(ConfigError, match=f"^`config.{name}`"):
        config_from_dict(RunConfig, {name: value})


def test_every_settings_class_is_covered() -> None:
    seen, todo = set(), [RunConfig]
    while todo:
        cls = todo.pop()
        for hint in typing.get_type_hints(cls).values():
            if isinstance(hint, type) and dataclasses.is_dataclass(hint) and hint not in seen:
                seen.add(hint)
                todo.append(hint)
    assert seen == set(SECTIONS)


def test_defaults_are_valid_and_survive_a_yaml_round_trip(tmp_path) -> None:
    config = RunConfig()
    dump_yaml(config, tmp_path / "config.yaml")
    assert config_from_dict(RunConfig, load_yaml(tmp_path / "config.yaml")) == config
    coarse = WorldConfig.coarse()
    assert config_from_dict(WorldConfig, config_to_dict(coarse)) == coarse


def test_a_misspelt_choice_is_refused_not_replaced_by_another() -> None:
    with pytest.raises(SettingError, match=r"`model` must be one of \['residual', 'height'\]"):
        TouchGPConfig(model="heigth")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=r"`config.exploration.touch.model` must be one of"):
        config_from_dict(RunConfig, {"exploration": {"touch": {"model": "heigth"}}})
    with pytest.raises(SettingError, match="`mode` must be one of"):
        ShapeMatchingConfig(mode="Quadratic")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"width": -640}, "`width` must be an integer >= 1; got -640"),
        ({"pitch_deg": 0.0}, "`pitch_deg` must be > 0; got 0.0"),
        ({"height": math.nan}, "`height` must be an integer; got nan"),
        ({"height_m": math.nan}, "`height_m` must be finite; got nan"),
        ({"flying_probability": 5.0}, "`flying_probability` must be <= 1; got 5.0"),
        ({"fov_deg": (58.0, 180.0)}, "`fov_deg` entry 1 must be < 180; got 180.0"),
        ({"baseline_m": 0.0}, "`baseline_m` must be > 0; got 0.0"),
        ({"use_embree": "no"}, "`use_embree` must be True or False"),
    ],
)
def test_the_camera_refuses_impossible_settings(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(SettingError, match=message):
        CameraConfig(**kwargs)
    section = {k: list(v) if isinstance(v, tuple) else v for k, v in kwargs.items()}
    with pytest.raises(ConfigError, match=f"`config.world.camera.{message[1:]}"):
        config_from_dict(RunConfig, {"world": {"camera": section}})


@pytest.mark.parametrize(
    ("cls", "kwargs", "name"),
    [
        (SurfaceGPConfig, {"z_min_m": 0.1, "z_max_m": 0.1}, "z_max_m"),
        (TouchGPConfig, {"noise_samples": 1}, "noise_samples"),
        (ShapeMatchingConfig, {"tol": 1e-4, "sweep_tol": 1e-5}, "sweep_tol"),
    ],
)
def test_rules_between_fields_name_a_field_too(
    cls: type, kwargs: dict[str, Any], name: str
) -> None:
    with pytest.raises(SettingError) as info:
        cls(**kwargs)
    assert info.value.field == name
    section = SECTIONS[cls]
    with pytest.raises(ConfigError, match=rf"^`config\.{section}\.{name}` "):
        config_from_dict(RunConfig, _nested(section, kwargs))


def test_a_file_that_is_no_run_config_is_named_without_its_whole_text(tmp_path) -> None:
    """`--config /etc/passwd` read as one long string: the error says what came in one short
    line, not the file's whole text."""
    text = "root:x:0:0:root:/root:/bin/bash " * 40
    with pytest.raises(ConfigError) as info:
        config_from_dict(RunConfig, text, where="passwd")
    message = str(info.value)
    assert message.startswith("`passwd` must be a mapping of settings; got str of 1280 characters")
    assert len(message) < 200
