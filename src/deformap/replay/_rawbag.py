"""A ROS 2 bag as a robot records it, read as a recorded session (``docs/robot.md``).

The bag holds an organised PointCloud2 stream in the camera's frame, a WrenchStamped stream in the
force sensor's frame, and ``/tf`` with ``/tf_static`` (:class:`~deformap.replay.RawBagConfig`).
A first pass decodes the wrenches, transforms and the clouds' stamps and finds the presses in the
force stream (:func:`find_presses`); a second averages, pixel by pixel, the frames each press was
held for and the observation's (colours too, when every frame has them), one frame in memory at a
time. A press that cannot be read is refused in one line naming it, the topic and the gap.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud, points_in_hull
from deformap.cloud.io import (
    TransformTree,
    bag_error_text,
    bag_read_errors,
    bag_topics,
    header_stamp_ns,
    iter_bag_messages,
    pointcloud2_colors,
    pointcloud2_structured,
    typestore,
    xyz_with_holes,
)
from deformap.environment import TRAVEL_BACKWARDS_TOLERANCE_M, ForceTravel, Workspace
from deformap.errors import DeformapError, FileFormatError
from deformap.replay._format import PokeSpec, PressParts
from deformap.replay._rawconfig import WORKSPACE_MARGIN_RADII, HullPart, RawBagConfig
from deformap.replay._rawpress import (
    CONTACT_NOISE_MULTIPLE,
    FoundPress,
    block_means,
    block_size,
    contact_threshold,
    find_presses,
    noise_floor,
    onset,
)

__all__ = ["DENT_SIGMAS", "RawBagReader", "hull_points"]

logger = logging.getLogger(__name__)

_CLOUD = "sensor_msgs/msg/PointCloud2"
_WRENCH = "geometry_msgs/msg/WrenchStamped"
_TF = "tf2_msgs/msg/TFMessage"

#: A frame is averaged only while the camera holds within these [m, rad] of its pose at the
#: middle frame: 1 mrad moves a point 1 m away by 1 mm, below a depth camera's noise.
STILL_M, STILL_RAD = 5e-4, 1e-3

#: The largest force component [N] a wrench may hold, beyond any force–torque sensor's range: a
#: larger or non-finite one is a damaged message, refused before it is squared.
MAX_FORCE_N = 1e6

#: A dent the camera sees lies this many of its σ below the observation (a 1e-4 chance of noise).
DENT_SIGMAS = 4.0

#: A Hertz dent of travel δ sinks the surface within two tip radii of the contact by about an
#: eighth of δ or more on average (the visible part, outside the contact radius √(Rδ)).
HERTZ_DISC_FRACTION = 0.125

#: Points of a hull part's circle (cylinder, cap): 16 give a polygon within 2 % of the circle.
_CIRCLE = 16


def hull_points(part: HullPart, rot: NDArray[np.float64], origin: NDArray[np.float64]
                ) -> NDArray[np.float64]:  # fmt: skip
    """``(m, 3)`` world points whose convex hull is ``part`` at the tip pose ``rot``, ``origin``."""
    c, (sx, sy, sz) = np.asarray(part.center_m), part.size_m
    if part.shape == "box":
        local = np.array([[x * sx, y * sy, z * sz] for x in (-0.5, 0.5) for y in (-0.5, 0.5)
                          for z in (-0.5, 0.5)])  # fmt: skip
    else:
        az = np.linspace(0.0, 2 * np.pi, _CIRCLE, endpoint=False)
        ring = np.column_stack([np.cos(az), np.sin(az), np.zeros_like(az)]) * (sx / 2)
        if part.shape == "cylinder":
            half = np.array([0.0, 0.0, sz / 2])
            local = np.vstack([ring - half, ring + half])
        else:  # cap: the upper half-sphere, as rings at 0°, 30°, 60° and the pole
            r = sx / 2
            local = np.vstack([ring * np.cos(a) + [0, 0, r * np.sin(a)]
                               for a in (0.0, np.pi / 6, np.pi / 3)] + [[[0, 0, r]]])
    return np.asarray((local + c) @ rot.T + origin)


def _resolved(name: str | None) -> str:
    """A topic or frame name, found or given, once the bag is open."""
    assert name is not None, "resolved when the bag is opened"
    return name


@dataclass
class _Group:
    """Frames averaged into one cloud, with the per-pixel sums (``rgb`` None once a frame lacks
    colours) and counts."""

    frames: list[int]
    cam_stamp: int
    shape: tuple[int, int] | None = None
    total: NDArray[np.float64] | None = None
    count: NDArray[np.int64] | None = None
    rgb: NDArray[np.float64] | None = None


class RawBagReader:
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
        self._check_merge(magnitude, contact_n)
        self.config = cfg = self._tip(cfg)
        self._groups: dict[int, _Group] = {}
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

    # -- what the bag holds, found once when it is opened ---------------------------------

    @property
    def cloud_topic(self) -> str:
        return _resolved(self.config.cloud_topic)

    @property
    def wrench_topic(self) -> str:
        return _resolved(self.config.wrench_topic)

    @property
    def world_frame(self) -> str:
        return _resolved(self.config.world_frame)

    @property
    def tip_frame(self) -> str:
        return _resolved(self.config.tip_frame)

    def _note(self, key: str, value: Any, why: str) -> None:
        self.found[key] = {"value": value, "from": why}

    def _topics(self, cfg: RawBagConfig) -> RawBagConfig:
        """Each role's topic, given (its type checked) or found (the one topic of its type)."""
        topics = bag_topics(self.path)
        listing = ", ".join(f"{t} ({kind}, {n})" for t, (kind, n) in sorted(topics.items()))
        chosen: dict[str, str] = {}
        roles = (("cloud_topic", _CLOUD, "the camera's cloud", "--cloud-topic"),
                 ("wrench_topic", _WRENCH, "the force sensor", "--wrench-topic"),
                 ("tf_topic", _TF, "the transforms", "`tf_topic`"),
                 ("tf_static_topic", _TF, "the static transforms", "`tf_static_topic`"))
        for key, msgtype, role, option in roles:
            given = getattr(cfg, key)
            if given is None:
                of_type = sorted(t for t, (kind, _) in topics.items() if kind == msgtype)
                if len(of_type) != 1:
                    raise FileFormatError(
                        f"{self.path}: {len(of_type)} topics carry {msgtype} ({role}); name one "
                        f"with {option}. The bag holds: {listing or 'no topic'}")
                chosen[key] = of_type[0]
                self._note(key, of_type[0], f"found: the bag's one {msgtype} topic")
                continue
            if given not in topics:
                if key == "tf_static_topic":  # optional: a rig may publish every link on /tf
                    chosen[key] = given
                    continue
                raise FileFormatError(
                    f"{self.path}: bag has no topic {given!r} ({role}, {option}). The bag holds: "
                    f"{listing or 'no topic'}")
            if topics[given][0] != msgtype:
                raise FileFormatError(
                    f"{self.path}: topic {given!r} ({option}, {role}) carries "
                    f"{topics[given][0]}; expected {msgtype}")
            chosen[key] = given
            if key in ("cloud_topic", "wrench_topic"):
                self._note(key, given, "given")
        used = [chosen["cloud_topic"], chosen["wrench_topic"], chosen["tf_topic"]]
        if len(set(used)) != 3:
            raise FileFormatError(f"{self.path}: the camera, force and /tf topics must differ; "
                                  f"got {used}")  # fmt: skip
        return replace(cfg, cloud_topic=chosen["cloud_topic"],
                       wrench_topic=chosen["wrench_topic"], tf_topic=chosen["tf_topic"],
                       tf_static_topic=chosen["tf_static_topic"])

    def _frames(self, cfg: RawBagConfig) -> RawBagConfig:
        """The world frame (given, ``world``, or the camera's root) and the camera's and the
        sensor's frames, each checked to reach the world frame: one refusal naming what is
        missing and listing the frames there are."""
        frames = self.tree.frames
        if cfg.world_frame is not None:
            world, why = cfg.world_frame, "given"
        elif "world" in frames:
            world, why = "world", "assumed: the frame named 'world' (z up, the table at z = 0)"
        elif self.camera_frame in frames:
            world = self.tree.root(self.camera_frame)
            why = (f"assumed: the root of the camera's frame {self.camera_frame!r} (z up, the "
                   "table at z = 0)")
        else:
            world, why = "world", "default"
        self._note("world_frame", world, why)
        self._note("camera_frame", self.camera_frame,
                   "given" if cfg.camera_frame else "found: the cloud's header.frame_id")
        self._note("force_frame", self.force_frame,
                   "given" if cfg.force_frame else "found: the wrench's header.frame_id")
        absent, apart = [], []
        for what, frame, option in (("world", world, "--world-frame"),
                                    ("camera", self.camera_frame, "`camera_frame`"),
                                    ("force sensor", self.force_frame, "--force-frame")):
            if frame not in frames:
                absent.append(f"the {what} frame {frame!r} ({option})")
            elif world in frames and self.tree.root(frame) != self.tree.root(world):
                apart.append(f"the {what} frame {frame!r} ({option})")
        if absent or apart:
            parts = ([f"not on {cfg.tf_topic!r} or {cfg.tf_static_topic!r}: {', '.join(absent)}"]
                     if absent else [])
            parts += [f"not connected to {world!r}: {', '.join(apart)}"] if apart else []
            raise FileFormatError(f"{self.path}: {'; '.join(parts)}; the frames there: {frames}")
        return replace(cfg, world_frame=world)

    def _threshold(self, cfg: RawBagConfig) -> float:
        """The contact threshold: given, or from the noise of the quiet samples before the presses."""
        self.noise = noise_floor(self.wrench_force)
        self._note("force_noise_n", [round(float(v), 6) for v in self.noise.std],
                   f"estimated: per sensor axis, from {self.noise.n_samples} quiet samples in "
                   f"{self.noise.n_windows} span(s) between the presses")
        if cfg.contact_force_n is not None:
            self._note("contact_force_n", cfg.contact_force_n, "given (`contact_force_n`)")
            return cfg.contact_force_n
        contact = contact_threshold(self.noise, self.commanded_n)
        self._note("contact_force_n", round(contact, 6),
                   f"{CONTACT_NOISE_MULTIPLE:g} × the noise's rms magnitude "
                   f"{self.noise.rms_n:.3g} N: noise alone crosses it with probability < 1e-4 a "
                   "sample")
        band_low = self.commanded_n * (1 - cfg.hold_band)
        if contact >= band_low:
            raise FileFormatError(
                f"{self.path}: topic {self.wrench_topic!r} is too noisy for presses of "
                f"{self.commanded_n:.4g} N: its noise ({self.noise.rms_n:.3g} N rms with the probe "
                f"free) puts the contact threshold at {contact:.3g} N, above the hold's band; "
                "set `contact_force_n` if the force holds well above it")
        return contact

    def _tip(self, cfg: RawBagConfig) -> RawBagConfig:
        """The tip frame: given and checked, or found among the frames rigidly joined to the
        force sensor (else the moving frames) as the lowest at the first press's hold whose
        ``z`` points up (the press goes along its ``−z``)."""
        frames, world = self.tree.frames, self.world_frame
        assert world is not None
        press = next((p for p in self.presses if p.error is None), self.presses[0])
        k = press.hold_start if press.hold_start >= 0 else press.start
        stamp = int(self.wrench_ns[k])
        what = f"{self.path}: the tip frame"
        if cfg.tip_frame is not None:
            if cfg.tip_frame not in frames or self.tree.root(cfg.tip_frame) != self.tree.root(world):
                raise FileFormatError(
                    f"{what} {cfg.tip_frame!r} (--tip-frame) is not on {cfg.tf_topic!r} or "
                    f"{cfg.tf_static_topic!r}, connected to {world!r}; the frames there: "
                    f"{frames}")
            self._note("tip_frame", cfg.tip_frame, "given")
            return cfg
        rigid = [f for f in self.tree.rigid_group(self.force_frame) if self.tree.moves(f)]
        moving = [f for f in frames if f != world and self.tree.moves(f)
                  and self.tree.root(f) == self.tree.root(world)]  # fmt: skip
        for pool, why in ((rigid, f"rigidly joined to the force sensor's {self.force_frame!r}"),
                          (moving, "moving with the arm")):
            up = []
            for frame in pool:
                try:
                    rot, trans = self.tree.lookup(world, frame, stamp, what=what)
                except DeformapError:
                    continue
                if rot[0][2, 2] > 0.5:  # z up: the press goes along -z, into the table
                    up.append((float(trans[0][2]), frame))
            if up:
                tip = min(up)[1]
                self._note("tip_frame", tip, f"found: the lowest frame {why} whose z points up "
                           f"at press {press.index + 1}'s hold")
                return replace(cfg, tip_frame=tip)
        raise FileFormatError(
            f"{what}: none found (no frame rigidly joined to the force sensor's "
            f"{self.force_frame!r} or moving with the arm has its z up at press "
            f"{press.index + 1}); name it with --tip-frame. The frames there: {frames}")

    # -- first pass -------------------------------------------------------------------------

    def _index(self) -> None:
        cfg, store, errors = self.config, typestore(), bag_read_errors()
        topics = {self.cloud_topic: _CLOUD, self.wrench_topic: _WRENCH, cfg.tf_topic: _TF}
        optional = {cfg.tf_static_topic: _TF}
        stamps: list[int] = []
        frames: set[str] = set()
        w_ns: list[int] = []
        w_force: list[list[float]] = []
        w_frames: set[str] = set()
        types = {**topics, **optional}
        for raw in iter_bag_messages(self.path, topics, optional=optional):
            where = f"{self.path} [{raw.topic} message {raw.number}]"
            try:
                msg = store.deserialize_cdr(bytes(raw.data), types[raw.topic])
            except errors as exc:
                raise FileFormatError(f"{where}: could not be decoded: "
                                      f"{bag_error_text(exc, 120)}") from None  # fmt: skip
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

    def _plan_observation(self) -> _Group:
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

    def _still(self, frames: list[int], where: str) -> _Group:
        """The frames whose camera pose lies within ``STILL_M``, ``STILL_RAD`` of the middle one's."""
        stamps = self.cloud_ns[frames]
        rot, trans = self.tree.lookup(self.world_frame, self.camera_frame, stamps,
                                      what=f"{where} [{self.cloud_topic}]")  # fmt: skip
        mid = len(frames) // 2
        angle = np.arccos(np.clip((np.einsum("nij,ij->n", rot, rot[mid]) - 1) / 2, -1.0, 1.0))
        still = (np.linalg.norm(trans - trans[mid], axis=1) <= STILL_M) & (angle <= STILL_RAD)
        kept = [f for f, s in zip(frames, still, strict=True) if s]
        return _Group(frames=kept, cam_stamp=int(stamps[mid]))

    # -- second pass: the average of each group ----------------------------------------------

    def _average(self) -> None:
        groups = [self._observation_group, *self._groups.values()]
        wanted: dict[int, list[_Group]] = {}
        for group in groups:
            for frame in group.frames:
                wanted.setdefault(frame, []).append(group)
        store, errors = typestore(), bag_read_errors()
        for raw in iter_bag_messages(self.path, {self.cloud_topic: _CLOUD}):
            number = raw.number - 1  # the frame index the groups name
            if number not in wanted:
                continue
            where = f"{self.path} [{self.cloud_topic} message {raw.number}]"
            try:
                msg = store.deserialize_cdr(bytes(raw.data), _CLOUD)
                xyz, rgb = self._xyz(msg, where)
            except errors as exc:
                raise FileFormatError(f"{where}: could not be decoded: "
                                      f"{bag_error_text(exc, 120)}") from None  # fmt: skip
            shape = (int(msg.height), int(msg.width))
            ok = np.isfinite(xyz).all(axis=1)
            for group in wanted[number]:
                if group.total is None or group.count is None:
                    group.shape, group.total = shape, np.zeros_like(xyz)
                    group.count = np.zeros(xyz.shape[0], dtype=np.int64)
                    group.rgb = None if rgb is None else np.zeros_like(xyz)
                elif shape != group.shape or shape[0] == 1:
                    continue  # another layout, or an unorganised cloud: no pixel to average
                group.total[ok] += xyz[ok]
                group.count[ok] += 1
                if group.rgb is not None and rgb is not None:
                    group.rgb[ok] += rgb[ok]
                else:
                    group.rgb = None

    def _xyz(self, msg: Any, where: str) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
        """The frame's points, NaN holes kept, and their colours (NaN at the holes) or None."""
        try:
            table = pointcloud2_structured(msg)
            xyz = xyz_with_holes(msg, table)
        except DeformapError as exc:
            raise FileFormatError(f"{where}: {str(exc).replace('`msg` ', '')}") from None
        rgb = pointcloud2_colors(msg, where=where, table=table, valid=np.isfinite(xyz).all(axis=1))
        return xyz * (1e-3 if self.config.units == "mm" else 1.0), rgb

    def _cloud(self, group: _Group, where: str) -> PointCloud:
        if group.total is None or group.count is None or not group.count.any():
            raise FileFormatError(f"{where}: topic {self.cloud_topic!r}: its frames hold "
                                  "no finite point")  # fmt: skip
        seen = group.count > 0
        cam = group.total[seen] / group.count[seen, None]
        rgb = None if group.rgb is None else np.clip(group.rgb[seen] / group.count[seen, None], 0, 1)
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
        record: ForceTravel | None = None
        # the sensor's noise along the press: its per-axis σ seen along the direction
        along = r_force[mid].T @ direction
        noise = float(np.sqrt(np.sum((along * self.noise.std) ** 2)))
        samples = block_means(travel, normal[ramp], noise)
        try:
            record = ForceTravel(travel_m=samples[0], force_n=samples[1])
        except DeformapError as exc:
            # a force step, or a ramp the sensor's noise hides: the camera still reads the dent
            notes["force_travel"] = (f"the ramp's force–travel record cannot be read ({exc}); "
                                     "β from the camera alone, no modulus")
        dent, dent_std = self._camera_dent(cloud, tip - cfg.tip_radius_m * direction, robot)
        moved = float(travel[-1]) if travel.size else 0.0
        notes["camera_dent_m"] = f"{dent:.5f} ± {dent_std:.5f}"
        notes["record_travel_m"] = f"{moved:.5f}"
        seen = dent > DENT_SIGMAS * dent_std and dent > TRAVEL_BACKWARDS_TOLERANCE_M
        if record is not None and moved <= TRAVEL_BACKWARDS_TOLERANCE_M and seen:
            notes["disagreement"] = (
                f"the record shows no travel ({moved * 1e3:.2f} mm) but the camera sees a dent of "
                f"{dent * 1e3:.2f} ± {dent_std * 1e3:.2f} mm around the contact; is the tip frame "
                f"{self.tip_frame!r} the measured pose (a commanded one does not move)? The "
                "record is not used: β from the camera alone, no modulus")
            notes["force_travel"] = notes["disagreement"]
            record = None
        elif record is not None and moved > 4 * TRAVEL_BACKWARDS_TOLERANCE_M and (
                dent + DENT_SIGMAS * dent_std < moved * HERTZ_DISC_FRACTION / 2):
            notes["disagreement"] = (
                f"the record shows {moved * 1e3:.2f} mm of travel but the camera sees no dent "
                f"({dent * 1e3:.2f} ± {dent_std * 1e3:.2f} mm) within two tip radii of the "
                "contact: a camera too coarse to see it there, or its extrinsics or the tip frame "
                "are off")
        if "disagreement" in notes:  # a warning in the report (map_session), said once
            logger.info("%s: %s", where, notes["disagreement"])
        return PressParts(cloud, tip, force, robot, record)

    def _camera_dent(self, cloud: PointCloud, contact: NDArray[np.float64],
                     robot: tuple[NDArray[np.float64], ...]) -> tuple[float, float]:
        """How far [m] the camera sees the surface sink within two tip radii of ``contact``, and
        its σ: each point of ``cloud`` there (below the tip's top, outside the robot's hulls)
        paired with the observation's point nearest in ``x``–``y`` (the same surface patch for a
        still camera); the mean of their height differences, a fifth cut off at each end (the
        robot's edges, a block's side), σ that mean's (a mean, not a median: a depth camera's
        heights come in disparity steps of millimetres, which a median keeps)."""
        from scipy.spatial import cKDTree

        radius, before = self.config.tip_radius_m, self.observation().points
        pts = cloud.points
        r = np.linalg.norm(pts[:, :2] - contact[:2], axis=1)
        # below the tip's top: what is higher there is the probe, the hand or the arm
        near = pts[(r <= 2 * radius) & (pts[:, 2] <= contact[2] + 2 * radius)]
        if len(near):
            near = near[~points_in_hull(near, robot)]
        if len(near) < 3:
            return 0.0, float("inf")
        gap, j = cKDTree(before[:, :2]).query(near[:, :2])
        dz = np.sort((before[j, 2] - near[:, 2])[gap <= radius / 2])
        cut = len(dz) // 5
        kept = dz[cut: len(dz) - cut]
        if len(kept) < 3:
            return 0.0, float("inf")
        return float(kept.mean()), float(kept.std(ddof=1) / np.sqrt(len(kept)))
