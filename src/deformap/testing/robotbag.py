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

from deformap.replay import (
    APPROACH,
    FIRST_PRESS_S,
    HOLD,
    PAUSE,
    RAMP,
    RELEASE,
    T0_NS,
    RawPress,
    RecordedSession,
    RigConfig,
    raw_messages,
    raw_timeline,
)

__all__ = ["APPROACH", "FIRST_PRESS_S", "HOLD", "MSGDEFS", "PAUSE", "RAMP", "RELEASE", "T0_NS",
           "TEST_RIG", "RawPress", "copy_to_db3", "raw_settings", "write_raw_bag"]

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

#: The rig these tests record: a 2 mN sensor, the tip frame named ``probe_tip``.
TEST_RIG = RigConfig(force_noise_n=(0.002, 0.002, 0.002), tip_frame="probe_tip", colors=False)


def write_raw_bag(path: Path, session: RecordedSession, *, seed: int = 0,
                  drop: tuple[str, ...] = (), camera_gap_s: tuple[float, float] | None = None,
                  tf_gap_s: tuple[float, float] | None = None, bias_n: float = 0.0,
                  camera_hz: float = 30.0, tf_hz: float = 50.0, wrench_hz: float = 500.0,
                  chunk_size: int = 1024 * 1024, compression: str = "zstd",
                  colors: bool = False, rig: RigConfig | None = None) -> list[RawPress]:  # fmt: skip
    """Write ``session``'s presses as a robot's drivers record them; return the timeline.

    ``drop`` leaves topics out; ``camera_gap_s`` and ``tf_gap_s`` leave out the camera's frames
    or the arm's transforms stamped within a span [s]; ``bias_n`` offsets the sensor's z (a
    sensor not zeroed); the rates are the camera's, the arm's ``/tf`` and the force sensor's
    [Hz]; ``chunk_size`` and ``compression`` (``"zstd"``, ``"lz4"`` or ``"none"``) the writer's
    chunks', each with its CRC-32. The packed ``rgb`` field is grey, or with ``colors`` the
    session clouds' own colours (which they must have), rounded to 8 bits a channel. ``rig``
    replaces :data:`TEST_RIG` (then the rates, ``bias_n`` and ``colors`` are its own).
    """
    import mcap_ros2.writer as mcap_ros2_writer
    from mcap.writer import CompressionType

    observation = session.observation()
    presses = [session.press_observation(i) for i in range(len(session))]
    if rig is None:
        if colors and (observation.colors is None or any(p.cloud.colors is None for p in presses)):
            raise ValueError("`colors=True` needs a session whose clouds have colours")
        rig = dataclasses.replace(TEST_RIG, camera_hz=camera_hz, tf_hz=tf_hz,
                                  wrench_hz=wrench_hz, force_bias_n=bias_n, colors=colors)
    writer = mcap_ros2_writer.Writer(str(path), chunk_size=chunk_size,
                                     compression=CompressionType[compression.upper()])
    schemas = {name: writer.register_msgdef(name, text) for name, text in MSGDEFS.items()}
    gaps = {rig.cloud_topic: camera_gap_s, "/tf": tf_gap_s}
    for msg in raw_messages(observation, presses, rig, seed=seed):
        gap = gaps.get(msg.topic)
        t_s = (msg.log_time_ns - T0_NS) / 1e9
        if msg.topic in drop or (gap is not None and gap[0] <= t_s <= gap[1]):
            continue
        writer.write_message(msg.topic, schemas[msg.msgtype], msg.fields,
                             log_time=msg.log_time_ns)  # fmt: skip
    writer.finish()
    return raw_timeline(presses)


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

