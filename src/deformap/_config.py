"""Frozen settings dataclasses to and from plain dicts and YAML, strictly.

Reading back refuses unknown keys (a class's ``RETIRED_KEYS`` say why a removed one went) and
leaves every value to the dataclasses' own check (:func:`~deformap._validation.check_settings`, one
rule set for Python and YAML); either refusal is a :class:`~deformap.errors.ConfigError` naming the
field's dotted path (``exploration.threshold``).
"""

from __future__ import annotations

import dataclasses
import inspect
import os
import re
import stat
import textwrap
import types
import typing
from pathlib import Path
from typing import Any, Literal, TypeVar, get_args, get_origin

import yaml

from deformap._files import write_text_atomically
from deformap._validation import SettingError, setting_metadata
from deformap.errors import ConfigError, DeformapError

#: Largest YAML file read (config, scenario, session; a session lists files, not their data).
MAX_YAML_BYTES = 16 * 2**20
#: Deepest nesting of mappings and lists read: a settings file nests a few levels, and every walk
#: over what was read (its check, a report's JSON) recurses once per level.
MAX_YAML_DEPTH = 64

__all__ = ["NoAliasDumper", "config_from_dict", "config_to_dict", "data_file_kind",
           "described_yaml", "dump_yaml", "few", "load_yaml", "parse_yaml", "setting_docs"]
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
    """Give plain data the shape ``hint`` asks for (mappings into nested settings dataclasses,
    lists into tuples); the dataclass judges it."""
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


def few(names: list[str], most: int = 5) -> str:
    """``names`` as a list for a message: the first ``most``, each cut to 40 characters, and
    how many more."""
    shown = ", ".join(repr(n[:40]) for n in names[:most])
    return f"[{shown}" + (f" and {len(names) - most:,} more]" if len(names) > most else "]")


def config_from_dict(cls: type[T], data: Any, *, where: str = "config") -> T:
    """Build the settings dataclass ``cls`` from plain data; missing keys keep their defaults.

    The data is only shaped and handed to the constructor, so a value is refused or accepted exactly
    as from Python. An unknown key or a refused value is a ConfigError naming its dotted path
    (``config.exploration.touch.model``).
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        shown = repr(data)
        if len(shown) > 80:  # a whole file read as one string (a file that is no run config)
            shown = f"{type(data).__name__} of {len(str(data))} characters, {shown[:60]}…"
        raise ConfigError(f"`{where}` must be a mapping of settings; got {shown}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}  # type: ignore[arg-type]
    unknown = sorted(map(str, set(data) - set(fields)))
    for key in (k for k in unknown if k in getattr(cls, "RETIRED_KEYS", {})):  # why it went
        raise ConfigError(f"`{where}.{key}` was retired: {cls.RETIRED_KEYS[key]}; delete it")  # type: ignore[attr-defined]
    if unknown:
        raise ConfigError(
            f"`{where}` has unknown key(s) {few(unknown)}; known keys are {sorted(fields)}")
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


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing anchors and aliases (``&name``, ``*name``) anywhere and a
    mapping that repeats a key (PyYAML keeps the last).

    Without aliases a document has at most as many nodes as its text has characters, so reading
    it, and every walk over what it read, is bounded by the file's size: a nested alias bomb
    ("billion laughs") is refused at its first anchor, before anything is built.
    """

    def compose_node(self, parent: Any, index: Any) -> Any:
        event = self.peek_event()
        mark = event.start_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}"
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None) is not None:
            raise _AliasRefused(where)
        depth = getattr(self, "_depth", 0) + 1
        if depth > MAX_YAML_DEPTH:
            raise _TooDeep(where)
        self._depth = depth
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth = depth - 1

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


class _AliasRefused(Exception):
    """An anchor or alias met while composing (its place in the text)."""


class _TooDeep(Exception):
    """Nesting deeper than :data:`MAX_YAML_DEPTH` met while composing (its place in the text)."""


def parse_yaml(text: str, *, where: str) -> Any:
    """Plain data of the YAML ``text`` (one document; mappings, lists and scalars only).

    The one YAML reader of deformap: anchors and aliases are refused anywhere (so what is read is
    bounded by the text's size), and so are nesting deeper than :data:`MAX_YAML_DEPTH` and a
    mapping that repeats a key. ``where`` names the text
    in the message (a file's path, ``--set key``).

    Raises
    ------
    ConfigError
        One line naming ``where``: an anchor or alias (with its line), a syntax error, nesting too
        deep, an impossible date, a repeated key.
    """
    try:
        return yaml.load(text, Loader=_StrictLoader)  # a SafeLoader: plain data only
    except _AliasRefused as exc:
        raise ConfigError(
            f"{where}: YAML anchors and aliases (&name, *name) are not accepted ({exc}); "
            "write each value out in full") from None
    except _TooDeep as exc:
        raise ConfigError(f"{where}: YAML nested deeper than {MAX_YAML_DEPTH} levels ({exc})"
                          ) from None
    except (yaml.YAMLError, RecursionError, ValueError) as exc:
        detail = f"{type(exc).__name__}: {exc}".replace("\n", " ")[:300]
        raise ConfigError(f"{where} is not valid YAML: {detail}") from None


#: Leading bytes (or, for text formats, the suffix) of data files a YAML file is mistaken for.
_DATA_FILES = ((b"\x89MCAP", None, "an MCAP file (a ROS 2 bag)"),
               (b"SQLite format 3\x00", None, "a sqlite3 database (a ROS 2 bag?)"),
               (b"ply\n", ".ply", "a PLY point cloud"), (b"ply\r\n", ".ply", "a PLY point cloud"),
               (b"# .PCD", ".pcd", "a PCD point cloud"), (b"VERSION 0.", ".pcd", "a PCD point cloud"),
               (b"VERSION .", ".pcd", "a PCD point cloud"),
               (b"\x93NUMPY", ".npy", "a NumPy array file"),
               (b"PK\x03\x04", ".npz", "a zip archive (an NPZ file?)"),
               (b"\x89PNG", ".png", "a PNG image"))


def data_file_kind(path: Path, head: bytes) -> str | None:
    """What the file ``path`` whose first bytes are ``head`` is, when it is one of the data files
    deformap reads (a cloud, a bag, an array) rather than YAML; else None."""
    suffix = path.suffix.lower()
    for magic, known_suffix, kind in _DATA_FILES:
        if head.startswith(magic) or (known_suffix is not None and suffix == known_suffix):
            return kind
    return None


def load_yaml(path: str | Path, *, what: str = "config file",
              unreadable: type[DeformapError] = ConfigError) -> Any:
    """Read a YAML file through :func:`parse_yaml`; errors name the file.

    A file that cannot be read raises ``unreadable`` (``cannot read {what}``); a data file
    (:func:`data_file_kind`: a cloud, a bag), bytes that are not UTF-8, or text
    :func:`parse_yaml` refuses, raise :class:`ConfigError` (the first naming what the file is).
    """
    p = Path(path)
    try:
        if not stat.S_ISREG(os.stat(p).st_mode):  # a FIFO would block, a device never end
            raise unreadable(f"cannot read {what} {str(p)!r}: not a regular file")
        with p.open("rb") as stream:
            raw = stream.read(MAX_YAML_BYTES + 1)
        kind = data_file_kind(p, raw[:16])
        if kind is not None:
            raise ConfigError(f"{str(p)!r} is {kind}, not YAML ({what})")
        if len(raw) > MAX_YAML_BYTES:
            raise unreadable(f"cannot read {what} {str(p)!r}: larger than "
                             f"{MAX_YAML_BYTES // 2**20} MiB")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise unreadable(f"cannot read {what} {str(p)!r}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{str(p)!r} is not UTF-8 text (byte {exc.start})") from None
    return parse_yaml(text, where=repr(str(p)))


class NoAliasDumper(yaml.SafeDumper):
    """PyYAML's safe dumper writing a value met twice in full each time, never as an anchor and
    alias, so that :func:`parse_yaml` reads back what deformap writes."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


def dump_yaml(data: Any, path: str | Path | None = None) -> str:
    """Write plain data as YAML (block style, keys in definition order, no aliases); return the
    text. With ``path`` it is written there atomically (:mod:`deformap._files`: a failure is one
    :class:`~deformap.errors.FileWriteError` naming the file, nothing half-written left)."""
    text = yaml.dump(config_to_dict(data), Dumper=NoAliasDumper, sort_keys=False,
                     default_flow_style=False)
    if path is not None:
        write_text_atomically(path, text)
    return text


# -- the configuration reference: YAML with each setting's description, unit and bounds --------

#: Unit of a setting by the suffix of its name, longest first.
_UNIT_SUFFIXES = (("_n_per_m", "N/m"), ("_n_per_s", "N/s"), ("_kpa", "kPa"), ("_deg", "degrees"),
                  ("_rel", "fraction"), ("_pa", "Pa"), ("_mm", "mm"), ("_hz", "Hz"), ("_px", "pixels"),
                  ("_m", "m"), ("_n", "N"), ("_s", "s"))
#: Unit words a numpydoc type line may end with (``reference_modulus_pa : float, pascals``).
_UNIT_WORDS = {"metres": "m", "meters": "m", "newtons": "N", "pascals": "Pa", "seconds": "s",
               "degrees": "degrees", "radians": "rad", "n/m": "N/m"}
#: A sentence's end: a full stop and a capital, digit or quote next, not after an abbreviation.
_SENTENCE_END = re.compile(r"(?<![ .]al\.)(?<!e\.g\.)(?<!i\.e\.)(?<!Eq\.)(?<!Fig\.)(?<=[.!?])\s+"
                           r"(?=[A-Z0-9(`\"])")
_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")  # :mod:`deformap.world` -> deformap.world


def _parameters_section(cls: type) -> dict[str, tuple[str, str]]:
    """``name -> (type text, first sentence)`` of the numpydoc "Parameters" section of ``cls``;
    ``a, b : float`` documents both names."""
    lines = inspect.cleandoc(cls.__doc__ or "").splitlines()
    try:
        start = next(i for i in range(len(lines) - 1)
                     if lines[i].strip() == "Parameters" and set(lines[i + 1].strip()) == {"-"})
    except StopIteration:
        return {}
    entries: dict[str, tuple[str, str]] = {}
    names: list[str] = []
    text: list[str] = []
    kind = ""

    def flush() -> None:
        sentence = _SENTENCE_END.split(" ".join(text).strip(), maxsplit=1)[0]
        sentence = _ROLE.sub(r"\1", sentence).replace("``", "")
        entries.update({name: (kind, sentence) for name in names})

    for i in range(start + 2, len(lines)):
        line = lines[i]
        if i + 1 < len(lines) and line.strip() and set(lines[i + 1].strip()) == {"-"}:
            break  # the next section
        if line and not line[0].isspace():
            flush()
            head, _, kind = line.partition(" : ")
            names, text = [n.strip() for n in head.split(",")], []
        elif line.strip():
            text.append(line.strip())
    flush()
    return entries


def _unit(name: str, kind: str) -> str | None:
    for suffix, unit in _UNIT_SUFFIXES:
        if name.endswith(suffix):
            return unit
    if not kind.startswith("{") and "," in kind:
        return _UNIT_WORDS.get(kind.rsplit(",", 1)[1].strip().lower())
    return None


def _range(bounds: dict[str, Any]) -> str | None:
    """The :func:`~deformap._validation.setting` bounds as one interval, the tighter of each side."""
    low = max(((bounds[k], k == "gt") for k in ("gt", "ge") if k in bounds), default=None)
    high = min(((bounds[k], k == "le") for k in ("lt", "le") if k in bounds), default=None)
    if low is not None and high is not None:
        return f"{'(' if low[1] else '['}{low[0]:g}, {high[0]:g}{']' if high[1] else ')'}"
    if low is not None:
        return f"{'>' if low[1] else '>='} {low[0]:g}"
    if high is not None:
        return f"{'<=' if high[1] else '<'} {high[0]:g}"
    return None


def _facts(name: str, hint: Any, kind: str, bounds: dict[str, Any]) -> list[str]:
    """Unit, range, choices and ``null`` of one setting, as ``key: value`` phrases."""
    facts = []
    options = get_args(hint) if get_origin(hint) in (typing.Union, types.UnionType) else (hint,)
    unit = _unit(name, kind)
    if unit is not None:
        facts.append(f"unit: {unit}")
    if any(o in (int, float) or get_origin(o) is tuple for o in options):
        interval = _range(bounds)
        if interval is not None:
            facts.append(f"range: {interval}")
    for option in options:
        if get_origin(option) is Literal:
            facts.append("one of: " + ", ".join(str(c) for c in get_args(option)))
    if type(None) in options:
        facts.append("null allowed")
    return facts


def setting_docs(cls: type, prefix: str = "") -> list[tuple[str, str | None, list[str]]]:
    """``(dotted name, description or None, facts)`` of every setting of ``cls``, nested ones
    included, in definition order.

    The description is the field's ``setting(doc=...)``, else the first sentence of its "Parameters"
    entry, else (nested settings) its class docstring's first line. The facts are its unit (from the
    name's suffix or its numpydoc type), bounds, ``Literal`` choices and whether it may be ``None``.
    """
    params = _parameters_section(cls)
    hints = typing.get_type_hints(cls)
    out: list[tuple[str, str | None, list[str]]] = []
    for f in dataclasses.fields(cls):
        bounds, doc = setting_metadata(f)
        kind, sentence = params.get(f.name, ("", ""))
        hint = hints[f.name]
        nested = isinstance(hint, type) and dataclasses.is_dataclass(hint)
        if doc is None and sentence:
            doc = sentence
        if doc is None and nested and hint.__doc__:
            doc = inspect.cleandoc(hint.__doc__).splitlines()[0]
        out.append((prefix + f.name, doc, [] if nested else _facts(f.name, hint, kind, bounds)))
        if nested:
            out.extend(setting_docs(hint, prefix + f.name + "."))
    return out


def described_yaml(config: Any, *, width: int = 99) -> str:
    """``config`` as YAML with a comment above each setting (:func:`setting_docs`); it loads
    back as :func:`dump_yaml`'s text does."""
    docs = {name: (doc, facts) for name, doc, facts in setting_docs(type(config))}
    lines = [f"# {type(config).__name__}: every setting, with its description, unit and bounds."]
    _describe(config, "", docs, lines, width)
    return "\n".join(lines) + "\n"


def _describe(obj: Any, prefix: str, docs: dict[str, tuple[str | None, list[str]]],
              lines: list[str], width: int) -> None:
    indent = "  " * prefix.count(".")
    for f in dataclasses.fields(obj):
        name = prefix + f.name
        value = getattr(obj, f.name)
        doc, facts = docs[name]
        nested = dataclasses.is_dataclass(value) and dataclasses.fields(value)
        if nested and not prefix:
            lines.append("")
        comment = textwrap.wrap(doc or "", width - len(indent) - 2)
        if facts:
            comment.append("; ".join(facts))
        lines.extend(f"{indent}# {text}" for text in comment)
        if nested:
            lines.append(f"{indent}{f.name}:")
            _describe(value, name + ".", docs, lines, width)
            continue
        text = yaml.dump({f.name: config_to_dict(value)}, Dumper=NoAliasDumper, sort_keys=False,
                         default_flow_style=False)
        lines.extend(indent + line for line in text.splitlines())
