"""Bag-form sessions as other tools write them: a clock skew between topics (`--stamp-tolerance`,
nearest stamps, the gap reported, bounded), and a wrench or tip in a frame the bag's
`/tf_static` takes to the world."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from deformap.cli import app
from deformap.errors import DeformapError, FileFormatError, InvalidArgumentError
from deformap.replay import load_session

pytest.importorskip("rosbags")
runner = CliRunner()

SKEW_NS = 1_500_000  # 1.5 ms


def _rewrite(bag: Path, edit: Callable[[str, Any], Any], static: list[Any] | None = None,
             moving: list[Any] | None = None) -> None:
    """Copy ``bag`` message by message through ``edit(topic, msg)``, with ``static``
    ``(parent, child, 4×4)`` transforms on ``/tf_static`` and ``moving`` ``(stamp_ns, parent,
    child, 4×4)`` ones on ``/tf``; replace it."""
    from rosbags.rosbag2 import Reader

    from deformap.cloud.io import bag_writer, typestore
    from deformap.cloud.io._bag import _tf_message

    store, new = typestore(), bag.with_name("rewritten")
    with Reader(bag) as reader, bag_writer(new) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store)
                 for c in reader.connections}  # fmt: skip
        for conn, log_time, data in reader.messages():
            msg = edit(conn.topic, store.deserialize_cdr(data, conn.msgtype))
            writer.write(conns[conn.id], log_time, store.serialize_cdr(msg, conn.msgtype))
        if static:
            tf = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=store)
            writer.write(tf, 0, store.serialize_cdr(_tf_message(static),
                                                    "tf2_msgs/msg/TFMessage"))
        if moving:
            tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
            for stamp, parent, child, matrix in moving:
                msg = _tf_message([(parent, child, matrix)])
                msg.transforms[0].header.stamp.sec = stamp // 10**9
                msg.transforms[0].header.stamp.nanosec = stamp % 10**9
                writer.write(tf, stamp, store.serialize_cdr(msg, "tf2_msgs/msg/TFMessage"))
    shutil.rmtree(bag)
    new.rename(bag)


def _session(tmp_path: Path, write_synthetic: Any, synthetic: Any) -> Path:
    folder = tmp_path / "session"
    write_synthetic(folder, synthetic, sealed=False, format="mcap")
    return folder


def _skew(topic: str, msg: Any) -> Any:
    if topic == "/deformap/press/wrench":
        stamp = msg.header.stamp
        ns = int(stamp.sec) * 10**9 + int(stamp.nanosec) + SKEW_NS
        stamp.sec, stamp.nanosec = ns // 10**9, ns % 10**9
    return msg


def test_a_skewed_clock_needs_the_tolerance_and_reports_the_gap(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    folder = _session(tmp_path, write_synthetic, synthetic)
    exact = load_session(folder)
    want = [exact.press_observation(i).contact.force for i in range(len(exact))]
    _rewrite(folder / "bag", _skew)
    with pytest.raises(FileFormatError, match="no message stamped"):
        load_session(folder).press_observation(0)
    session = load_session(folder, stamp_tolerance_s=0.002)
    for i in range(len(session)):
        np.testing.assert_array_equal(session.press_observation(i).contact.force, want[i])
        assert session.poke_notes(i)["stamp_gaps_s"] == {"/deformap/press/wrench": 0.0015}
    assert session.source["presses"]["1"]["stamp_gaps_s"] == {"/deformap/press/wrench": 0.0015}
    with pytest.raises(FileFormatError, match=r"or within 0.001 s \(--stamp-tolerance\)"):
        load_session(folder, stamp_tolerance_s=0.001).press_observation(0)


def test_a_tolerance_that_joins_pokes_is_refused_and_a_folder_takes_none(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    folder = _session(tmp_path, write_synthetic, synthetic)
    with pytest.raises(InvalidArgumentError, match="half-way from one poke's stamp to the next"):
        load_session(folder, stamp_tolerance_s=1e9)
    plain = tmp_path / "plain"
    write_synthetic(plain, synthetic)
    with pytest.raises(InvalidArgumentError, match="applies to bags"):
        load_session(plain, stamp_tolerance_s=0.01)


def test_map_takes_the_stamp_tolerance_for_a_session(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    folder = _session(tmp_path, write_synthetic, synthetic)
    _rewrite(folder / "bag", _skew)
    out = tmp_path / "map"
    result = runner.invoke(app, ["map", str(folder), "--out", str(out), "--no-figures",
                                 "--stamp-tolerance", "0.002"])  # fmt: skip
    assert result.exit_code == 0, result.output
    report = json.loads((out / "report.json").read_text())
    assert report["skipped"] == [] and len(report["pokes"]) == len(synthetic.presses)
    assert report["source"]["presses"]["1"]["stamp_gaps_s"] == {"/deformap/press/wrench": 0.0015}
    result = runner.invoke(app, ["map", str(folder), "--out", str(tmp_path / "m2"),
                                 "--stamp-tolerance", "1e9"])  # fmt: skip
    assert result.exit_code == 2 and "--stamp-tolerance 1e+09 s" in result.output


def _into_sensor(topic: str, msg: Any, sensor2world: np.ndarray) -> Any:
    """A press's wrench (rotated) or tip (moved) given in the frame ``ft_sensor`` at
    ``sensor2world`` instead of ``world``; other messages as they are."""
    if topic in ("/deformap/press/wrench", "/deformap/press/tip"):
        inv = np.linalg.inv(sensor2world)
        v = msg.wrench.force if topic.endswith("wrench") else msg.point
        v.x, v.y, v.z = inv[:3, :3] @ [v.x, v.y, v.z] + (inv[:3, 3] if topic.endswith("tip") else 0)
        msg.header.frame_id = "ft_sensor"
    return msg


def _assert_contacts(folder: Path, want: list[Any]) -> None:
    session = load_session(folder)
    for i in range(len(session)):
        got = session.press_observation(i).contact
        np.testing.assert_allclose(got.force, want[i].force, atol=1e-9)
        np.testing.assert_allclose(got.tip_center, want[i].tip_center, atol=1e-9)


def test_a_wrench_and_tip_in_a_frame_of_tf_static_are_taken_to_the_world(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    from scipy.spatial.transform import Rotation

    folder = _session(tmp_path, write_synthetic, synthetic)
    exact = load_session(folder)
    want = [exact.press_observation(i).contact for i in range(len(exact))]
    sensor2world = np.eye(4)
    sensor2world[:3, :3] = Rotation.from_euler("zx", [30, 180], degrees=True).as_matrix()
    sensor2world[:3, 3] = [0.1, -0.2, 0.3]

    _rewrite(folder / "bag", lambda topic, msg: _into_sensor(topic, msg, sensor2world),
             static=[("world", "ft_sensor", sensor2world)])
    _assert_contacts(folder, want)


def test_a_wrench_and_tip_in_a_moving_sensor_frame_are_taken_to_the_world_by_tf(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    from scipy.spatial.transform import Rotation

    from deformap.cloud.io import header_stamp_ns

    folder = _session(tmp_path, write_synthetic, synthetic)
    exact = load_session(folder)
    want = [exact.press_observation(i).contact for i in range(len(exact))]
    poses: dict[int, np.ndarray] = {}  # the sensor's pose at each press, another each time

    def pose(stamp: int) -> np.ndarray:
        if stamp not in poses:
            m = np.eye(4)
            m[:3, :3] = Rotation.from_euler("zx", [30 + 40 * len(poses), 180], degrees=True
                                            ).as_matrix()
            m[:3, 3] = [0.1 * len(poses), -0.2, 0.3]
            poses[stamp] = m
        return poses[stamp]

    def to_sensor(topic: str, msg: Any) -> Any:
        if topic in ("/deformap/press/wrench", "/deformap/press/tip"):
            return _into_sensor(topic, msg, pose(header_stamp_ns(msg.header)))
        return msg

    _rewrite(folder / "bag", to_sensor, static=[("world", "camera", np.eye(4))],
             moving=[])  # the poses are known only once the messages are read: a second pass
    _rewrite(folder / "bag", lambda topic, msg: msg,
             moving=[(s, "world", "ft_sensor", m) for s, m in poses.items()])
    assert len({round(float(m[0, 3]), 3) for m in poses.values()}) == len(poses) > 1
    _assert_contacts(folder, want)


def test_a_frame_tf_static_does_not_resolve_is_named(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    folder = _session(tmp_path, write_synthetic, synthetic)

    def rename(topic: str, msg: Any) -> Any:
        if topic == "/deformap/press/wrench":
            msg.header.frame_id = "optoforce"
        return msg

    _rewrite(folder / "bag", rename, static=[("world", "camera", np.eye(4))])
    with pytest.raises(DeformapError, match="'optoforce', which the bag's /tf and /tf_static do"):
        load_session(folder).press_observation(0)


def test_an_observation_stream_is_averaged_pixel_by_pixel(
    tmp_path: Path, write_synthetic: Any, synthetic: Any
) -> None:
    from rosbags.rosbag2 import Reader

    from deformap.cloud.io import bag_writer, typestore

    folder = _session(tmp_path, write_synthetic, synthetic)
    want = load_session(folder).observation()
    store, bag, new = typestore(), folder / "bag", folder / "rewritten"
    n = len(want) // 2 * 2  # an even count: two rows
    with Reader(bag) as reader, bag_writer(new) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store)
                 for c in reader.connections}  # fmt: skip
        for conn, log_time, data in reader.messages():
            if conn.topic != "/deformap/observation":
                writer.write(conns[conn.id], log_time, data)
                continue
            for k, dz in enumerate((0.001, -0.001, 0.0)):  # three frames of one scene
                msg = store.deserialize_cdr(data, conn.msgtype)
                step = int(msg.point_step)
                table = np.frombuffer(bytes(msg.data), dtype=np.float64).reshape(-1, step // 8)
                table = table[:n].copy()
                table[:, 2] += dz
                if k == 2:
                    table[::2, :3] = np.nan  # holes in the last frame only
                msg.data = table.view(np.uint8).ravel()
                msg.height, msg.width, msg.row_step = 2, n // 2, step * n // 2
                msg.is_dense = False
                msg.header.stamp.nanosec = k
                writer.write(conns[conn.id], log_time + k,
                             store.serialize_cdr(msg, conn.msgtype))
    shutil.rmtree(bag)
    new.rename(bag)
    got = load_session(folder).observation()
    np.testing.assert_allclose(got.points, want.points[:n], atol=1e-12)
