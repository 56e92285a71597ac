"""A recorded session read back: ``load_session``, ``load_raw_bag`` and ``RecordedSession``.

A session is a folder of ``session.yaml`` (``docs/recording-format.md``) and either one cloud file
per observation (folder form, read here; contacts in ``session.yaml``) or a ROS 2 bag (bag form);
a robot's own bag opens as a session of form ``"raw"``, one poke per press found. Loading checks
the whole ``session.yaml`` and opens the data; each poke is read and checked only when asked for,
so that a broken poke is reported on its own.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from deformap._config import config_to_dict, load_yaml
from deformap._validation import check_instance, check_int, check_path, check_positive
from deformap.cloud import PointCloud, points_in_hull
from deformap.cloud.io import path_kind, read_cloud
from deformap.environment import PressObservation, TactileContact, Workspace
from deformap.errors import ConfigError, DeformapError, FileFormatError, InvalidArgumentError
from deformap.replay._bagform import BagReader
from deformap.replay._confine import (
    check_manifest_complete,
    check_no_links,
    check_seal,
    verify_digest,
)
from deformap.replay._format import (
    SESSION_FILE,
    PokeSpec,
    PressParts,
    SessionHeader,
    parse_session_yaml,
)
from deformap.replay._rawbag import RawBagReader
from deformap.replay._rawconfig import RawBagConfig
from deformap.replay._truth import GroundTruth, read_ground_truth

__all__ = ["DEFAULT_CONTACT_GAP_M", "RAW_SUFFIXES", "RecordedSession", "check_contact_gap",
           "is_raw_bag", "load_raw_bag", "load_session"]

logger = logging.getLogger(__name__)

#: A poke whose contact point lies farther than this [m] from every surface point of its cloud
#: is refused: the robot hides a few centimetres around the tip, while a tip or cloud in the
#: wrong frame or units lands tens of centimetres away.
DEFAULT_CONTACT_GAP_M = 0.05


class FolderReader:
    """Reads the files a folder-form ``session.yaml`` names, one at a time."""

    def __init__(self, header: SessionHeader) -> None:
        self.header = header
        assert header.observation is not None
        if path_kind(header.observation) != "file":
            raise FileFormatError(
                f"{header.observation}: no such file (the session's `observation`)")

    def _read(self, path: Path | None, to_world: bool = True) -> PointCloud:
        assert path is not None
        if path_kind(path) != "file":
            raise FileFormatError(f"{path}: no such file")
        verify_digest(self.header.sha256, path)
        cloud = read_cloud(path, units=self.header.units)
        if not to_world or self.header.frame == "world":
            return cloud
        assert isinstance(self.header.cam2world, np.ndarray)  # parse_session_yaml guarantees it
        return PointCloud(cloud.points, cloud.colors, frame=self.header.frame).transformed(
            self.header.cam2world, "world")

    def observation(self) -> PointCloud:
        return self._read(self.header.observation)

    def press_parts(self, spec: PokeSpec) -> PressParts:
        assert spec.cloud is not None and spec.tip_center is not None and spec.force is not None
        cloud, robot = self._read(spec.cloud), spec.robot_points
        if isinstance(robot, Path):
            # Robot geometry comes from the robot model in the world (base) frame, not the camera's.
            robot = np.asarray(self._read(robot, to_world=False).points)
        assert robot is not None
        released = None if spec.released is None else self._read(spec.released)
        return PressParts(cloud, spec.tip_center, spec.force, robot, spec.force_travel, released)


@dataclass(eq=False)
class RecordedSession:
    """A recorded session: ``header`` (all ``session.yaml`` says), the optional ``ground_truth``,
    and the observation and pokes read on demand (build one with :func:`load_session`)."""

    path: Path
    header: SessionHeader
    ground_truth: GroundTruth | None
    _reader: FolderReader | BagReader | RawBagReader = field(repr=False)
    contact_gap_m: float = DEFAULT_CONTACT_GAP_M

    @property
    def form(self) -> str:
        """``"folder"``, ``"bag"`` or ``"raw"`` (a bag as a robot records it)."""
        return self.header.form

    @property
    def workspace(self) -> Workspace:
        return self.header.workspace


    @property
    def source(self) -> dict[str, Any]:
        """Free-form provenance from ``session.yaml`` (scenario, seed, ...); a raw bag's holds
        what was found in it and, once its presses are read, ``presses``: what each one's entry
        says beyond its β (:meth:`poke_notes`)."""
        out = dict(self.header.source)
        notes = getattr(self._reader, "notes", None)
        if notes:
            out["presses"] = {str(i + 1): dict(n) for i, n in sorted(notes.items())}
        return out

    def poke_notes(self, index: int) -> dict[str, str]:
        """What was noted while poke ``index`` was read: ``force_travel`` (why its record was not
        used), ``disagreement`` (the record and the camera disagree), the camera's dent and the
        record's travel; ``stamp_gaps_s``, topic → how far [s] the message used lies from the
        poke's stamp (a bag-form session read with a stamp tolerance); else empty."""
        notes = getattr(self._reader, "notes", None)
        return dict(notes.get(index, {})) if notes else {}

    def __len__(self) -> int:
        return len(self.header.pokes)

    def observation(self) -> PointCloud:
        """The initial observation of the undisturbed surface, world frame, metres."""
        return self._reader.observation()

    def press_observation(self, index: int) -> PressObservation:
        """Poke ``index`` (0-based, in recorded order) as the environment returned it; a broken
        poke raises FileFormatError or ConfigError naming its file, key or topic."""
        i = check_int("index", index, minimum=0)
        if i >= len(self):
            raise InvalidArgumentError(f"`index` must be < {len(self)} (the pokes); got {i}")
        spec = self.header.pokes[i]
        if spec.error is not None:
            raise spec.error
        parts = self._reader.press_parts(spec)
        assert spec.target_xy is not None and spec.force_n is not None  # set when no error
        # a raw bag's presses are named from 1, in the bag itself (it has no session.yaml)
        where = (f"{self.path}: press {i + 1}" if self.form == "raw"
                 else f"{self.path / SESSION_FILE}: poke {i}")  # fmt: skip
        try:
            contact = TactileContact(tip_center=parts.tip_center, force=parts.force,
                                     tip_radius_m=self.header.tip_radius_m)  # fmt: skip
            obs = PressObservation(cloud=parts.cloud, contact=contact,
                                   robot_points=parts.robot_points, target_xy=spec.target_xy,
                                   force_n=spec.force_n,
                                   force_travel=parts.force_travel,
                                   released=parts.released)  # fmt: skip
        except InvalidArgumentError as exc:
            raise FileFormatError(f"{where}: {exc}") from None
        self._check_contact(obs, where)
        return obs

    def _check_contact(self, obs: PressObservation, where: str) -> None:
        point = obs.contact.contact_point
        # A target on the workspace's edge may land a little outside it (sensor noise, slip): the
        # same slack as for the surface gap below.
        lo = np.asarray(self.workspace.lower) - self.contact_gap_m
        hi = np.asarray(self.workspace.upper) + self.contact_gap_m
        if np.any(point[:2] < lo) or np.any(point[:2] > hi):
            raise FileFormatError(
                f"{where}: the contact point ({point[0]:.4g}, {point[1]:.4g}) m lies more than "
                f"{self.contact_gap_m} m outside the workspace "
                f"{self.workspace.lower}..{self.workspace.upper}")
        check_contact_gap(obs, self.contact_gap_m, where)


def check_contact_gap(obs: PressObservation, gap_m: float, where: str) -> None:
    """Refuse a press whose contact point lies farther than ``gap_m`` from every point of its
    cloud outside the robot's hull; ``where`` starts the message."""
    point = obs.contact.contact_point
    pts = obs.cloud.points
    try:
        surface = pts[~points_in_hull(pts, obs.robot_points)]
    except DeformapError as exc:
        raise FileFormatError(f"{where}: robot points: {exc}") from None
    gap = float(np.min(np.linalg.norm(surface - point, axis=1))) if len(surface) else np.inf
    if gap > gap_m:
        raise FileFormatError(
            f"{where}: the contact point {np.round(point, 4).tolist()} m is {gap:.3g} m from "
            f"the nearest surface point of the cloud (limit {gap_m} m); tip and "
            "cloud are probably in different frames or units")


def _session_file(path: Path) -> Path:
    kind = path_kind(path)
    if kind == "dir":
        file = path / SESSION_FILE
        if path_kind(file) != "file":
            raise FileFormatError(f"{path}: not a session folder (it has no {SESSION_FILE})")
        return file
    if kind == "file":
        return path
    raise FileFormatError(f"{path}: no such session folder or file")


def load_session(path: str | Path, *, contact_gap_m: float = DEFAULT_CONTACT_GAP_M,
                 stamp_tolerance_s: float | None = None) -> RecordedSession:
    """Open a recorded session (its folder or ``session.yaml``) and check ``session.yaml``.

    Pokes are read on demand (:meth:`RecordedSession.press_observation`), each refused when its
    contact point lies farther than ``contact_gap_m`` from every surface point. A bag-form poke
    takes on each topic the message stamped ``stamp_ns``, or with ``stamp_tolerance_s`` the one
    nearest it within that many seconds (the gap in :meth:`RecordedSession.poke_notes`); a
    tolerance reaching half-way to another poke's stamp, or given to a folder-form session, is
    refused. A ``session.yaml`` that is no valid YAML or has unknown, missing or bad keys is a
    ConfigError; a missing observation or bag, a missing topic or an unreadable ground truth a
    FileFormatError.
    """
    p = check_path("path", path)
    gap = check_positive("contact_gap_m", contact_gap_m)
    file = _session_file(p)
    header = parse_session_yaml(
        load_yaml(file, what="the session file", unreadable=FileFormatError), file)
    check_no_links(file.parent)
    if file.is_symlink():
        raise ConfigError(f"{file}: a symbolic link; name the session folder or its own file")
    check_seal(file, header.sha256)
    check_manifest_complete(file, header.sha256)
    tolerance = _stamp_tolerance(file, header, stamp_tolerance_s)
    reader = (FolderReader(header) if header.form == "folder"
              else BagReader(header, tolerance))  # fmt: skip
    truth = None
    if header.ground_truth is not None:
        if path_kind(header.ground_truth) == "file":
            verify_digest(header.sha256, header.ground_truth)
        truth = read_ground_truth(header.ground_truth)
    broken = [p.index for p in header.pokes if p.error is not None]
    if broken:
        logger.warning("%s: poke(s) %s have bad entries and will be refused", file, broken)
    return RecordedSession(path=file.parent, header=header, ground_truth=truth,
                           contact_gap_m=gap, _reader=reader)  # fmt: skip


def _stamp_tolerance(file: Path, header: SessionHeader, tolerance_s: float | None) -> int:
    """The stamp tolerance [ns] of a bag-form session: bounded by half the closest two pokes'
    stamps, so that no message can be taken for two pokes."""
    if tolerance_s is None:
        return 0
    tol = check_positive("stamp_tolerance_s", tolerance_s)
    if header.form != "bag":
        raise InvalidArgumentError(
            f"{file}: --stamp-tolerance applies to bags (stamped messages); this session is of "
            f"the {header.form} form")
    stamps = sorted(s.stamp_ns for s in header.pokes if s.stamp_ns is not None)
    gaps = np.diff(stamps)
    if gaps.size and tol * 1e9 >= gaps.min() / 2:
        k = int(np.argmin(gaps))
        raise InvalidArgumentError(
            f"{file}: --stamp-tolerance {tol:g} s reaches half-way from one poke's stamp to the "
            f"next ({stamps[k]} and {stamps[k + 1]} ns, {gaps[k] / 1e9:g} s apart): a message "
            "could be taken for two pokes; give less than half their distance")
    return round(tol * 1e9)


#: Files that are a ROS 2 bag on their own (MCAP, sqlite3).
RAW_SUFFIXES = (".mcap", ".db3", ".bag")


def is_raw_bag(path: str | Path) -> bool:
    """Whether ``path`` is a bag as a robot records it: a ``.mcap`` or ``.db3`` file (or a ROS 1
    ``.bag``, refused when opened), or a rosbag2 folder (with ``metadata.yaml``) without
    ``session.yaml``."""
    p = Path(path)
    kind = path_kind(p)
    if kind == "dir":
        return path_kind(p / "metadata.yaml") == "file" and path_kind(p / SESSION_FILE) != "file"
    return kind == "file" and p.suffix in RAW_SUFFIXES


def load_raw_bag(path: str | Path, config: RawBagConfig | None = None, *, default_force_n: float,
                 contact_gap_m: float = DEFAULT_CONTACT_GAP_M) -> RecordedSession:
    """Open a raw robot recording (a ``.mcap`` / ``.db3`` file or a rosbag2 folder) and find its
    presses: a session of form ``"raw"``, one poke per press.

    ``config`` names its topics, frames and thresholds (default ``RawBagConfig()``; see
    :func:`~deformap.replay.load_raw_config`); ``default_force_n`` is the commanded force when
    ``config.force_n`` is None; ``contact_gap_m`` as for :func:`~deformap.replay.load_session`.
    A bag missing or unreadable, lacking a topic or a press, or whose observation frames do not come
    before the first press, is a FileFormatError.
    """
    bag = check_path("path", path)
    cfg = check_instance("config", RawBagConfig() if config is None else config, RawBagConfig)
    if path_kind(bag) == "missing":
        raise FileFormatError(f"{bag}: no such bag")
    default_n = check_positive("default_force_n", default_force_n)
    force = default_n if cfg.force_n is None else cfg.force_n
    reader = RawBagReader(bag, cfg, force)
    specs = reader.poke_specs()
    workspace = reader.workspace([s.target_xy for s in specs if s.target_xy is not None])
    reader.found["force_n"] = {"value": force, "from": "given" if cfg.force_n is not None else
                               "the run configuration's exploration.force_n"}
    defaults = RawBagConfig()
    for key in ("units", "wrench_sign", "tip_radius_m", "hull", "stamp_tolerance_s",
                "hold_band", "hold_min_s", "observation_frames"):
        value = getattr(cfg, key)
        shown = (f"{len(value)} part(s): " + ", ".join(p.shape for p in value) if key == "hull"
                 else value)  # fmt: skip
        reader.found[key] = {"value": shown, "from": "assumed: the default (docs/robot.md)"
                             if value == getattr(defaults, key) else "given"}
    for key, value in reader.found.items():
        logger.info("%s: %s = %s (%s)", bag, key, value["value"], value["from"])
    header = SessionHeader(
        root=bag if bag.is_dir() else bag.parent, form="raw", units=cfg.units,
        frame=str(reader.config.world_frame), cam2world=None, workspace=workspace,
        tip_radius_m=cfg.tip_radius_m, observation=None, bag=bag, ground_truth=None,
        source={"raw": config_to_dict(cfg), "found": reader.found, "force_n": force,
                "n_presses": len(reader.presses)},
        pokes=specs)
    return RecordedSession(path=bag, header=header, ground_truth=None,
                           contact_gap_m=check_positive("contact_gap_m", contact_gap_m),
                           _reader=reader)
