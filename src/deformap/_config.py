"""Frozen settings dataclasses to and from plain dicts and YAML, strictly.

Every component has one frozen, keyword-only dataclass of settings. This module turns any tree of
them into plain data (for ``config.yaml`` next to each result) and back. Reading back refuses
unknown keys itself and leaves every value to the dataclasses' own check
(:func:`deformap._validation.check_settings`, the one rule set for Python and YAML alike); either
refusal is a :class:`~deformap.errors.ConfigError` that names the field by its dotted path
(``exploration.threshold``).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import stat
import types
import typing
from pathlib import Path
from typing import Any, TypeVar, get_args, get_origin

import yaml

from deformap._validation import SettingError
from deformap.errors import ConfigError, DeformapError

#: Largest YAML file read (config, scenario, session): a session lists its pokes and files, never
#: their data, so even thousands of pokes stay far below this.
MAX_YAML_BYTES = 16 * 2**20

__all__ = ["config_from_dict", "config_to_dict", "dump_yaml", "load_yaml"]

logger = logging.getLogger(__name__)

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


def _shape(value: Any, hint: Any, where: str) -> Any:
    """Give plain data the shape ``hint`` asks for: a mapping becomes the nested settings dataclass,
    a list a tuple. Nothing is judged here: the dataclass's own :func:`check_settings` does that."""
    origin = get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        options = [a for a in get_args(hint) if a is not type(None)]
        return value if value is None or len(options) != 1 else _shape(value, options[0], where)
    if origin is tuple and isinstance(value, list):
        args = get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            args = (args[0],) * len(value)
        if len(args) != len(value):
            return tuple(value)  # the dataclass names the wrong length
        pairs = enumerate(zip(value, args, strict=True))
        return tuple(_shape(v, a, f"{where}[{i}]") for i, (v, a) in pairs)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return config_from_dict(hint, value, where=where)
    return value


def config_from_dict(cls: type[T], data: Any, *, where: str = "config") -> T:
    """Build the settings dataclass ``cls`` from plain data; missing keys keep their defaults.

    A class may read files written by an older version through a static ``upgrade_settings(data)
    -> data`` (called first, on its own level of the data). A key the class lists in its
    ``RETIRED_SETTINGS`` (a setting that was removed, with why) is
    accepted with a logged warning and dropped, so configuration files written before still load.
    The data is only shaped (mappings into nested dataclasses, lists into tuples) and handed to
    the constructor, whose ``__post_init__`` checks every field (:func:`check_settings`): a value
    is refused or accepted exactly as it would be from Python.

    Raises
    ------
    ConfigError
        On an unknown key, or a value the dataclass refuses; the message names the field's dotted
        path (``config.exploration.touch.model``).
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        shown = repr(data)
        if len(shown) > 80:  # a whole file read as one string (a file that is no run config)
            shown = f"{type(data).__name__} of {len(str(data))} characters, {shown[:60]}…"
        raise ConfigError(f"`{where}` must be a mapping of settings; got {shown}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}  # type: ignore[arg-type]
    # files written by an older version: the class reads them as they were meant
    upgrade = getattr(cls, "upgrade_settings", None)
    if upgrade is not None:
        data = upgrade(dict(data))
    # settings that were removed: accepted in files written before, said once, and dropped
    retired: dict[str, str] = getattr(cls, "RETIRED_SETTINGS", {})
    for key in sorted(set(data) & set(retired)):
        logger.warning("`%s.%s` is no longer a setting (%s); ignored", where, key, retired[key])
    data = {k: v for k, v in data.items() if k not in retired}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(
            f"`{where}` has unknown key(s) {unknown}; known keys are {sorted(fields)}"
        )
    hints = typing.get_type_hints(cls)
    kwargs = {name: _shape(value, hints[name], f"{where}.{name}") for name, value in data.items()}
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except SettingError as exc:
        raise ConfigError(f"`{where}.{exc.field}` {exc.detail}") from None
    except (DeformapError, TypeError, ValueError) as exc:
        raise ConfigError(f"`{where}`: {exc}") from None


class _UniqueKeyLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing a mapping that repeats a key (PyYAML keeps the last one
    silently: a session or config edited by hand would lose the first)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            try:
                repeated = key in seen
                seen.add(key)
            except TypeError:  # an unhashable key: PyYAML's own error follows
                continue
            if repeated:
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key {key!r} appears twice in one mapping",
                    key_node.start_mark)
        return super().construct_mapping(node, deep=deep)


def load_yaml(path: str | Path, *, what: str = "config file",
              unreadable: type[DeformapError] = ConfigError) -> Any:
    """Read a YAML file safely (no arbitrary objects); errors name the file.

    A file that cannot be read raises ``unreadable`` (``cannot read {what}``); bytes that are not
    UTF-8 text, or text PyYAML cannot take (a syntax error, nesting too deep, an impossible date
    such as 2020-02-30 from its timestamp constructor), raise :class:`ConfigError`.
    """
    p = Path(path)
    try:
        if not stat.S_ISREG(os.stat(p).st_mode):  # a FIFO would block, a device never end
            raise unreadable(f"cannot read {what} {str(p)!r}: not a regular file")
        with p.open("rb") as stream:
            raw = stream.read(MAX_YAML_BYTES + 1)
        if len(raw) > MAX_YAML_BYTES:
            raise unreadable(f"cannot read {what} {str(p)!r}: larger than "
                             f"{MAX_YAML_BYTES // 2**20} MiB")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise unreadable(f"cannot read {what} {str(p)!r}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{str(p)!r} is not UTF-8 text (byte {exc.start})") from None
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # a SafeLoader: plain data only
    except (yaml.YAMLError, RecursionError, ValueError) as exc:
        detail = f"{type(exc).__name__}: {exc}".replace("\n", " ")[:300]
        raise ConfigError(f"{str(p)!r} is not valid YAML: {detail}") from None


def dump_yaml(data: Any, path: str | Path | None = None) -> str:
    """Write plain data as YAML (block style, keys in definition order); return the text."""
    text = yaml.safe_dump(config_to_dict(data), sort_keys=False, default_flow_style=False)
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text
