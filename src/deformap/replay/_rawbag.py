"""A ROS 2 bag as a robot records it, read as a recorded session (``docs/robot.md``).

The bag holds an organised PointCloud2 stream in the camera's frame, a WrenchStamped stream in the
force sensor's frame, and ``/tf`` with ``/tf_static`` (:class:`~deformap.replay.RawBagConfig`).
A first pass decodes the wrenches, transforms and the clouds' stamps and finds the presses in the
force stream (:func:`find_presses`); a second averages, pixel by pixel, the frames each press was
held for and the observation's (colours too, when every frame has them), one frame in memory at a
time. A press that cannot be read is refused in one line naming it, the topic and the gap.
"""

from __future__ import annotations

import hashlib
import logging
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import LIMITS
from deformap.cloud import PointCloud
from deformap.cloud.io import (
    TransformTree,
    bag_error_text,
    bag_read_errors,
    header_stamp_ns,
    iter_bag_messages,
    typestore,
)
from deformap.environment import Workspace
from deformap.errors import DeformapError, FileFormatError
from deformap.replay._format import PokeSpec, PressParts
from deformap.replay._rawcheck import CameraCheck
from deformap.replay._rawconfig import WORKSPACE_MARGIN_RADII, RawBagConfig, hull_points
from deformap.replay._rawfind import CLOUD_TYPE, TF_TYPE, WRENCH_TYPE
from deformap.replay._rawframes import FrameGroup, average_frames, group_points
from deformap.replay._rawpress import (
    FoundPress,
    block_size,
    find_presses,
    onset,
    press_record,
)

__all__ = ["RawBagReader"]

logger = logging.getLogger(__name__)


#: A frame is averaged only while the camera holds within these [m, rad] of its pose at the
#: middle frame: 1 mrad moves a point 1 m away by 1 mm, below a depth camera's noise.
STILL_M, STILL_RAD = 5e-4, 1e-3

#: The largest force component [N] a wrench may hold, beyond any force–torque sensor's range: a
#: larger or non-finite one is a damaged message, refused before it is squared.
MAX_FORCE_N = 1e6

class RawBagReader(CameraCheck):
    """Reads a raw recording: finds its presses, averages their frames, builds each press."""

    def __init__(self, bag: Path, config: RawBagConfig, commanded_n: float) -> None:
        self.path, self.commanded_n = bag, commanded_n
        #: every value found in the bag or assumed, ``{key: {"value": v, "from": why}}``
        self.found: dict[str, dict[str, Any]] = {}
        #: per press (0-based): what the report says of it beyond its β (``force_travel``, ...)
        self.notes: dict[int, dict[str, str]] = {}
        self.config = config = self._topics(config)
        self.tree = TransformTree(config.tf_topic, round(config.stamp_tolerance_s * 1e9))
        self._index()
        self.origin_ns = self.tree.origin_ns = int(min(self.cloud_ns.min(), self.wrench_ns[0]))
        self.config = cfg = self._frames(self.config)
        magnitude = np.linalg.norm(self.wrench_force, axis=1)
        contact_n = self._threshold(cfg)
        self.presses = find_presses(
            self.wrench_ns, magnitude, commanded_n=commanded_n,
            contact_n=contact_n, band=cfg.hold_band,
            hold_min_ns=round(cfg.hold_min_s * 1e9),
            merge_ns=round(cfg.stamp_tolerance_s * 1e9), topic=self.wrench_topic,
            origin_ns=self.origin_ns)
        source = self.found["contact_force_n"]["from"]
        if self.presses and self.presses[0].start == 0:
            raise FileFormatError(
                f"{bag}: topic {self.wrench_topic!r} reads {magnitude[0]:.4g} N from its first "
                f"sample, over the contact threshold {contact_n:.4g} N ({source}): a sensor "
                "not zeroed with the probe free, or a recording started during a press")
        if not self.presses:
            raise FileFormatError(
                f"{bag}: no press on {self.wrench_topic!r}: the force must stay above "
                f"{contact_n:.4g} N ({source}) for {cfg.hold_min_s:g} s at least once; its "
                f"largest is {float(magnitude.max()):.4g} N")
        most = LIMITS["pokes"]["le"]
        if len(self.presses) > most:
            raise FileFormatError(
                f"{bag}: {len(self.presses):,} presses found on {self.wrench_topic!r}, more than the "
                f"{most:,} pokes one map is made of; split the recording")
        self._check_merge(magnitude, contact_n)
        self.config = cfg = self._tip(cfg)
        self.tip_still = self._tip_still()
        self._groups: dict[int, FrameGroup] = {}
        self._errors: dict[int, str] = {}
        self._observation_group = self._plan_observation()
        for press in self.presses:
            if press.error is None:
                self._plan_press(press)
        self._average()
        self._observation: PointCloud | None = None

    def _check_merge(self, magnitude: NDArray[np.float64], contact_n: float) -> None:
        """Refuse a ``stamp_tolerance_s`` that joins presses: one that holds the commanded force
        twice, over the threshold apart, is two presses."""
        cfg = self.config
        apart = find_presses(self.wrench_ns, magnitude, commanded_n=self.commanded_n,
                             contact_n=contact_n, band=cfg.hold_band,
                             hold_min_ns=round(cfg.hold_min_s * 1e9), merge_ns=0,
                             topic=self.wrench_topic, origin_ns=self.origin_ns)  # fmt: skip
        held = [p for p in apart if p.hold_start >= 0]
        for a, b in pairwise(held):
            gap = (self.wrench_ns[b.start] - self.wrench_ns[a.end - 1]) / 1e9
            if gap < cfg.stamp_tolerance_s:
                raise FileFormatError(
                    f"{self.path}: --stamp-tolerance {cfg.stamp_tolerance_s:g} s "
                    f"(`stamp_tolerance_s`) would join the presses at t = "
                    f"{self._s(self.wrench_ns[a.start])} and {self._s(self.wrench_ns[b.start])} s, "
                    f"{gap:.3f} s apart; it must stay below the time between two presses")

    def _index(self) -> None:
        cfg, store, errors = self.config, typestore(), bag_read_errors()
        topics = {self.cloud_topic: CLOUD_TYPE, self.wrench_topic: WRENCH_TYPE, cfg.tf_topic: TF_TYPE}
        optional = {cfg.tf_static_topic: TF_TYPE}
        stamps: list[int] = []
        frames: set[str] = set()
        w_ns: list[int] = []
        w_force: list[list[float]] = []
        w_frames: set[str] = set()
        types = {**topics, **optional}
        seen: dict[tuple[str, int, bytes], int] = {}  # (topic, stamp, digest) -> message number
        for raw in iter_bag_messages(self.path, topics, optional=optional):
            where = f"{self.path} [{raw.topic} message {raw.number}]"
            try:
                msg = store.deserialize_cdr(bytes(raw.data), types[raw.topic])
            except errors as exc:
                raise FileFormatError(f"{where}: could not be decoded: "
                                      f"{bag_error_text(exc, 120)}") from None  # fmt: skip
            if raw.topic in (self.cloud_topic, self.wrench_topic):
                key = (raw.topic, header_stamp_ns(msg.header),
                       hashlib.blake2b(bytes(raw.data), digest_size=16).digest())
                first = seen.setdefault(key, raw.number)
                if first != raw.number:  # it would count twice in a press's average
                    raise FileFormatError(
                        f"{where}: repeats message {first} byte for byte (same header stamp); "
                        "the bag holds messages written twice")
            if raw.topic == self.cloud_topic:
                stamps.append(header_stamp_ns(msg.header))
                frames.add(str(msg.header.frame_id))
            elif raw.topic == self.wrench_topic:
                f = msg.wrench.force
                w_ns.append(header_stamp_ns(msg.header))
                w_force.append([float(f.x), float(f.y), float(f.z)])
                w_frames.add(str(msg.header.frame_id))
            else:
                self.tree.add(msg, static=raw.topic == cfg.tf_static_topic and
                              raw.topic != cfg.tf_topic, where=where)  # fmt: skip
        for topic, got in ((self.cloud_topic, stamps), (self.wrench_topic, w_ns)):
            if not got:
                raise FileFormatError(f"{self.path}: topic {topic!r} has no messages")
            if len(got) > 1 and not any(got):
                raise FileFormatError(
                    f"{self.path}: topic {topic!r}: every header stamp of its {len(got)} messages "
                    "is zero; its driver did not stamp them, and deformap pairs the camera, the "
                    "force and /tf by their header stamps")
        self.camera_frame = cfg.camera_frame or self._one_frame(frames, self.cloud_topic)
        self.force_frame = cfg.force_frame or self._one_frame(w_frames, self.wrench_topic)
        order = np.argsort(np.asarray(w_ns, dtype=np.int64), kind="stable")
        self.wrench_ns = np.asarray(w_ns, dtype=np.int64)[order]
        self.wrench_force = np.asarray(w_force, dtype=np.float64)[order]
        bad = ~(np.abs(self.wrench_force) <= MAX_FORCE_N).all(axis=1)  # NaN fails too
        if bad.any():
            first = int(order[np.flatnonzero(bad)[0]])
            raise FileFormatError(
                f"{self.path} [{self.wrench_topic} message {first + 1}]: force "
                f"{w_force[first]} N: expected finite components within ±{MAX_FORCE_N:g} N "
                "(no force sensor reads more: a damaged message)")
        self.cloud_ns = np.asarray(stamps, dtype=np.int64)

    def _s(self, stamp_ns: Any) -> str:
        """A stamp as seconds after the bag's start (its first camera or force message)."""
        return f"{(int(stamp_ns) - self.origin_ns) / 1e9:.3f}"

    def _one_frame(self, frames: set[str], topic: str) -> str:
        if len(frames) != 1:
            raise FileFormatError(f"{self.path}: topic {topic!r} must use one frame_id; got "
                                  f"{sorted(frames)}")  # fmt: skip
        return frames.pop()

    # -- which frames -----------------------------------------------------------------------

    def _plan_observation(self) -> FrameGroup:
        cfg, first_contact = self.config, int(self.wrench_ns[self.presses[0].start])
        order = np.argsort(self.cloud_ns, kind="stable")
        times = self.cloud_ns[order]
        pick = 0
        if cfg.observation_time_s is not None:
            wanted = self.origin_ns + round(cfg.observation_time_s * 1e9)
            pick = int(np.argmin(np.abs(times - wanted)))
        chosen = [int(i) for i in order[pick: pick + cfg.observation_frames]]
        last = int(self.cloud_ns[chosen[-1]])
        if last >= first_contact or len(chosen) < cfg.observation_frames:
            raise FileFormatError(
                f"{self.path}: the observation's {cfg.observation_frames} frame(s) on "
                f"{self.cloud_topic!r} from t = {self._s(times[pick])} s must all come before the "
                f"first contact at t = {self._s(first_contact)} s (`observation_time_s`, "
                "`observation_frames`)")
        return self._still(chosen, f"{self.path}: the observation")

    def _plan_press(self, press: FoundPress) -> None:
        cfg = self.config
        t0, t1 = int(self.wrench_ns[press.hold_start]), int(self.wrench_ns[press.hold_end - 1])
        inside = np.flatnonzero((self.cloud_ns >= t0) & (self.cloud_ns <= t1))
        where = f"press {press.index + 1} (hold t = {self._s(t0)}–{self._s(t1)} s)"
        if inside.size == 0:
            gap = np.maximum(t0 - self.cloud_ns, self.cloud_ns - t1)
            nearest = int(np.argmin(gap))
            if gap[nearest] > round(cfg.stamp_tolerance_s * 1e9):
                self._errors[press.index] = (
                    f"{where}: topic {self.cloud_topic!r} has no frame within "
                    f"{cfg.stamp_tolerance_s:g} s of the hold (nearest {gap[nearest] / 1e9:.3f} s "
                    "away)")
                return
            inside = np.array([nearest])
        try:
            self._groups[press.index] = self._still([int(i) for i in inside], where)
        except DeformapError as exc:
            self._errors[press.index] = str(exc)

    def _still(self, frames: list[int], where: str) -> FrameGroup:
        """The frames whose camera pose lies within ``STILL_M``, ``STILL_RAD`` of the middle one's."""
        stamps = self.cloud_ns[frames]
        rot, trans = self.tree.lookup(self.world_frame, self.camera_frame, stamps,
                                      what=f"{where} [{self.cloud_topic}]")  # fmt: skip
        mid = len(frames) // 2
        angle = np.arccos(np.clip((np.einsum("nij,ij->n", rot, rot[mid]) - 1) / 2, -1.0, 1.0))
        still = (np.linalg.norm(trans - trans[mid], axis=1) <= STILL_M) & (angle <= STILL_RAD)
        kept = [f for f, s in zip(frames, still, strict=True) if s]
        return FrameGroup(frames=kept, cam_stamp=int(stamps[mid]))

    # -- second pass: the average of each group ----------------------------------------------

    def _average(self) -> None:
        average_frames(self.path, self.cloud_topic, [self._observation_group, *self._groups.values()],
                       1e-3 if self.config.units == "mm" else 1.0)

    def _cloud(self, group: FrameGroup, where: str) -> PointCloud:
        cam, rgb = group_points(group, self.cloud_topic, where)
        rot, trans = self.tree.lookup(self.world_frame, self.camera_frame, group.cam_stamp,
                                      what=f"{where} [{self.cloud_topic}]")  # fmt: skip
        return PointCloud(cam @ rot[0].T + trans[0], rgb)

    # -- what the session asks for -----------------------------------------------------------

    def observation(self) -> PointCloud:
        if self._observation is None:
            self._observation = self._cloud(self._observation_group, f"{self.path}: the observation")
        return self._observation

    def workspace(self, targets: list[NDArray[np.float64]]) -> Workspace:
        """The given rectangle, or the ``targets``' surroundings within the observation's extent."""
        cfg = self.config
        if cfg.workspace_lower is not None and cfg.workspace_upper is not None:
            self._note("workspace", [list(cfg.workspace_lower), list(cfg.workspace_upper)], "given")
            return Workspace(lower=cfg.workspace_lower, upper=cfg.workspace_upper)
        pts = self.observation().points
        lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
        why = "the observation's x–y extent (no press usable)"
        if targets:
            margin = WORKSPACE_MARGIN_RADII * cfg.tip_radius_m
            xy = np.array(targets)
            lo = np.maximum(lo, xy.min(axis=0) - margin)
            hi = np.minimum(hi, xy.max(axis=0) + margin)
            why = (f"assumed: the presses' bounding box grown by {WORKSPACE_MARGIN_RADII:g} tip "
                   f"radii ({margin:g} m), within the observation's extent; set "
                   "`workspace_lower`, `workspace_upper` to map more")
        ws = Workspace(lower=(float(lo[0]), float(lo[1])), upper=(float(hi[0]), float(hi[1])))
        self._note("workspace", [[round(v, 4) for v in ws.lower], [round(v, 4) for v in ws.upper]],
                   why)
        return ws

    def poke_specs(self) -> tuple[PokeSpec, ...]:
        """One entry per press found; a press that cannot be used carries its error."""
        specs = []
        for press in self.presses:
            error = press.error or self._errors.get(press.index)
            stamp, target = None, None
            if error is None:
                # the command is not recorded: the target is where the tip held
                stamp = int(self.wrench_ns[(press.hold_start + press.hold_end) // 2])
                try:
                    _, tip = self.tree.lookup(
                        self.world_frame, self.tip_frame, stamp,
                        what=f"press {press.index + 1} [{self.config.tf_topic}, the tip]")
                    target = tip[0, :2]
                except DeformapError as exc:
                    error = str(exc)
            specs.append(PokeSpec(index=press.index, stamp_ns=stamp, force_n=self.commanded_n,
                                  target_xy=target,
                                  error=None if error is None else FileFormatError(
                                      f"{self.path}: {error}")))  # fmt: skip
        return tuple(specs)

    def press_parts(self, spec: PokeSpec) -> PressParts:
        press, cfg = self.presses[spec.index], self.config
        where = (f"{self.path}: press {press.index + 1} (hold t = "
                 f"{self._s(self.wrench_ns[press.hold_start])}–"
                 f"{self._s(self.wrench_ns[press.hold_end - 1])} s)")
        # first contact: the foot of the ramp under the threshold, found on block means
        k = block_size(press.hold_start - press.start, self.noise.rms_n, self.commanded_n)
        first = onset(self.wrench_force, press.start,
                      self.presses[press.index - 1].end if press.index else 0, self.noise, k)
        span = slice(first, press.hold_end)
        stamps = self.wrench_ns[span]
        r_force, _ = self.tree.lookup(self.world_frame, self.force_frame, stamps,
                                      what=f"{where} [{self.wrench_topic}]")  # fmt: skip
        sign = -1.0 if cfg.wrench_sign == "reaction" else 1.0
        forces = sign * np.einsum("nij,nj->ni", r_force, self.wrench_force[span])
        r_tip, tips = self.tree.lookup(self.world_frame, self.tip_frame, stamps,
                                       what=f"{where} [{cfg.tf_topic}, the tip]")  # fmt: skip
        hold = slice(press.hold_start - first, press.hold_end - first)
        mid = (hold.start + hold.stop) // 2
        direction = -r_tip[mid][:, 2]  # the press goes along the tip frame's -z
        if direction[2] >= 0.0:  # the press must go down, into the table's surface
            raise FileFormatError(
                f"{where}: the tip frame {self.tip_frame!r}'s −z points "
                f"{np.round(direction, 3).tolist()} in {self.world_frame!r}, not down into the "
                f"surface; `tip_frame` must have z along the stick, away from the surface "
                f"(docs/robot.md)")
        force = forces[hold].mean(axis=0)
        if float(force @ direction) <= 0.0:
            raise FileFormatError(
                f"{where}: the force on the surface, {np.round(force, 3).tolist()} N in the world "
                f"frame, points away from it (against the press direction "
                f"{np.round(direction, 3).tolist()}); the sensor's sign is the other one "
                f"(`wrench_sign` is {cfg.wrench_sign!r})")
        normal = forces @ direction
        # the record runs from first contact to the first sample that reaches the force held
        # (the hold's mean, the commanded force within the controller's error and the noise)
        reached = np.flatnonzero(normal[: hold.stop] >= float(normal[hold].mean()))
        ramp = slice(0, int(reached[0]) + 1 if reached.size else hold.start + 1)
        travel = (tips[ramp] - tips[0]) @ direction
        if spec.index not in self._groups:
            raise FileFormatError(f"{where}: {self._errors.get(spec.index, 'no frame')}")
        cloud = self._cloud(self._groups[spec.index], where)
        # the tip where it settled: the hold's last third (after a force step the tip still
        # sinks early in the hold; after a ramp it is still throughout)
        settled = max(1, (hold.stop - hold.start) // 3)
        tip = tips[hold.stop - settled: hold.stop].mean(axis=0)
        robot = tuple(hull_points(p, r_tip[mid], tip) for p in cfg.hull)  # a hull per part
        notes = self.notes.setdefault(spec.index, {})
        # the sensor's noise along the press: its per-axis σ seen along the direction
        along = r_force[mid].T @ direction
        noise = float(np.sqrt(np.sum((along * self.noise.std) ** 2)))
        seconds, held = (stamps - stamps[0]) / 1e9, slice(ramp.stop, hold.stop)
        record = press_record(travel, normal[ramp], seconds[ramp], noise, notes,
                              (seconds[held], (tips[held] - tips[0]) @ direction, normal[held]))
        record = self.against_camera(notes, record, travel, cloud,
                                     tip + cfg.tip_radius_m * direction, robot)
        if "disagreement" in notes:  # a warning in the report (map_session), said once
            logger.info("%s: %s", where, notes["disagreement"])
        return PressParts(cloud, tip, force, robot, record)
