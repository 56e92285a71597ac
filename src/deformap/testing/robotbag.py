"""A bag as a robot's drivers record it, written with the ``mcap`` and ``mcap-ros2-support`` packages
(the ``test`` extra), not deformap's writer: for tests of ``deformap map BAG`` and of its reader.

:func:`write_raw_bag` writes a recorded session's presses as a rig publishes them: an organised
``PointCloud2`` in the camera's optical frame (NaN holes, packed rgb, pixels blanked in some
frames), a ``WrenchStamped`` in a rotated sensor frame with the reaction force's sign, ``/tf``
with the arm moving the tip along the press and ``/tf_static`` for the camera mount, every stamp
jittered. :func:`raw_settings` is the YAML beside it. :func:`copy_to_db3` writes such a bag's
messages as a lone sqlite3 ``.db3`` with rosbags' writer (the ``ros`` extra).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from deformap.environment import PressObservation
from deformap.replay import RecordedSession

__all__ = ["APPROACH", "FIRST_PRESS_S", "HOLD", "MSGDEFS", "PAUSE", "RAMP", "RELEASE", "T0_NS",
           "Press", "copy_to_db3", "raw_settings", "write_raw_bag"]

T0_NS = 1_700_000_000 * 10**9  # a realistic epoch stamp
#: Timeline of one press [s]: approach, ramp from contact to the force, hold, release, pause.
APPROACH, RAMP, HOLD, RELEASE, PAUSE = 0.2, 0.4, 0.3, 0.15, 0.15
FIRST_PRESS_S = 0.3

# -- message definitions, as ROS 2 ships them (dependencies after the ==== lines) -----------------
_SEP = "\n" + "=" * 80 + "\n"
_HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id" + _SEP + \
    "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec"
_VECTOR = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z"
MSGDEFS = {
    "sensor_msgs/msg/PointCloud2": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n"
        "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense"
        + _SEP + _HEADER + _SEP + "MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\n"
        "uint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\n"
        "uint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count"),
    "geometry_msgs/msg/WrenchStamped": (
        "std_msgs/Header header\ngeometry_msgs/Wrench wrench" + _SEP + _HEADER + _SEP
        + "MSG: geometry_msgs/Wrench\ngeometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque"
        + _SEP + _VECTOR),
    "tf2_msgs/msg/TFMessage": (
        "geometry_msgs/TransformStamped[] transforms" + _SEP
        + "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/Transform transform" + _SEP + _HEADER + _SEP
        + "MSG: geometry_msgs/Transform\ngeometry_msgs/Vector3 translation\n"
        "geometry_msgs/Quaternion rotation" + _SEP + _VECTOR + _SEP
        + "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w"),
}  # fmt: skip


def _header(t_s: float, frame: str) -> dict[str, Any]:
    ns = T0_NS + round(t_s * 1e9)
    return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": frame}


def _pose(rot: np.ndarray, trans: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rot, trans
    return m


def _tf(t_s: float, parent: str, child: str, m: np.ndarray) -> dict[str, Any]:
    x, y, z, w = Rotation.from_matrix(m[:3, :3]).as_quat()
    tx, ty, tz = m[:3, 3]
    return {"header": _header(t_s, parent), "child_frame_id": child,
            "transform": {"translation": {"x": tx, "y": ty, "z": tz},
                          "rotation": {"x": x, "y": y, "z": z, "w": w}}}  # fmt: skip


# -- the rig: camera mount, arm base, tool, tip and sensor --------------------------------------
def _camera_optical2world() -> np.ndarray:
    eye, target = np.array([0.30, -0.35, 0.65]), np.array([0.30, 0.20, 0.0])
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return _pose(np.column_stack([x, np.cross(z, x), z]), eye)


OPTICAL2LINK = _pose(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), [0, 0, 0])
BASE2WORLD = _pose(Rotation.from_euler("z", 180, degrees=True).as_matrix(), [0.3, 0.7, 0.0])
TIP2TOOL = _pose(Rotation.from_euler("x", 180, degrees=True).as_matrix(), [0.0, 0.0, 0.15])
SENSOR2TIP = _pose(Rotation.from_euler("zx", [90, 180], degrees=True).as_matrix(), [0, 0, 0.1])
TIP_YAW = Rotation.from_euler("z", 30, degrees=True).as_matrix()  # the tip's z stays up


@dataclasses.dataclass
class Press:
    obs: PressObservation
    start_s: float

    @property
    def contact_s(self) -> float:
        return self.start_s + APPROACH

    @property
    def hold_s(self) -> tuple[float, float]:
        return self.contact_s + RAMP, self.contact_s + RAMP + HOLD

    def lift(self) -> float:
        assert self.obs.force_travel is not None
        return float(self.obs.force_travel.travel_m[-1] - self.obs.force_travel.travel_m[0])


def _timeline(session: RecordedSession) -> list[Press]:
    step = APPROACH + RAMP + HOLD + RELEASE + PAUSE
    return [Press(session.press_observation(i), FIRST_PRESS_S + i * step)
            for i in range(len(session))]


def _ramp_u(press: Press, t: np.ndarray) -> np.ndarray:
    """Position in the force–travel record (sample index, fractional) at times within the ramp."""
    assert press.obs.force_travel is not None
    n = len(press.obs.force_travel)
    return np.clip((t - press.contact_s) / RAMP, 0.0, 1.0) * (n - 1)


def _tip_position(presses: list[Press], t: float) -> np.ndarray:
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
            w = np.clip((t - prev.hold_s[1] - RELEASE) / PAUSE, 0.0, 1.0)
            return prev_above + w * (above - prev_above)
        if t < p.contact_s:
            return above + (t - p.start_s) / APPROACH * (contact - above)
        if t < p.hold_s[0]:
            record = p.obs.force_travel
            assert record is not None
            u = _ramp_u(p, np.array([t]))
            travel = np.interp(u, np.arange(len(record)), record.travel_m)[0]
            return contact - (travel - record.travel_m[0]) * up
        if t <= p.hold_s[1]:
            return hold
        if t <= p.hold_s[1] + RELEASE:
            return hold + (t - p.hold_s[1]) / RELEASE * (above - hold)
    last = presses[-1]
    return last.obs.contact.tip_center + (last.lift() + 0.05) * up


def _force_on_surface(presses: list[Press], t: np.ndarray) -> np.ndarray:
    """``(n, 3)`` world force the probe exerts on the surface at the times."""
    out = np.zeros((t.size, 3))
    for p in presses:
        f = p.obs.contact.force
        unit = f / np.linalg.norm(f)
        record = p.obs.force_travel
        assert record is not None
        ramp = (t >= p.contact_s) & (t < p.hold_s[0])
        mags = np.interp(_ramp_u(p, t[ramp]), np.arange(len(record)), record.force_n)
        out[ramp] = mags[:, None] * unit
        out[(t >= p.hold_s[0]) & (t <= p.hold_s[1])] = f
        rel = (t > p.hold_s[1]) & (t < p.hold_s[1] + RELEASE)
        out[rel] = (1 - (t[rel] - p.hold_s[1]) / RELEASE)[:, None] * f
    return out


def _organised(points_world: np.ndarray, optical2world: np.ndarray, pixels: np.ndarray,
               shape: tuple[int, int]) -> np.ndarray:  # fmt: skip
    """``(h·w, 3)`` float32 camera-frame points on the given (sorted) pixels, NaN elsewhere."""
    cam = (points_world - optical2world[:3, 3]) @ optical2world[:3, :3]
    grid = np.full((shape[0] * shape[1], 3), np.nan, dtype=np.float32)
    grid[pixels] = cam.astype(np.float32)
    return grid


def _packed(colors: np.ndarray | None, pixels: np.ndarray, n: int) -> np.ndarray:
    """``(n,)`` uint32 ``0x00RRGGBB`` words: ``colors`` on ``pixels``, grey without colours."""
    words = np.full(n, 0x808080, dtype=np.uint32)
    if colors is not None:
        rgb = np.round(colors * 255).astype(np.uint32)
        words[pixels] = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    return words


def _cloud_msg(t_s: float, grid: np.ndarray, shape: tuple[int, int],
               words: np.ndarray) -> dict[str, Any]:  # fmt: skip
    table = np.zeros(grid.shape[0], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                           ("rgb", "<f4")])  # fmt: skip
    for i, a in enumerate("xyz"):
        table[a] = grid[:, i]
    table["rgb"] = words.view(np.float32)  # the bits, as the drivers publish them
    fields = [{"name": a, "offset": 4 * i, "datatype": 7, "count": 1}
              for i, a in enumerate(["x", "y", "z", "rgb"])]  # fmt: skip
    return {"header": _header(t_s, "camera_depth_optical_frame"), "height": shape[0],
            "width": shape[1], "fields": fields, "is_bigendian": False, "point_step": 16,
            "row_step": 16 * shape[1], "data": table.tobytes(), "is_dense": False}  # fmt: skip


def write_raw_bag(path: Path, session: RecordedSession, *, seed: int = 0,
                  drop: tuple[str, ...] = (), camera_gap_s: tuple[float, float] | None = None,
                  tf_gap_s: tuple[float, float] | None = None, bias_n: float = 0.0,
                  camera_hz: float = 30.0, tf_hz: float = 50.0, wrench_hz: float = 500.0,
                  chunk_size: int = 1024 * 1024, compression: str = "zstd",
                  colors: bool = False) -> list[Press]:  # fmt: skip
    """Write ``session``'s presses as a robot's drivers record them; return the timeline.

    ``drop`` leaves topics out; ``camera_gap_s`` and ``tf_gap_s`` leave out the camera's frames
    or the arm's transforms stamped within a span [s]; ``bias_n`` offsets the sensor's z (a
    sensor not zeroed); the rates are the camera's, the arm's ``/tf`` and the force sensor's
    [Hz]; ``chunk_size`` and ``compression`` (``"zstd"``, ``"lz4"`` or ``"none"``) the writer's
    chunks', each with its CRC-32. The packed ``rgb`` field is grey, or with ``colors`` the
    session clouds' own colours (which they must have), rounded to 8 bits a channel.
    """
    import mcap_ros2.writer as mcap_ros2_writer
    from mcap.writer import CompressionType

    rng = np.random.default_rng(seed)
    presses = _timeline(session)
    end_s = presses[-1].hold_s[1] + RELEASE + PAUSE
    optical2world = _camera_optical2world()
    colored = [session.observation()] + [p.obs.cloud for p in presses]
    clouds = [c.points for c in colored]
    width = 128
    height = -(-max(len(c) for c in clouds) * 5 // 4 // width)  # a quarter more pixels: holes
    shape = (height, width)
    layouts = [np.sort(rng.choice(height * width, len(c), replace=False)) for c in clouds]
    grids = [_organised(c, optical2world, px, shape) for c, px in zip(clouds, layouts, strict=True)]
    if colors and any(c.colors is None for c in colored):
        raise ValueError("`colors=True` needs a session whose clouds have colours")
    words = [_packed(c.colors if colors else None, px, height * width)
             for c, px in zip(colored, layouts, strict=True)]  # fmt: skip
    writer = mcap_ros2_writer.Writer(str(path), chunk_size=chunk_size,
                                     compression=CompressionType[compression.upper()])
    schemas = {name: writer.register_msgdef(name, text) for name, text in MSGDEFS.items()}

    def put(topic: str, kind: str, msg: dict[str, Any], t_s: float) -> None:
        if topic not in drop:
            writer.write_message(topic, schemas[kind], msg, log_time=T0_NS + round(t_s * 1e9))

    static = [_tf(0.0, "world", "camera_link", optical2world @ np.linalg.inv(OPTICAL2LINK)),
              _tf(0.0, "camera_link", "camera_depth_optical_frame", OPTICAL2LINK),
              _tf(0.0, "world", "base_link", BASE2WORLD),
              _tf(0.0, "tool0", "probe_tip", TIP2TOOL),
              _tf(0.0, "probe_tip", "ft_sensor", SENSOR2TIP)]  # fmt: skip
    put("/tf_static", "tf2_msgs/msg/TFMessage", {"transforms": static}, 0.0)
    # the camera (30 Hz): the observation, or from contact to release the press's cloud (each
    # pixel blanked in one frame of nine at most, so the per-pixel mean gives every point back)
    for n, t in enumerate(np.arange(0.0, end_s, 1 / camera_hz)):
        stamp = t + rng.uniform(-0.003, 0.003)
        if camera_gap_s is not None and camera_gap_s[0] <= stamp <= camera_gap_s[1]:
            continue
        held = [k for k, p in enumerate(presses) if p.contact_s <= stamp <= p.hold_s[1] + RELEASE]
        which = held[0] + 1 if held else 0
        grid = grids[which].copy()
        blank = layouts[which]
        grid[blank[(np.arange(blank.size) * 7 + n) % 9 == 0][::3]] = np.nan
        put("/camera/depth/color/points", "sensor_msgs/msg/PointCloud2",
            _cloud_msg(stamp, grid, shape, words[which]), stamp)
    # the arm (50 Hz): base_link -> tool0 carries the tip along the press
    for t in np.arange(0.0, end_s, 1 / tf_hz):
        stamp = t + rng.uniform(-0.002, 0.002)
        if tf_gap_s is not None and tf_gap_s[0] <= stamp <= tf_gap_s[1]:
            continue
        tip2world = _pose(TIP_YAW, _tip_position(presses, stamp))
        tool2base = np.linalg.inv(BASE2WORLD) @ tip2world @ np.linalg.inv(TIP2TOOL)
        put("/tf", "tf2_msgs/msg/TFMessage",
            {"transforms": [_tf(stamp, "base_link", "tool0", tool2base)]}, stamp)
    # the force sensor (500 Hz): the reaction (the surface on the probe) in its own frame
    times = np.arange(0.0, end_s, 1 / wrench_hz)
    times = times + rng.uniform(-4e-4, 4e-4, times.size)
    force = _force_on_surface(presses, times) + rng.normal(0.0, 0.002, (times.size, 3))
    force[:, 2] -= bias_n  # a sensor not zeroed
    sensor2world = TIP_YAW @ SENSOR2TIP[:3, :3]
    reaction = -force @ sensor2world  # = (sensor2world.T @ -f) row by row
    for t, f in zip(times, reaction, strict=True):
        put("/ft_sensor/wrench", "geometry_msgs/msg/WrenchStamped", {
            "header": _header(t, "ft_sensor"),
            "wrench": {"force": dict(zip("xyz", f.tolist(), strict=True)),
                       "torque": {"x": 0.0, "y": 0.0, "z": 0.0}}}, t)  # fmt: skip
    writer.finish()
    return presses


def copy_to_db3(bag: Path, db3: Path) -> Path:
    """Write every message of ``bag`` (an MCAP written by :func:`write_raw_bag`), in its order,
    as the lone sqlite3 file ``db3`` (``NAME.db3``) with rosbags' rosbag2 writer, not
    deformap's: its topics, types, definitions (rosbags' Humble typestore) and log times.
    Returns ``db3``."""
    import shutil
    import tempfile

    from rosbags.rosbag2 import Reader, Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with tempfile.TemporaryDirectory(dir=db3.parent) as tmp:
        staging = Path(tmp) / "rosbag2"  # the writer makes a rosbag2 folder around the .db3
        with Reader(bag) as reader, Writer(staging, version=8,
                                           storage_plugin=StoragePlugin.SQLITE3) as writer:
            conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store)
                     for c in reader.connections}  # fmt: skip
            for conn, log_time, data in reader.messages():
                writer.write(conns[conn.id], log_time, data)
        shutil.move(staging / "rosbag2.db3", db3)
    return db3


def raw_settings(session: RecordedSession, **extra: Any) -> dict[str, Any]:
    """The YAML beside the bag: this rig's frames, the live run's workspace, the world's probe."""
    ws = session.workspace
    return {"tip_frame": "probe_tip", "observation_frames": 3,
            "workspace_lower": list(ws.lower), "workspace_upper": list(ws.upper),
            "hull": [{"shape": "cap", "size_m": [0.02, 0.02, 0.02]},
                     {"shape": "cylinder", "center_m": [0, 0, 0.05], "size_m": [0.016, 0.016, 0.1]},
                     {"shape": "box", "center_m": [0, 0, 0.15], "size_m": [0.085, 0.065, 0.105]}],
            **extra}  # fmt: skip

