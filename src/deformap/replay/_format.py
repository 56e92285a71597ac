"""The ``session.yaml`` of a recorded session (``docs/recording-format.md``), parsed strictly.

The file as a whole (unknown or missing keys, format name or version, workspace, probe, frame,
units) raises :class:`~deformap.errors.ConfigError` when loaded; the values of one poke's entry
are kept as that poke's error and raised when it is read, so one broken poke hides no other.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._config import few
from deformap._validation import (
    LIMITS,
    check_array,
    check_int,
    check_limit,
    check_positive,
    check_rigid_transform,
    check_vector,
)
from deformap.cloud import PointCloud
from deformap.cloud.io import UNITS
from deformap.environment import ForceTravel, PressPhase, Workspace
from deformap.errors import ConfigError, DeformapError
from deformap.replay._confine import confined_path

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "OPTIONAL_TOPICS", "SESSION_FILE", "TOPICS",
           "PokeSpec", "PressParts", "SessionHeader", "parse_session_yaml"]

logger = logging.getLogger(__name__)

FORMAT_NAME = "deformap-session"
FORMAT_VERSION = 1
SESSION_FILE = "session.yaml"

#: Topic names of the bag form and their message types.
TOPICS = {"observation": ("/deformap/observation", "sensor_msgs/msg/PointCloud2"),
          "cloud": ("/deformap/press/cloud", "sensor_msgs/msg/PointCloud2"),
          "wrench": ("/deformap/press/wrench", "geometry_msgs/msg/WrenchStamped"),
          "tip": ("/deformap/press/tip", "geometry_msgs/msg/PointStamped"),
          "robot": ("/deformap/press/robot", "sensor_msgs/msg/PointCloud2")}

#: Topics of the bag form that a bag may lack (then no poke has what they carry).
OPTIONAL_TOPICS = {"force_travel": ("/deformap/press/force_travel",
                                    "std_msgs/msg/Float64MultiArray"),
                   "released": ("/deformap/press/released", "sensor_msgs/msg/PointCloud2")}

_TOP_REQUIRED = {"format", "version", "workspace", "probe", "pokes"}
_TOP_OPTIONAL = {"units", "frame", "cam2world", "ground_truth", "source", "observation", "bag",
                 "n_pokes", "sha256"}
_FOLDER_POKE_KEYS = {"cloud", "tip_center", "force", "target_xy", "force_n", "robot_points"}
_BAG_POKE_KEYS = {"stamp_ns", "target_xy", "force_n"}
_RECORD_KEYS = {"travel_m", "force_n"}
_RECORD_OPTIONAL = {"time_s", "hold", "unloading"}
_PHASE_KEYS = {"time_s", "travel_m", "force_n"}


@dataclass(frozen=True, kw_only=True)
class PokeSpec:
    """One poke's entry in ``session.yaml``, its values checked (world frame, SI).

    ``index`` is its place in ``pokes`` (0-based); ``target_xy`` and ``force_n`` the command. The
    folder form has ``cloud`` (a file), the contact ``tip_center`` and ``force``, ``robot_points``
    (a file or inline points), an optional ``force_travel`` (with, optionally, its ``time_s``,
    ``hold`` and ``unloading``) and an optional ``released`` (a cloud file of the surface once the
    tip has left); the bag form the ``stamp_ns`` its
    messages share. ``error`` says why the entry cannot be used (raised when the poke is read).
    """

    index: int
    target_xy: NDArray[np.float64] | None = None
    force_n: float | None = None
    cloud: Path | None = None
    tip_center: NDArray[np.float64] | None = None
    force: NDArray[np.float64] | None = None
    robot_points: Path | NDArray[np.float64] | None = None
    stamp_ns: int | None = None
    force_travel: ForceTravel | None = None
    released: Path | None = None
    error: DeformapError | None = None


@dataclass(frozen=True, kw_only=True)
class SessionHeader:
    """What ``session.yaml`` says about the whole session.

    ``root`` is the session folder; ``form`` ``"folder"``, ``"bag"`` or ``"raw"``; ``units`` those of
    the stored coordinates; ``cam2world`` maps clouds from ``frame`` to the world (a 4×4 matrix,
    ``"tf_static"`` or None when ``frame == "world"``). ``observation`` (folder form) and ``bag``
    name the data; ``source`` is free-form provenance copied into reports; ``sha256`` the manifest
    (file → digest), empty when the file has none.
    """

    root: Path
    form: str
    units: str
    frame: str
    cam2world: NDArray[np.float64] | str | None
    workspace: Workspace
    tip_radius_m: float
    observation: Path | None
    bag: Path | None
    ground_truth: Path | None
    source: dict[str, Any]
    pokes: tuple[PokeSpec, ...]
    sha256: dict[Path, str] = field(default_factory=dict)


@dataclass(frozen=True)
class PressParts:
    """What one poke's files hold before it becomes a ``PressObservation`` (world frame, SI)."""

    cloud: PointCloud
    tip_center: NDArray[np.float64]
    force: NDArray[np.float64]
    robot_points: NDArray[np.float64] | tuple[NDArray[np.float64], ...]  # one hull, or per part
    force_travel: ForceTravel | None = None
    released: PointCloud | None = None


def _where(file: Path, key: str) -> str:
    return f"{file}: `{key}`"


def _check_keys(file: Path, key: str, data: Any, required: set[str],
                optional: frozenset[str] | set[str] = frozenset()) -> None:

    if not isinstance(data, dict):
        raise ConfigError(f"{_where(file, key)} must be a mapping; got {type(data).__name__}")
    keys = {str(k) for k in data}
    unknown = sorted(keys - required - optional)
    if unknown:
        raise ConfigError(
            f"{_where(file, key)} has unknown key(s) {few(unknown)}; "
            f"allowed: {sorted(required | optional)}")
    missing = sorted(required - keys)
    if missing:
        raise ConfigError(f"{_where(file, key)} lacks required key(s) {missing}")


def _name(file: Path, key: str, value: Any, root: Path) -> Path:
    return confined_path(_where(file, key), value, root)


def _value(file: Path, key: str, check: Any, *args: Any, **kwargs: Any) -> Any:
    """Run a ``check_*`` validator and turn its refusal into a ConfigError naming the key."""
    try:
        return check(key, *args, **kwargs)
    except DeformapError as exc:
        raise ConfigError(f"{file}: {exc}") from None


def _cam2world(file: Path, data: dict[str, Any], frame: str, form: str) -> Any:
    raw = data.get("cam2world")
    if frame == "world":
        if raw is not None:
            raise ConfigError(
                f"{_where(file, 'cam2world')} is given but `frame` is 'world': the clouds are "
                "already in the world frame; remove one of the two")
        return None
    if raw is None:
        raise ConfigError(
            f"{_where(file, 'frame')} is {frame!r}, not 'world', so `cam2world` (a 4×4 "
            "camera-to-world matrix) is required" + (" or 'tf_static'" if form == "bag" else ""))
    if raw == "tf_static":
        if form != "bag":
            raise ConfigError(f"{_where(file, 'cam2world')}: 'tf_static' needs the bag form")
        return "tf_static"
    return _value(file, "cam2world", check_rigid_transform, raw)


def _poke(file: Path, index: int, data: Any, form: str, root: Path) -> PokeSpec:
    key = f"pokes[{index}]"
    if form == "bag":
        _check_keys(file, key, data, _BAG_POKE_KEYS)
    else:
        _check_keys(file, key, data, _FOLDER_POKE_KEYS, {"force_travel", "released"})
        if "force_travel" in data:
            raw = data["force_travel"]
            _check_keys(file, f"{key}.force_travel", raw, _RECORD_KEYS, _RECORD_OPTIONAL)
            for phase in ("hold", "unloading"):
                if phase in raw:
                    _check_keys(file, f"{key}.force_travel.{phase}", raw[phase], _PHASE_KEYS)
        if isinstance(data.get("released"), str):
            _name(file, f"{key}.released", data["released"], root)

        # Schema problems and names outside the session folder fail the file; value problems
        # (below) fail only this poke.
        for name in ("cloud", "robot_points"):
            if isinstance(data[name], str):
                _name(file, f"{key}.{name}", data[name], root)
    try:
        target = _value(file, f"{key}.target_xy", check_vector, data["target_xy"], 2, what="metres")
        force_n = _value(file, f"{key}.force_n", check_positive, data["force_n"])
        if form == "bag":
            stamp = _value(file, f"{key}.stamp_ns", check_int, data["stamp_ns"], minimum=0)
            return PokeSpec(index=index, target_xy=target, force_n=force_n, stamp_ns=stamp)
        center = _value(file, f"{key}.tip_center", check_vector, data["tip_center"], 3,
                        what="metres")  # fmt: skip
        force = _value(file, f"{key}.force", check_vector, data["force"], 3, what="newtons")
        if not np.any(force):
            raise ConfigError(f"{_where(file, key + '.force')} must be non-zero; got (0, 0, 0)")
        cloud = _name(file, f"{key}.cloud", data["cloud"], root)
        robot = data["robot_points"]
        robot = (_name(file, f"{key}.robot_points", robot, root) if isinstance(robot, str) else
                 _value(file, f"{key}.robot_points", check_array, robot, (None, 3),
                        what="points in metres", min_rows=4))  # fmt: skip
        record = None
        if "force_travel" in data:
            record = _record(file, key + ".force_travel", data["force_travel"])
        released = None
        if "released" in data:
            released = _name(file, f"{key}.released", data["released"], root)
        return PokeSpec(index=index, target_xy=target, force_n=force_n, cloud=cloud,
                        tip_center=center, force=force, robot_points=robot,
                        force_travel=record, released=released)  # fmt: skip
    except ConfigError as exc:
        return PokeSpec(index=index, error=exc)


def _record(file: Path, key: str, raw: dict[str, Any]) -> ForceTravel:
    """The ``force_travel`` entry (keys checked) as a record; its values' refusal names the key."""
    name = key
    try:
        phases = {}
        for phase in ("hold", "unloading"):
            if phase in raw:
                name = f"{key}.{phase}"
                phases[phase] = PressPhase(**{k: raw[phase][k] for k in _PHASE_KEYS})
        name = key
        return ForceTravel(travel_m=raw["travel_m"], force_n=raw["force_n"],
                           time_s=raw.get("time_s"), **phases)
    except DeformapError as exc:
        raise ConfigError(f"{_where(file, name)}: {exc}") from None


def _workspace(file: Path, data: Any) -> Workspace:
    _check_keys(file, "workspace", data, {"lower", "upper"})
    lower = _value(file, "workspace.lower", check_vector, data["lower"], 2, what="metres")
    upper = _value(file, "workspace.upper", check_vector, data["upper"], 2, what="metres")
    try:
        return Workspace(lower=tuple(lower), upper=tuple(upper))
    except DeformapError as exc:
        raise ConfigError(f"{_where(file, 'workspace')}: {exc}") from None


def parse_session_yaml(data: Any, file: Path) -> SessionHeader:
    """Check the plain data of a ``session.yaml``; a schema problem is a ConfigError naming the
    file and the key (``pokes[3].force``)."""
    root = file.parent
    _check_keys(file, "(top level)", data, _TOP_REQUIRED, _TOP_OPTIONAL)
    if data["format"] != FORMAT_NAME:
        raise ConfigError(
            f"{_where(file, 'format')} must be {FORMAT_NAME!r}; got {data['format']!r}")
    if data["version"] != FORMAT_VERSION or isinstance(data["version"], bool):
        raise ConfigError(
            f"{_where(file, 'version')} must be {FORMAT_VERSION} (this deformap reads format "
            f"version {FORMAT_VERSION}); got {data['version']!r}")
    has_bag, has_obs = "bag" in data, "observation" in data
    if has_bag == has_obs:
        raise ConfigError(
            f"{file}: give exactly one of `observation` (folder form) and `bag` (bag form); "
            f"got {'both' if has_bag else 'neither'}")
    form = "bag" if has_bag else "folder"
    units = data.get("units", "m")
    if not isinstance(units, str) or units not in UNITS:
        raise ConfigError(f"{_where(file, 'units')} must be one of {sorted(UNITS)}; got {units!r}")
    frame = data.get("frame", "world")
    if not isinstance(frame, str) or not frame:
        raise ConfigError(f"{_where(file, 'frame')} must be a non-empty string; got {frame!r}")
    cam2world = _cam2world(file, data, frame, form)
    workspace = _workspace(file, data["workspace"])
    _check_keys(file, "probe", data["probe"], {"tip_radius_m"})
    tip = _value(file, "probe.tip_radius_m", check_limit, data["probe"]["tip_radius_m"],
                 "tip_radius_m")
    source = data.get("source") or {}
    if not isinstance(source, dict):
        raise ConfigError(
            f"{_where(file, 'source')} must be a mapping; got {type(source).__name__}")
    pokes = data["pokes"]
    if not isinstance(pokes, list):
        raise ConfigError(f"{_where(file, 'pokes')} must be a list; got {type(pokes).__name__}")
    _check_poke_count(file, data, pokes)
    digests = _manifest(file, data.get("sha256"), root)
    truth = data.get("ground_truth")
    specs = [_poke(file, i, p, form, root) for i, p in enumerate(pokes)]
    return SessionHeader(
        root=root, form=form, units=units, frame=frame, cam2world=cam2world,
        workspace=workspace, tip_radius_m=tip,
        observation=_name(file, "observation", data["observation"], root) if has_obs else None,
        bag=_name(file, "bag", data["bag"], root) if has_bag else None,
        ground_truth=None if truth is None else _name(file, "ground_truth", truth, root),
        source={str(k): v for k, v in source.items()},
        pokes=tuple(_unique_stamps(file, specs)), sha256=digests)


def _check_poke_count(file: Path, data: dict[str, Any], pokes: list[Any]) -> None:
    """``pokes`` may list at most the pokes one map is made of (``LIMITS["pokes"]``, the cap of
    ``exploration.max_pokes``); ``n_pokes``, when given, must count its entries: a file cut at a
    poke boundary is still valid YAML."""
    most = LIMITS["pokes"]["le"]
    if len(pokes) > most:
        raise ConfigError(
            f"{_where(file, 'pokes')} lists {len(pokes):,} pokes; a map is made of at most "
            f"{most:,} (as `exploration.max_pokes`): split the session")
    if "n_pokes" not in data:
        logger.info("%s: no `n_pokes`; cannot check that the poke list is complete", file)
        return
    count = data["n_pokes"]
    if not isinstance(count, int) or isinstance(count, bool) or count < 0:
        raise ConfigError(f"{_where(file, 'n_pokes')} must be a whole number >= 0; got {count!r}")
    if count != len(pokes):
        raise ConfigError(
            f"{_where(file, 'n_pokes')} is {count} but `pokes` lists {len(pokes)} entries; "
            "the file was cut or edited")


_HEX64 = re.compile(r"[0-9a-f]{64}")


def _manifest(file: Path, raw: Any, root: Path) -> dict[Path, str]:
    """The ``sha256`` manifest: file name (inside the session folder) → lowercase hex digest."""
    if raw is None:
        return {}
    if not isinstance(raw, dict) or not raw:
        raise ConfigError(
            f"{_where(file, 'sha256')} must be a non-empty mapping of file name to SHA-256; "
            f"got {raw!r:.80}")
    out = {}
    for name, digest in raw.items():
        key = f"sha256[{name!r}]"
        path = confined_path(_where(file, key), name, root)
        if not isinstance(digest, str) or not _HEX64.fullmatch(digest):
            raise ConfigError(
                f"{_where(file, key)} must be 64 lowercase hex digits; got {digest!r:.80}")
        out[path] = digest
    return out


def _unique_stamps(file: Path, specs: list[PokeSpec]) -> list[PokeSpec]:
    """Refuse a bag-form poke whose ``stamp_ns`` an earlier poke has: it would read that poke."""
    first: dict[int, int] = {}
    for i, spec in enumerate(specs):
        earlier = spec.index if spec.stamp_ns is None else first.setdefault(spec.stamp_ns, i)
        if earlier != spec.index:
            specs[i] = PokeSpec(index=i, error=ConfigError(
                f"{_where(file, f'pokes[{i}].stamp_ns')} is {spec.stamp_ns}, already the stamp "
                f"of `pokes[{earlier}]`; each poke needs its own messages"))
    return specs

