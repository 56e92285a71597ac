"""Writing a session (folder or bag form), as ``deformap record-sim`` does, from what a
:class:`RecordingEnvironment` kept of an environment's answers."""

from __future__ import annotations

import logging
import os
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from deformap._files import LOCK_NAME, write_text_atomically, writing
from deformap._validation import check_instance, check_path, check_positive
from deformap.cloud import PointCloud
from deformap.cloud.io import BAG_STORAGES, CLOUD_FORMATS, write_cloud
from deformap.environment import Environment, ForceTravel, PressObservation, Workspace
from deformap.errors import EnvironmentStateError, InvalidArgumentError
from deformap.replay._bagform import write_session_bag
from deformap.replay._confine import manifest_of, seal
from deformap.replay._format import FORMAT_NAME, FORMAT_VERSION, SESSION_FILE
from deformap.replay._truth import GroundTruth, write_ground_truth

__all__ = ["SESSION_FORMATS", "RecordingEnvironment", "write_session"]

logger = logging.getLogger(__name__)

#: ``"folder"``: one cloud file per observation; ``"mcap"`` / ``"sqlite3"``: a ROS 2 bag.
SESSION_FORMATS = ("folder", *BAG_STORAGES)

#: Poke ``i`` (0-based) of a bag written here is stamped ``(i + 1)`` seconds; the observation 0.
_STAMP_STEP_NS = 10**9


class RecordingEnvironment:
    """Pass every call through to ``env`` and keep each ``observe()`` and ``press()`` result,
    ready for :func:`~deformap.replay.write_session`."""

    def __init__(self, env: Environment) -> None:
        if not isinstance(env, Environment):
            raise InvalidArgumentError(
                f"`env` must implement the Environment protocol; got {type(env).__name__}")
        self._env = env
        self.observations: list[PointCloud] = []
        self.presses: list[PressObservation] = []

    @property
    def workspace(self) -> Workspace:
        return self._env.workspace

    @property
    def observation(self) -> PointCloud:
        """The first observation (the one the mapper is initialised with)."""
        if not self.observations:
            raise EnvironmentStateError("nothing recorded yet: `observe()` was never called")
        return self.observations[0]

    def observe(self) -> PointCloud:
        cloud = self._env.observe()
        self.observations.append(cloud)
        return cloud

    def press(self, target_xy: Any, force_n: float) -> PressObservation:
        obs = self._env.press(target_xy, force_n)
        self.presses.append(obs)
        return obs

    def release(self) -> None:
        self._env.release()


class _Dumper(yaml.SafeDumper):
    """Vectors (lists of numbers) on one line; everything else in block style; a value met twice
    written in full (the reader refuses aliases)."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


def _represent_list(dumper: yaml.SafeDumper, data: list[Any]) -> Any:
    flow = all(isinstance(v, (int, float)) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _represent_list)


def _floats(values: Any) -> list[float]:
    # Python floats: PyYAML writes their repr, which reads back bit for bit.
    return [float(v) for v in np.asarray(values, dtype=float).ravel()]


def _check_inputs(folder: Any, workspace: Any, observation: Any, presses: Any, tip_radius_m: Any,
                  format: Any, cloud_format: Any,
                  ground_truth: Any) -> tuple[Path, list[PressObservation], float]:
    out = check_path("folder", folder)
    if out.exists() and (not out.is_dir() or any(p.name != LOCK_NAME for p in out.iterdir())):
        raise InvalidArgumentError(f"`folder` {out} exists and is not an empty folder")
    check_instance("workspace", workspace, Workspace)
    if not isinstance(observation, PointCloud) or len(observation) == 0:
        raise InvalidArgumentError("`observation` must be a non-empty PointCloud")
    if observation.frame != "world":
        raise InvalidArgumentError(
            f"`observation` must be in frame 'world'; got {observation.frame!r}")
    presses = list(presses)
    for i, obs in enumerate(presses):
        check_instance(f"presses[{i}]", obs, PressObservation)
        if obs.cloud.frame != "world":
            raise InvalidArgumentError(f"`presses[{i}].cloud` must be in frame 'world'")
    radii = {obs.contact.tip_radius_m for obs in presses}
    if tip_radius_m is None:
        if len(radii) != 1:
            raise InvalidArgumentError(
                "`tip_radius_m` is needed: the presses do not give exactly one tip radius "
                f"(got {sorted(radii)})")
        tip_radius_m = radii.pop()
    tip = check_positive("tip_radius_m", tip_radius_m)
    if radii - {tip}:
        raise InvalidArgumentError(
            f"every press must use `tip_radius_m` {tip}; got {sorted(radii)}")
    if format not in SESSION_FORMATS:
        raise InvalidArgumentError(f"`format` must be one of {SESSION_FORMATS}; got {format!r}")
    if cloud_format not in CLOUD_FORMATS:
        raise InvalidArgumentError(
            f"`cloud_format` must be one of {CLOUD_FORMATS}; got {cloud_format!r}")
    if ground_truth is not None:
        check_instance("ground_truth", ground_truth, GroundTruth)
    return out, presses, tip


def record_entry(record: ForceTravel) -> dict[str, Any]:
    """A force–travel record as ``session.yaml``'s ``force_travel`` entry (parts it lacks left out)."""
    entry: dict[str, Any] = {"travel_m": _floats(record.travel_m),
                             "force_n": _floats(record.force_n)}
    if record.time_s is not None:
        entry["time_s"] = _floats(record.time_s)
    for name in ("hold", "unloading"):
        phase = getattr(record, name)
        if phase is not None:
            entry[name] = {k: _floats(getattr(phase, k)) for k in ("time_s", "travel_m", "force_n")}
    return entry


def write_session(folder: str | Path, *, workspace: Workspace, observation: PointCloud,
                  presses: Sequence[PressObservation], tip_radius_m: float | None = None,
                  ground_truth: GroundTruth | None = None, source: dict[str, Any] | None = None,
                  format: str = "folder", cloud_format: str = "pcd") -> Path:
    """Write a session that :func:`load_session` reads back exactly; returns its ``session.yaml``.

    ``folder`` is new or empty (but for a lock file, :data:`deformap._files.LOCK_NAME`, of the
    process writing it). The ``observation`` and the ``presses`` (world frame, in order) are
    written as float64 and read back bit for bit, colours exactly in NPZ and to 8 bits a channel in
    PCD, PLY and bags; a press with one hull per part keeps its parts' common hull (with a warning).
    ``tip_radius_m`` defaults to the presses' (which must agree); ``source`` is plain provenance data.
    ``format`` ``"folder"`` writes cloud files of ``cloud_format``, ``"mcap"`` or ``"sqlite3"`` a ROS 2
    bag in ``bag/``. ``session.yaml`` comes last, with ``n_pokes``, every file's ``sha256`` and its
    seal (:func:`~deformap.replay._confine.seal`). Every file is written atomically: a failed write
    is one :class:`~deformap.errors.FileWriteError` naming the file, and leaves no file cut short
    under its name (a bag is written in a folder beside and renamed into place).
    """
    out, presses, tip = _check_inputs(folder, workspace, observation, presses, tip_radius_m,
                                      format, cloud_format, ground_truth)  # fmt: skip
    with writing(out):
        out.mkdir(parents=True, exist_ok=True)
    doc: dict[str, Any] = {
        "format": FORMAT_NAME, "version": FORMAT_VERSION, "units": "m", "frame": "world",
        "workspace": {"lower": list(workspace.lower), "upper": list(workspace.upper)},
        "probe": {"tip_radius_m": tip}}  # fmt: skip
    if source:
        doc["source"] = dict(source)
    if ground_truth is not None:
        write_ground_truth(out / "ground_truth.npz", ground_truth)
        doc["ground_truth"] = "ground_truth.npz"
    parted = [i for i, obs in enumerate(presses) if len(obs.robot_hulls) > 1]
    if parted:
        logger.warning("presses %s give one robot hull per part; the session keeps one hull per "
                       "poke, their common hull (docs/recording-format.md)", parted)
    if format == "folder":
        doc["observation"] = f"observation.{cloud_format}"
        write_cloud(out / doc["observation"], observation)
        pokes = []
        for i, obs in enumerate(presses, start=1):
            cloud, robot = f"poke-{i:02d}.{cloud_format}", f"poke-{i:02d}-robot.{cloud_format}"
            write_cloud(out / cloud, obs.cloud)
            write_cloud(out / robot, PointCloud(np.vstack(obs.robot_hulls)))
            entry: dict[str, Any] = {
                "cloud": cloud, "tip_center": _floats(obs.contact.tip_center),
                "force": _floats(obs.contact.force), "target_xy": _floats(obs.target_xy),
                "force_n": float(obs.force_n), "robot_points": robot}  # fmt: skip
            if obs.force_travel is not None:
                entry["force_travel"] = record_entry(obs.force_travel)
            if obs.released is not None:
                entry["released"] = f"poke-{i:02d}-released.{cloud_format}"
                write_cloud(out / entry["released"], obs.released)
            pokes.append(entry)
    else:
        stamps = [(i + 1) * _STAMP_STEP_NS for i in range(len(presses))]
        # written beside, then renamed into place: a failed write leaves no bag cut short
        staging = out / f".bag-{os.getpid()}.partial"
        with writing(out / "bag"):
            try:
                write_session_bag(staging / "bag", storage=format, observation=observation,
                                  presses=presses, stamps_ns=stamps)  # fmt: skip
                os.replace(staging / "bag", out / "bag")
            finally:
                shutil.rmtree(staging, ignore_errors=True)
        doc["bag"] = "bag"
        pokes = [
            {"stamp_ns": s, "target_xy": _floats(o.target_xy), "force_n": float(o.force_n)}
            for s, o in zip(stamps, presses, strict=True)]
    # The count and the manifest come before the pokes: a file cut in its poke list keeps them.
    doc["n_pokes"] = len(pokes)
    doc["sha256"] = manifest_of(out, (p for p in out.rglob("*")
                                      if p.is_file() and p.name != LOCK_NAME))
    doc["pokes"] = pokes
    file = out / SESSION_FILE
    write_text_atomically(file, seal(yaml.dump(doc, Dumper=_Dumper, sort_keys=False)))
    return file
