"""What a robot's drivers record while it presses, generated from an environment's answers: the
raw layout that ``deformap map`` reads with no settings (``docs/robot.md``).

:func:`raw_messages` turns an observation and a list of presses (world frame, each with its
force–travel record) into the messages a rig publishes: an organised ``PointCloud2`` in the
camera's optical frame (NaN holes, packed ``rgb`` as a FLOAT32, each pixel blanked in some
frames), a ``WrenchStamped`` in the force sensor's frame with the reaction force's sign and
per-axis noise, ``/tf`` with the arm moving the tool (and the tip below it) along each press, and
``/tf_static`` for the camera mount, the tip and the sensor. The messages are plain dicts of the
ROS 2 fields, so that any writer can store them; :func:`write_raw_mcap` stores them as one MCAP
file with deformap's bag writer. :class:`~deformap.replay.RigConfig` holds the rig's rates, noise,
clock skew, force profile and frame names: the imperfections a real recording has, as settings.

Each press runs approach (0.2 s), ramp from contact to the force (0.4 s; a ``step`` profile jumps
to the force at contact), hold (0.3 s), release (0.15 s) and a pause (0.15 s); the camera sees the
press's cloud from contact to the end of the release, the undisturbed surface otherwise. A record's
hold replays (its own clock) instead of the 0.3 s at the force, and its unloading after the hold;
without one the force is zero when the tip lifts (as when an arm retracts faster than the surface
recovers), so only a recorded unloading branch gives the bag one.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud
from deformap.environment import PressObservation
from deformap.errors import InvalidArgumentError
from deformap.replay._rawrig import RigConfig

__all__ = ["APPROACH", "FIRST_PRESS_S", "HOLD", "PAUSE", "RAMP", "RELEASE", "T0_NS",
           "RawMessage", "RawPress", "raw_messages", "raw_timeline", "write_raw_mcap"]

T0_NS = 1_700_000_000 * 10**9  # a realistic epoch stamp
#: Timeline of one press [s]: approach, ramp from contact to the force, hold, release, pause.
APPROACH, RAMP, HOLD, RELEASE, PAUSE = 0.2, 0.4, 0.3, 0.15, 0.15
FIRST_PRESS_S = 0.3

_CLOUD, _WRENCH, _TF = ("sensor_msgs/msg/PointCloud2", "geometry_msgs/msg/WrenchStamped",
                        "tf2_msgs/msg/TFMessage")  # fmt: skip


@dataclass(frozen=True)
class RawMessage:
    """One message: its ``topic``, ROS 2 ``msgtype``, log time [ns] and fields as plain data."""

    topic: str
    msgtype: str
    log_time_ns: int
    fields: dict[str, Any]


@dataclass(frozen=True)
class RawPress:
    """One press on the bag's timeline [s after the bag's start]."""

    obs: PressObservation
    start_s: float

    @property
    def contact_s(self) -> float:
        return self.start_s + APPROACH

    @property
    def hold_s(self) -> tuple[float, float]:
        """Start and end of the hold: the record's own hold's length, else :data:`HOLD`."""
        hold = self._phases["hold"]
        return self.contact_s + RAMP, self.contact_s + RAMP + (HOLD if hold is None else hold[0][-1])

    @property
    def release_s(self) -> float:
        """Start of the release: the end of the hold, or of the unloading branch replayed after it."""
        unloading = self._phases["unloading"]
        return self.hold_s[1] + (0.0 if unloading is None else unloading[0][-1])

    @property
    def end_s(self) -> float:
        """End of the press: release and pause done."""
        return self.release_s + RELEASE + PAUSE

    @cached_property
    def _phases(self) -> dict[str, tuple[NDArray[np.float64], ...] | None]:
        """For ``"hold"`` and ``"unloading"``: ``(seconds since the stretch began, travel since
        contact, force)`` of the record's stretch, its first sample the one before the stretch (the
        ramp's or the hold's last), or ``None`` when the record has none (built once a press)."""
        return {name: self._stretch(name) for name in ("hold", "unloading")}

    def _stretch(self, name: str) -> tuple[NDArray[np.float64], ...] | None:
        record = self.obs.force_travel
        phase = None if record is None else getattr(record, name)
        if record is None or phase is None or record.time_s is None:
            return None
        before = record.hold if name == "unloading" and record.hold is not None else record
        t0, d0, f0 = (float(before.time_s[-1]), float(before.travel_m[-1]),  # type: ignore[index]
                      float(before.force_n[-1]))
        return (np.concatenate([[0.0], phase.time_s - t0]),
                np.concatenate([[d0], phase.travel_m]) - float(record.travel_m[0]),
                np.concatenate([[f0], phase.force_n]))

    def replayed(self, t: float) -> tuple[float, float] | None:
        """Travel since contact [m] and force [N] the record's hold or unloading gives at ``t``
        [s on the bag's timeline], or ``None`` outside them or where the record has none."""
        for name, start, end in (("hold", *self.hold_s), ("unloading", self.hold_s[1],
                                                          self.release_s)):
            phase = self._phases[name]
            if phase is not None and start <= t <= end:
                return (float(np.interp(t - start, phase[0], phase[1])),
                        float(np.interp(t - start, phase[0], phase[2])))
        return None

    def lift(self) -> float:
        """The tip's travel from contact to the hold [m] (its record's)."""
        record = self.obs.force_travel
        return 0.0 if record is None else float(record.travel_m[-1] - record.travel_m[0])


def raw_timeline(presses: Sequence[PressObservation]) -> list[RawPress]:
    """The presses, one after the other from :data:`FIRST_PRESS_S`."""
    step = APPROACH + RAMP + HOLD + RELEASE + PAUSE
    timeline: list[RawPress] = []
    longer = 0.0  # what the presses so far ran over the plain step (their holds and unloadings)
    for i, obs in enumerate(presses):
        timeline.append(RawPress(obs, FIRST_PRESS_S + i * step + longer))
        longer += timeline[-1].end_s - timeline[-1].start_s - step
    return timeline


def _pose(rot: NDArray[np.float64], trans: Any) -> NDArray[np.float64]:
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rot, trans
    return m


def _rot(axes: str, degrees: Sequence[float]) -> NDArray[np.float64]:
    from scipy.spatial.transform import Rotation

    return np.asarray(Rotation.from_euler(axes, degrees, degrees=True).as_matrix())


def camera_optical2world() -> NDArray[np.float64]:
    """The camera above the table's near edge, looking at its middle (optical ``z`` forward)."""
    eye, target = np.array([0.30, -0.35, 0.65]), np.array([0.30, 0.20, 0.0])
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return _pose(np.column_stack([x, np.cross(z, x), z]), eye)


OPTICAL2LINK = _pose(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), [0, 0, 0])
BASE2WORLD = _pose(_rot("z", [180]), [0.3, 0.7, 0.0])
TIP2TOOL = _pose(_rot("x", [180]), [0.0, 0.0, 0.15])  # the flange's z points down the stick
SENSOR2TIP = _pose(_rot("zx", [90, 180]), [0, 0, 0.1])
TIP_YAW = _rot("z", [30])  # the tip's z stays up


def _tip_position(presses: list[RawPress], t: float, tip_moves: bool) -> NDArray[np.float64]:
    """The tip's centre: over each target, down 5 cm, along the record's travel, hold, up."""
    up = np.array([0.0, 0.0, 1.0])
    for k, p in enumerate(presses):
        hold = p.obs.contact.tip_center
        contact = hold + p.lift() * up
        above = contact + 0.05 * up
        if t < p.start_s:  # moving from the last press to above this one
            if k == 0:
                return above
            prev = presses[k - 1]
            prev_above = prev.obs.contact.tip_center + (prev.lift() + 0.05) * up
            w = np.clip((t - prev.release_s - RELEASE) / PAUSE, 0.0, 1.0)
            return np.asarray(prev_above + w * (above - prev_above))
        if t < p.contact_s:
            return np.asarray(above + (t - p.start_s) / APPROACH * (contact - above))
        if not tip_moves and t <= p.release_s:
            return np.asarray(contact)
        if t < p.hold_s[0]:
            record = p.obs.force_travel
            if record is None:
                return np.asarray(contact + min((t - p.contact_s) / RAMP, 1.0) * (hold - contact))
            u = _ramp_u(p, np.array([t]))
            travel = np.interp(u, np.arange(len(record)), record.travel_m)[0]
            return np.asarray(contact - (travel - record.travel_m[0]) * up)
        if t <= p.release_s:
            replayed = p.replayed(t)
            return np.asarray(hold if replayed is None else contact - replayed[0] * up)
        if t <= p.release_s + RELEASE:
            left = p.replayed(p.release_s)
            start = contact if not tip_moves else hold if left is None else contact - left[0] * up
            return np.asarray(start + (t - p.release_s) / RELEASE * (above - start))
    last = presses[-1]
    return np.asarray(last.obs.contact.tip_center + (last.lift() + 0.05) * up)


def _ramp_u(press: RawPress, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Position in the force–travel record (sample index, fractional) at times within the ramp."""
    n = 2 if press.obs.force_travel is None else len(press.obs.force_travel)
    return np.asarray(np.clip((t - press.contact_s) / RAMP, 0.0, 1.0) * (n - 1))


def _force_on_surface(presses: list[RawPress], t: NDArray[np.float64],
                      profile: str) -> NDArray[np.float64]:  # fmt: skip
    """``(n, 3)`` world force the probe exerts on the surface at the times."""
    out = np.zeros((t.size, 3))
    for p in presses:
        f = p.obs.contact.force
        unit = f / np.linalg.norm(f)
        record = p.obs.force_travel
        ramp = (t >= p.contact_s) & (t < p.hold_s[0])
        if profile == "step" or record is None:
            out[ramp] = f
        else:
            mags = np.interp(_ramp_u(p, t[ramp]), np.arange(len(record)), record.force_n)
            out[ramp] = mags[:, None] * unit
        after = np.flatnonzero((t >= p.hold_s[0]) & (t <= p.release_s))
        out[after] = f
        for i in after:  # the record's hold and unloading, where it has them
            replayed = p.replayed(float(t[i]))
            if replayed is not None:
                out[i] = replayed[1] * unit
    return out


def _organised(points_world: NDArray[np.float64], optical2world: NDArray[np.float64],
               pixels: NDArray[np.int64], n_pixels: int) -> NDArray[np.float32]:  # fmt: skip
    """``(n_pixels, 3)`` float32 camera-frame points on the given pixels, NaN elsewhere."""
    cam = (points_world - optical2world[:3, 3]) @ optical2world[:3, :3]
    grid = np.full((n_pixels, 3), np.nan, dtype=np.float32)
    grid[pixels] = cam.astype(np.float32)
    return grid


def _packed(colors: NDArray[np.float64] | None, pixels: NDArray[np.int64],
            n: int) -> NDArray[np.uint32]:  # fmt: skip
    """``(n,)`` uint32 ``0x00RRGGBB`` words: ``colors`` on ``pixels``, grey without colours."""
    words = np.full(n, 0x808080, dtype=np.uint32)
    if colors is not None:
        rgb = np.round(np.asarray(colors) * 255).astype(np.uint32)
        words[pixels] = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    return words


def _header(t_s: float, frame: str) -> dict[str, Any]:
    ns = T0_NS + round(t_s * 1e9)
    return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": frame}


def _tf(t_s: float, parent: str, child: str, m: NDArray[np.float64]) -> dict[str, Any]:
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(m[:3, :3]).as_quat()
    tx, ty, tz = m[:3, 3]
    return {"header": _header(t_s, parent), "child_frame_id": child,
            "transform": {"translation": {"x": float(tx), "y": float(ty), "z": float(tz)},
                          "rotation": {"x": float(x), "y": float(y), "z": float(z),
                                       "w": float(w)}}}  # fmt: skip


def _cloud_msg(t_s: float, frame: str, grid: NDArray[np.float32], shape: tuple[int, int],
               words: NDArray[np.uint32]) -> dict[str, Any]:  # fmt: skip
    table = np.zeros(grid.shape[0], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                           ("rgb", "<f4")])  # fmt: skip
    for i, a in enumerate("xyz"):
        table[a] = grid[:, i]
    table["rgb"] = words.view(np.float32)  # the bits, as the drivers publish them
    fields = [{"name": a, "offset": 4 * i, "datatype": 7, "count": 1}
              for i, a in enumerate(["x", "y", "z", "rgb"])]  # fmt: skip
    return {"header": _header(t_s, frame), "height": shape[0], "width": shape[1],
            "fields": fields, "is_bigendian": False, "point_step": 16,
            "row_step": 16 * shape[1], "data": table.tobytes(), "is_dense": False}  # fmt: skip


def raw_messages(observation: PointCloud, presses: Sequence[PressObservation], rig: RigConfig,
                 *, seed: int = 0) -> Iterator[RawMessage]:
    """The messages of a robot recording of ``presses`` after ``observation`` (world frame),
    topic by topic (``/tf_static``, the camera, ``/tf``, the force sensor), each topic in time
    order, every stamp jittered by a little of its period; ``seed`` draws holes, jitter and
    noise."""
    if not presses:
        raise InvalidArgumentError("`presses` must hold at least one press; got none")
    rng = np.random.default_rng(seed)
    timeline = raw_timeline(presses)
    end_s = timeline[-1].end_s
    optical2world = camera_optical2world()
    colored = [observation] + [p.cloud for p in presses]
    clouds = [np.asarray(c.points) for c in colored]
    width = 128
    height = -(-max(len(c) for c in clouds) * 5 // 4 // width)  # a quarter more pixels: holes
    n_pixels = height * width
    layouts = [np.sort(rng.choice(n_pixels, len(c), replace=False)) for c in clouds]
    grids = [_organised(c, optical2world, px, n_pixels) for c, px in zip(clouds, layouts,
                                                                       strict=True)]  # fmt: skip
    words = [_packed(c.colors if rig.colors else None, px, n_pixels)
             for c, px in zip(colored, layouts, strict=True)]  # fmt: skip

    def at(t_s: float) -> int:
        return T0_NS + round(t_s * 1e9)

    static = [_tf(0.0, rig.world_frame, "camera_link", optical2world @ np.linalg.inv(OPTICAL2LINK)),
              _tf(0.0, "camera_link", rig.camera_frame, OPTICAL2LINK),
              _tf(0.0, rig.world_frame, rig.base_frame, BASE2WORLD),
              _tf(0.0, rig.tool_frame, rig.tip_frame, TIP2TOOL),
              _tf(0.0, rig.tip_frame, rig.sensor_frame, SENSOR2TIP)]  # fmt: skip
    yield RawMessage("/tf_static", _TF, at(0.0), {"transforms": static})
    # the camera: the observation, or from contact to release the press's cloud (each pixel
    # blanked in one frame of nine at most, so the per-pixel mean gives every point back)
    jitter = 0.1 / rig.camera_hz
    for n, t in enumerate(np.arange(0.0, end_s, 1 / rig.camera_hz)):
        stamp = float(t + rng.uniform(-jitter, jitter))
        held = [k for k, p in enumerate(timeline) if p.contact_s <= stamp <= p.release_s + RELEASE]
        which = held[0] + 1 if held else 0
        grid = grids[which].copy()
        blank = layouts[which]
        grid[blank[(np.arange(blank.size) * 7 + n) % 9 == 0][::3]] = np.nan
        yield RawMessage(rig.cloud_topic, _CLOUD, at(stamp),
                         _cloud_msg(stamp, rig.camera_frame, grid, (height, width), words[which]))
    # the arm: base -> tool carries the tip along the press
    jitter = 0.1 / rig.tf_hz
    for t in np.arange(0.0, end_s, 1 / rig.tf_hz):
        stamp = float(t + rng.uniform(-jitter, jitter))
        tip2world = _pose(TIP_YAW, _tip_position(timeline, stamp, rig.tip_moves))
        tool2base = np.linalg.inv(BASE2WORLD) @ tip2world @ np.linalg.inv(TIP2TOOL)
        yield RawMessage("/tf", _TF, at(stamp), {
            "transforms": [_tf(stamp, rig.base_frame, rig.tool_frame, tool2base)]})
    # the force sensor: the reaction (the surface on the probe) in its own frame
    times = np.arange(0.0, end_s, 1 / rig.wrench_hz)
    times = times + rng.uniform(-0.2 / rig.wrench_hz, 0.2 / rig.wrench_hz, times.size)
    force = _force_on_surface(timeline, times, rig.force_profile)
    force[:, 2] -= rig.force_bias_n  # a sensor not zeroed
    sensor2world = TIP_YAW @ SENSOR2TIP[:3, :3]
    reaction = -force @ sensor2world  # = (sensor2world.T @ -f) row by row
    reaction += rng.normal(0.0, 1.0, reaction.shape) * np.asarray(rig.force_noise_n)
    for t, f in zip(times, reaction, strict=True):
        yield RawMessage(rig.wrench_topic, _WRENCH, at(float(t)), {
            "header": _header(float(t) + rig.stamp_skew_s, rig.sensor_frame),
            "wrench": {"force": dict(zip("xyz", f.tolist(), strict=True)),
                       "torque": {"x": 0.0, "y": 0.0, "z": 0.0}}})  # fmt: skip


# -- stored with deformap's bag writer (rosbags) ----------------------------------------------------
def _to_rosbags(msgtype: str, d: dict[str, Any]) -> Any:
    from deformap.cloud.io import typestore

    types = typestore().types

    def header(h: dict[str, Any]) -> Any:
        stamp = types["builtin_interfaces/msg/Time"](sec=h["stamp"]["sec"],
                                                     nanosec=h["stamp"]["nanosec"])
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id=h["frame_id"])

    def vec(v: dict[str, float], kind: str = "Vector3") -> Any:
        return types[f"geometry_msgs/msg/{kind}"](**v)

    if msgtype == _TF:
        return types[_TF](transforms=[types["geometry_msgs/msg/TransformStamped"](
            header=header(tf["header"]), child_frame_id=tf["child_frame_id"],
            transform=types["geometry_msgs/msg/Transform"](
                translation=vec(tf["transform"]["translation"]),
                rotation=vec(tf["transform"]["rotation"], "Quaternion")))
            for tf in d["transforms"]])  # fmt: skip
    if msgtype == _WRENCH:
        return types[_WRENCH](header=header(d["header"]), wrench=types["geometry_msgs/msg/Wrench"](
            force=vec(d["wrench"]["force"]), torque=vec(d["wrench"]["torque"])))
    fields = [types["sensor_msgs/msg/PointField"](**f) for f in d["fields"]]
    return types[_CLOUD](
        header=header(d["header"]), height=d["height"], width=d["width"], fields=fields,
        is_bigendian=d["is_bigendian"], point_step=d["point_step"], row_step=d["row_step"],
        data=np.frombuffer(d["data"], dtype=np.uint8), is_dense=d["is_dense"])


def write_raw_mcap(path: Path, observation: PointCloud, presses: Sequence[PressObservation],
                   rig: RigConfig, *, seed: int = 0) -> list[RawPress]:
    """Write :func:`raw_messages` as the new MCAP file ``path`` (rosbags' writer, the ``ros``
    extra) and return the timeline."""
    from deformap.cloud.io import bag_writer, typestore

    if path.exists():
        raise InvalidArgumentError(f"`path` {path} exists already; a bag is written to a new file")
    store = typestore()
    with tempfile.TemporaryDirectory(dir=path.parent) as tmp:
        staging = Path(tmp) / "bag"  # rosbags writes a rosbag2 folder around the .mcap
        with bag_writer(staging, "mcap") as writer:
            conns: dict[str, Any] = {}
            for msg in raw_messages(observation, presses, rig, seed=seed):
                if msg.topic not in conns:
                    conns[msg.topic] = writer.add_connection(msg.topic, msg.msgtype,
                                                             typestore=store)  # fmt: skip
                writer.write(conns[msg.topic], msg.log_time_ns,
                             store.serialize_cdr(_to_rosbags(msg.msgtype, msg.fields),
                                                 msg.msgtype))  # fmt: skip
        (mcap,) = staging.glob("*.mcap")
        shutil.move(mcap, path)
    return raw_timeline(presses)

