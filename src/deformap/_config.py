"""Frozen settings dataclasses to and from plain dicts and YAML, strictly.

Every component has one frozen, keyword-only dataclass of settings. This module turns any tree of
them into plain data (for ``config.yaml`` next to each result) and back, refusing unknown keys, wrong
types and out-of-range values with a :class:`~deformap.errors.ConfigError` that names the field by
its dotted path (``exploration.threshold``).
"""

from __future__ import annotations

import dataclasses
import types
import typing
from pathlib import Path
from typing import Any, Literal, TypeVar, get_args, get_origin

import yaml

from deformap.errors import ConfigError, DeformapError

__all__ = ["config_from_dict", "config_to_dict", "dump_yaml", "load_yaml"]

T = TypeVar("T")


def config_to_dict(obj: Any) -> Any:
    """Plain-data form of a settings dataclass tree (tuples become lists)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: config_to_dict(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (list, tuple)):
        return [config_to_dict(v) for v in obj]
    if hasattr(obj, "tolist") and callable(obj.tolist):  # numpy array or scalar
        return obj.tolist()
    if isinstance(obj, dict):
        return {str(k): config_to_dict(v) for k, v in obj.items()}
    return obj


def _convert(value: Any, hint: Any, where: str) -> Any:
    origin = get_origin(hint)
    if hint is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        options = get_args(hint)
        if value is None and type(None) in options:
            return None
        errors = []
        for option in options:
            if option is type(None):
                continue
            try:
                return _convert(value, option, where)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(errors[0] if errors else f"`{where}`: unexpected value {value!r}")
    if origin is Literal:
        choices = get_args(hint)
        if value not in choices:
            raise ConfigError(f"`{where}` must be one of {list(choices)}; got {value!r}")
        return value
    if origin is tuple:
        args = get_args(hint)
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"`{where}` must be a list; got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], f"{where}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(f"`{where}` must have {len(args)} entries; got {len(value)}")
        pairs = enumerate(zip(value, args, strict=True))
        return tuple(_convert(v, a, f"{where}[{i}]") for i, (v, a) in pairs)
    if dataclasses.is_dataclass(hint):
        return config_from_dict(hint, value, where=where)  # type: ignore[arg-type]
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"`{where}` must be true or false; got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"`{where}` must be an integer; got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"`{where}` must be a number; got {value!r}")
        return float(value)
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(f"`{where}` must be a string; got {value!r}")
        return value
    return value


def config_from_dict(cls: type[T], data: Any, *, where: str = "config") -> T:
    """Build the settings dataclass ``cls`` from plain data; missing keys keep their defaults.

    Raises
    ------
    ConfigError
        On an unknown key, a value of the wrong type, or a value the dataclass itself refuses;
        the message names the field's dotted path.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"`{where}` must be a mapping of settings; got {data!r}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}  # type: ignore[arg-type]
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(
            f"`{where}` has unknown key(s) {unknown}; known keys are {sorted(fields)}"
        )
    hints = typing.get_type_hints(cls)
    kwargs = {name: _convert(value, hints[name], f"{where}.{name}") for name, value in data.items()}
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (DeformapError, TypeError, ValueError) as exc:
        raise ConfigError(f"`{where}`: {exc}") from None


def load_yaml(path: str | Path, *, what: str = "config file",
              unreadable: type[DeformapError] = ConfigError) -> Any:
    """Read a YAML file safely (no arbitrary objects); errors name the file.

    A file that cannot be read raises ``unreadable`` (``cannot read {what}``); bytes that are not
    UTF-8 text, or text PyYAML cannot take (a syntax error, nesting too deep, an impossible date
    such as 2020-02-30 from its timestamp constructor), raise :class:`ConfigError`.
    """
    p = Path(path)
    try:
        text = p.read_bytes().decode("utf-8")
    except OSError as exc:
        raise unreadable(f"cannot read {what} {str(p)!r}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{str(p)!r} is not UTF-8 text (byte {exc.start})") from None
    try:
        return yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError, ValueError) as exc:
        detail = f"{type(exc).__name__}: {exc}".replace("\n", " ")[:300]
        raise ConfigError(f"{str(p)!r} is not valid YAML: {detail}") from None


def dump_yaml(data: Any, path: str | Path | None = None) -> str:
    """Write plain data as YAML (block style, keys in definition order); return the text."""
    text = yaml.safe_dump(config_to_dict(data), sort_keys=False, default_flow_style=False)
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text
