"""A ROS 2 bag as a robot records it, read as a recorded session (``docs/robot.md``).

The bag holds an organised PointCloud2 stream in the camera's frame, a WrenchStamped stream in the
force sensor's frame, and ``/tf`` with ``/tf_static`` (:class:`~deformap.replay.RawBagConfig`).
A first pass decodes the wrenches, transforms and the clouds' stamps and finds the presses in the
force stream (:func:`find_presses`); a second averages, pixel by pixel, the frames each press was
held for and the observation's (colours too, when every frame has them), one frame in memory at a
time. A press that cannot be read is refused in one line naming it, the topic and the gap.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud
from deformap.cloud.io import (
    TransformTree,
    bag_error_text,
    bag_read_errors,
    header_stamp_ns,
    iter_bag_messages,
    pointcloud2_colors,
    pointcloud2_structured,
    typestore,
    xyz_with_holes,
)
from deformap.environment import ForceTravel, Workspace
from deformap.errors import DeformapError, FileFormatError
from deformap.replay._format import PokeSpec, PressParts
from deformap.replay._rawconfig import HullPart, RawBagConfig
from deformap.replay._rawpress import FoundPress, find_presses

__all__ = ["RawBagReader", "hull_points"]

_CLOUD = "sensor_msgs/msg/PointCloud2"
_WRENCH = "geometry_msgs/msg/WrenchStamped"
_TF = "tf2_msgs/msg/TFMessage"

#: A frame is averaged only while the camera holds within these [m, rad] of its pose at the
#: middle frame: 1 mrad moves a point 1 m away by 1 mm, below a depth camera's noise.
STILL_M, STILL_RAD = 5e-4, 1e-3

#: The largest force component [N] a wrench may hold, beyond any force–torque sensor's range: a
#: larger or non-finite one is a damaged message, refused before it is squared.
MAX_FORCE_N = 1e6

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
        self.path, self.config, self.commanded_n = bag, config, commanded_n
        cfg = config
        self.tree = TransformTree(cfg.tf_topic, round(cfg.stamp_tolerance_s * 1e9))
        self._index()
        self.origin_ns = self.tree.origin_ns = int(min(self.cloud_ns.min(), self.wrench_ns[0]))
        self.presses = find_presses(
            self.wrench_ns, np.linalg.norm(self.wrench_force, axis=1), commanded_n=commanded_n,
            contact_n=cfg.contact_force_n, band=cfg.hold_band,
            hold_min_ns=round(cfg.hold_min_s * 1e9),
            merge_ns=round(cfg.stamp_tolerance_s * 1e9), topic=cfg.wrench_topic,
            origin_ns=self.origin_ns)
        if self.presses and self.presses[0].start == 0:
            first = float(np.linalg.norm(self.wrench_force[0]))
            raise FileFormatError(
                f"{bag}: topic {cfg.wrench_topic!r} reads {first:.4g} N from its first sample, over "
                f"the contact threshold {cfg.contact_force_n:g} N (`contact_force_n`): a sensor "
                "not zeroed with the probe free, or a recording started during a press")
        if not self.presses:
            peak = float(np.max(np.linalg.norm(self.wrench_force, axis=1)))
            raise FileFormatError(
                f"{bag}: no press on {cfg.wrench_topic!r}: the force must stay above "
                f"{cfg.contact_force_n:g} N (`contact_force_n`) for {cfg.hold_min_s:g} s at least "
                f"once; its largest is {peak:.4g} N")
        self._groups: dict[int, _Group] = {}
        self._errors: dict[int, str] = {}
        self._observation_group = self._plan_observation()
        for press in self.presses:
            if press.error is None:
                self._plan_press(press)
        self._average()

    # -- first pass -------------------------------------------------------------------------

    def _index(self) -> None:
        cfg, store, errors = self.config, typestore(), bag_read_errors()
        topics = {cfg.cloud_topic: _CLOUD, cfg.wrench_topic: _WRENCH, cfg.tf_topic: _TF}
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
            if raw.topic == cfg.cloud_topic:
                stamps.append(header_stamp_ns(msg.header))
                frames.add(str(msg.header.frame_id))
            elif raw.topic == cfg.wrench_topic:
                f = msg.wrench.force
                w_ns.append(header_stamp_ns(msg.header))
                w_force.append([float(f.x), float(f.y), float(f.z)])
                w_frames.add(str(msg.header.frame_id))
            else:
                self.tree.add(msg, static=raw.topic == cfg.tf_static_topic and
                              raw.topic != cfg.tf_topic, where=where)  # fmt: skip
        for topic, count in ((cfg.cloud_topic, len(stamps)), (cfg.wrench_topic, len(w_ns))):
            if count == 0:
                raise FileFormatError(f"{self.path}: topic {topic!r} has no messages")
        self.camera_frame = cfg.camera_frame or self._one_frame(frames, cfg.cloud_topic)
        self.force_frame = cfg.force_frame or self._one_frame(w_frames, cfg.wrench_topic)
        order = np.argsort(np.asarray(w_ns, dtype=np.int64), kind="stable")
        self.wrench_ns = np.asarray(w_ns, dtype=np.int64)[order]
        self.wrench_force = np.asarray(w_force, dtype=np.float64)[order]
        bad = ~(np.abs(self.wrench_force) <= MAX_FORCE_N).all(axis=1)  # NaN fails too
        if bad.any():
            first = int(order[np.flatnonzero(bad)[0]])
            raise FileFormatError(
                f"{self.path} [{cfg.wrench_topic} message {first + 1}]: force "
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
                f"{cfg.cloud_topic!r} from t = {self._s(times[pick])} s must all come before the "
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
                    f"{where}: topic {cfg.cloud_topic!r} has no frame within "
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
        rot, trans = self.tree.lookup(self.config.world_frame, self.camera_frame, stamps,
                                      what=f"{where} [{self.config.cloud_topic}]")  # fmt: skip
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
        cfg, store, errors = self.config, typestore(), bag_read_errors()
        for raw in iter_bag_messages(self.path, {cfg.cloud_topic: _CLOUD}):
            number = raw.number - 1  # the frame index the groups name
            if number not in wanted:
                continue
            where = f"{self.path} [{cfg.cloud_topic} message {raw.number}]"
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
            raise FileFormatError(f"{where}: topic {self.config.cloud_topic!r}: its frames hold "
                                  "no finite point")  # fmt: skip
        seen = group.count > 0
        cam = group.total[seen] / group.count[seen, None]
        rgb = None if group.rgb is None else np.clip(group.rgb[seen] / group.count[seen, None], 0, 1)
        rot, trans = self.tree.lookup(self.config.world_frame, self.camera_frame, group.cam_stamp,
                                      what=f"{where} [{self.config.cloud_topic}]")  # fmt: skip
        return PointCloud(cam @ rot[0].T + trans[0], rgb)

    # -- what the session asks for -----------------------------------------------------------

    def observation(self) -> PointCloud:
        return self._cloud(self._observation_group, f"{self.path}: the observation")

    def workspace(self) -> Workspace:
        cfg = self.config
        if cfg.workspace_lower is not None and cfg.workspace_upper is not None:
            return Workspace(lower=cfg.workspace_lower, upper=cfg.workspace_upper)
        pts = self.observation().points
        lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
        return Workspace(lower=(float(lo[0]), float(lo[1])), upper=(float(hi[0]), float(hi[1])))

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
                        self.config.world_frame, self.config.tip_frame, stamp,
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
        span = slice(press.start, press.hold_end)
        stamps = self.wrench_ns[span]
        r_force, _ = self.tree.lookup(cfg.world_frame, self.force_frame, stamps,
                                      what=f"{where} [{cfg.wrench_topic}]")  # fmt: skip
        sign = -1.0 if cfg.wrench_sign == "reaction" else 1.0
        forces = sign * np.einsum("nij,nj->ni", r_force, self.wrench_force[span])
        r_tip, tips = self.tree.lookup(cfg.world_frame, cfg.tip_frame, stamps,
                                       what=f"{where} [{cfg.tf_topic}, the tip]")  # fmt: skip
        hold = slice(press.hold_start - press.start, press.hold_end - press.start)
        mid = (hold.start + hold.stop) // 2
        direction = -r_tip[mid][:, 2]  # the press goes along the tip frame's -z
        if direction[2] >= 0.0:  # the press must go down, into the table's surface
            raise FileFormatError(
                f"{where}: the tip frame {cfg.tip_frame!r}'s −z points "
                f"{np.round(direction, 3).tolist()} in {cfg.world_frame!r}, not down into the "
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
        try:
            record = ForceTravel(travel_m=travel, force_n=normal[ramp])
        except DeformapError as exc:
            raise FileFormatError(f"{where}: the force–travel record of the ramp: {exc}") from None
        if spec.index not in self._groups:
            raise FileFormatError(f"{where}: {self._errors.get(spec.index, 'no frame')}")
        cloud = self._cloud(self._groups[spec.index], where)
        tip = tips[hold].mean(axis=0)
        robot = tuple(hull_points(p, r_tip[mid], tip) for p in cfg.hull)  # a hull per part
        return PressParts(cloud, tip, force, robot, record)
