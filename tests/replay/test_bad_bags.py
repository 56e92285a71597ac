"""Broken bag-form sessions: missing topics, wrong types, mismatched frames, damaged files."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("rosbags")

from rosbags.rosbag2 import StoragePlugin, Writer

from deformap.cloud.io import (
    array_to_pointcloud2,
    pointcloud2_structured,
    typestore,
    wrench_message,
)
from deformap.environment import ForceTravel
from deformap.errors import ConfigError, FileFormatError
from deformap.replay import OPTIONAL_TOPICS, TOPICS, load_session
from deformap.replay._bagform import _point_message, force_travel_message


def _write_variant(
    path: Path,
    syn: Any,
    *,
    cloud_frame: str = "world",
    wrench_frame: str = "world",
    omit: tuple[str, ...] = (),
    retype: dict[str, str] | None = None,
    skip_poke: dict[str, int] | None = None,
    static_cam2world: np.ndarray | None = None,
    repeat: dict[str, Any] | None = None,
    records: dict[int, list[Any]] | None = None,
    record_type: str = OPTIONAL_TOPICS["force_travel"][1],
) -> None:
    """A bag like write_session's, with one thing changed; poke i is stamped (i + 1) s.

    ``records`` maps a poke index to the messages to log on the force–travel topic at its stamp
    (without it, the bag has no such topic).
    """
    store = typestore()
    retype = retype or {}
    skip_poke = skip_poke or {}
    repeat = repeat or {}  # topic key -> a second message with the same stamp, made from the first
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {}
        for key, (topic, msgtype) in TOPICS.items():
            if key not in omit:
                conns[key] = writer.add_connection(topic, retype.get(key, msgtype), typestore=store)

        def put(key: str, stamp: int, msg: Any) -> None:
            if key in retype:
                vec = store.types["geometry_msgs/msg/Vector3"](x=1.0, y=2.0, z=3.0)
                msg = store.types[retype[key]](header=msg.header, vector=vec)
            if key in conns and skip_poke.get(key) != stamp:
                writer.write(conns[key], stamp, store.serialize_cdr(msg, conns[key].msgtype))
            if key in repeat and (key == "observation" or stamp == 2 * 10**9):
                again = store.serialize_cdr(repeat[key](msg), conns[key].msgtype)
                writer.write(conns[key], stamp + 1, again)

        world2cam = np.eye(4) if static_cam2world is None else np.linalg.inv(static_cam2world)
        obs = syn.observation.transformed(world2cam, cloud_frame)
        put("observation", 0, array_to_pointcloud2(obs.points, frame_id=cloud_frame,
                                                   dtype="float64"))  # fmt: skip
        for i, press in enumerate(syn.presses):
            stamp = (i + 1) * 10**9
            cloud = press.cloud.transformed(world2cam, cloud_frame)
            put("cloud", stamp, array_to_pointcloud2(cloud.points, frame_id=cloud_frame,
                                                     stamp_ns=stamp, dtype="float64"))  # fmt: skip
            wrench = wrench_message(stamp, "world", press.contact.force, np.zeros(3))
            wrench.header.frame_id = wrench_frame
            put("wrench", stamp, wrench)
            put("tip", stamp, _point_message(stamp, press.contact.tip_center))
            put("robot", stamp, array_to_pointcloud2(press.robot_points, stamp_ns=stamp,
                                                     dtype="float64"))  # fmt: skip
        if records is not None:
            conn = writer.add_connection(OPTIONAL_TOPICS["force_travel"][0], record_type,
                                         typestore=store)  # fmt: skip
            for i, msgs in records.items():
                for msg in msgs:
                    writer.write(conn, (i + 1) * 10**9, store.serialize_cdr(msg, record_type))
        if static_cam2world is not None:
            from deformap.cloud.io._bag import _tf_message

            conn = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=store)
            msg = _tf_message([("world", cloud_frame, static_cam2world)])
            writer.write(conn, 0, store.serialize_cdr(msg, "tf2_msgs/msg/TFMessage"))


@pytest.fixture
def bag_session(tmp_path: Path, synthetic, write_synthetic) -> Path:  # type: ignore[no-untyped-def]
    return write_synthetic(tmp_path / "s", synthetic, format="mcap", sealed=False).parent  # type: ignore[no-any-return]


def _replace_bag(folder: Path, syn: Any, **kwargs: Any) -> None:
    shutil.rmtree(folder / "bag")
    _write_variant(folder / "bag", syn, **kwargs)


def _edit(folder: Path, **changes: Any) -> None:
    file = folder / "session.yaml"
    doc = yaml.safe_load(file.read_text())
    doc.update(changes)
    file.write_text(yaml.safe_dump(doc))


def test_variant_writer_matches_write_session(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic)
    session = load_session(bag_session)
    for i in range(len(session)):
        assert np.array_equal(session.press_observation(i).cloud.points,
                              synthetic.presses[i].cloud.points)  # fmt: skip
        assert session.press_observation(i).force_travel is None  # a bag without the topic


@pytest.mark.parametrize("key", list(TOPICS))
def test_missing_topic(bag_session: Path, synthetic, key: str) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, omit=(key,))
    with pytest.raises(FileFormatError, match=f"bag has no topic '{TOPICS[key][0]}'"):
        load_session(bag_session)


def test_wrong_message_type(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, retype={"tip": "geometry_msgs/msg/Vector3Stamped"})
    with pytest.raises(
        FileFormatError,
        match="'/deformap/press/tip' carries "
        "geometry_msgs/msg/Vector3Stamped, expected geometry_msgs/msg/PointStamped",
    ):
        load_session(bag_session)


def test_cloud_frame_mismatch(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, cloud_frame="camera")
    session = load_session(bag_session)
    with pytest.raises(
        FileFormatError,
        match=r"/deformap/observation\].*frame_id is 'camera' but "
        "the session's frame is 'world'",
    ):
        session.observation()
    with pytest.raises(FileFormatError, match=r"/deformap/press/cloud stamped 2000000000\]"):
        session.press_observation(1)


def test_wrench_frame_must_be_world(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, wrench_frame="ft_sensor")
    with pytest.raises(FileFormatError, match=r"wrench stamped 1000000000.*'ft_sensor'"):
        load_session(bag_session).press_observation(0)


def test_camera_frame_through_tf_static(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    cam2world = np.eye(4)
    cam2world[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    cam2world[:3, 3] = [0.3, 0.2, 1.0]
    _replace_bag(bag_session, synthetic, cloud_frame="camera", static_cam2world=cam2world)
    _edit(bag_session, frame="camera", cam2world="tf_static")
    session = load_session(bag_session)
    np.testing.assert_allclose(session.observation().points, synthetic.observation.points,
                               atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(session.press_observation(2).cloud.points,
                               synthetic.presses[2].cloud.points, atol=1e-9)  # fmt: skip
    # the same matrix given in session.yaml
    _edit(bag_session, cam2world=cam2world.tolist())
    np.testing.assert_allclose(load_session(bag_session).observation().points,
                               synthetic.observation.points, atol=1e-9)  # fmt: skip


def test_poke_without_its_message_breaks_only_that_poke(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, skip_poke={"robot": 2 * 10**9})
    session = load_session(bag_session)
    session.press_observation(0)
    with pytest.raises(
        FileFormatError, match="'/deformap/press/robot' has no message stamped 2000000000"
    ):
        session.press_observation(1)
    session.press_observation(2)


def _shifted(msg: Any) -> Any:
    """The same cloud 2 cm higher, under the same header stamp."""
    table = pointcloud2_structured(msg).copy()
    table["z"] += 0.02
    msg.data = table.view(np.uint8)
    return msg


def test_two_messages_with_one_stamp_are_refused_not_one_silently_kept(
    bag_session: Path, synthetic
) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, repeat={"cloud": _shifted})
    session = load_session(bag_session)
    session.press_observation(0)
    with pytest.raises(
        FileFormatError, match="'/deformap/press/cloud' has 2 messages stamped 2000000000"
    ):
        session.press_observation(1)
    session.press_observation(2)
    _replace_bag(bag_session, synthetic, repeat={"observation": _shifted})
    # two unorganised clouds have no pixels to average: refused, not one of them kept
    with pytest.raises(FileFormatError, match="2 messages; several are averaged pixel by pixel"):
        load_session(bag_session).observation()


def test_two_pokes_with_one_stamp_are_refused(bag_session: Path) -> None:
    doc = yaml.safe_load((bag_session / "session.yaml").read_text())
    doc["pokes"][2]["stamp_ns"] = doc["pokes"][0]["stamp_ns"]
    (bag_session / "session.yaml").write_text(yaml.safe_dump(doc))
    session = load_session(bag_session)
    session.press_observation(0)
    with pytest.raises(ConfigError, match=r"`pokes\[2\].stamp_ns` .*already .*`pokes\[0\]`"):
        session.press_observation(2)


def test_sidecar_stamp_not_in_bag(bag_session: Path) -> None:
    doc = yaml.safe_load((bag_session / "session.yaml").read_text())
    doc["pokes"][2]["stamp_ns"] = 5
    (bag_session / "session.yaml").write_text(yaml.safe_dump(doc))
    session = load_session(bag_session)
    with pytest.raises(FileFormatError, match="has no message stamped 5"):
        session.press_observation(2)
    session.press_observation(1)


def test_bag_form_poke_keys_are_strict(bag_session: Path) -> None:
    doc = yaml.safe_load((bag_session / "session.yaml").read_text())
    doc["pokes"][0]["tip_center"] = [0, 0, 0]
    (bag_session / "session.yaml").write_text(yaml.safe_dump(doc))
    with pytest.raises(ConfigError, match=r"`pokes\[0\]` has unknown key\(s\) \['tip_center'\]"):
        load_session(bag_session)


def test_missing_and_truncated_bag(bag_session: Path) -> None:
    mcap = next((bag_session / "bag").glob("*.mcap"))
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) // 3])
    with pytest.raises(FileFormatError, match="bag"):
        session = load_session(bag_session)
        session.observation()
        for i in range(len(session)):
            session.press_observation(i)
    shutil.rmtree(bag_session / "bag")
    with pytest.raises(FileFormatError, match="no such bag"):
        load_session(bag_session)
    doc = yaml.safe_load((bag_session / "session.yaml").read_text())
    doc["bag"] = "a" * 300  # over NAME_MAX (255)
    (bag_session / "session.yaml").write_text(yaml.safe_dump(doc))
    with pytest.raises(FileFormatError, match="File name too long"):
        load_session(bag_session)


# -- the force–travel record on its optional topic ----------------------------------------------
def _record_message(travel: Any, force: Any, dims: tuple[str, str] | None = None) -> Any:
    record = ForceTravel(travel_m=[0.0, 0.001, 0.002], force_n=[0.02, 0.5, 1.0])
    msg = force_travel_message(record)
    msg.data = np.column_stack([travel, force]).ravel().astype(float)
    msg.layout.dim[0].size = len(travel)
    if dims is not None:
        msg.layout.dim[0].label, msg.layout.dim[1].label = dims
    return msg


GOOD = ([0.0, 0.001, 0.002, 0.003], [0.02, 0.4, 0.7, 1.0])


def test_bag_records_are_read_per_poke(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    _replace_bag(bag_session, synthetic, records={0: [_record_message(*GOOD)]})
    session = load_session(bag_session)
    got = session.press_observation(0).force_travel
    assert got == ForceTravel(travel_m=GOOD[0], force_n=GOOD[1])
    assert session.press_observation(1).force_travel is None  # no message for that poke
    assert session.press_observation(2).force_travel is None


@pytest.mark.parametrize(
    ("messages", "match"),
    [
        ([_record_message([0.0, np.nan, 0.002, 0.003], GOOD[1])], "`travel_m`.*NaN or infinite"),
        ([_record_message(GOOD[0], [0.02, 0.4, 0.7, 1.0], dims=("rows", "cols"))],
         "layout must be 'samples'"),
        ([_record_message([0.0, 0.001], [0.02, 1.0])], "`travel_m` must have at least 3"),
        ([_record_message(GOOD[0], GOOD[1][::-1])], "`force_n` must rise"),
        ([_record_message([0.0, 3.0, 2.0, 4.0], GOOD[1])], "`travel_m` must be metres"),
        ([_record_message([0.0, 0.003, 0.001, 0.003], GOOD[1])], "must not go backwards"),
        ([_record_message(*GOOD), _record_message(*GOOD)], "2 messages"),
        ([_record_message(GOOD[0], [0.02, 0.1, 0.2, 0.4])], "`force_travel` must end at"),
    ],
)
def test_bad_bag_record_breaks_only_its_poke(bag_session: Path, synthetic, messages: list[Any],  # type: ignore[no-untyped-def]
                                             match: str) -> None:  # fmt: skip
    _replace_bag(bag_session, synthetic, records={1: messages})
    session = load_session(bag_session)
    with pytest.raises(FileFormatError, match=match):
        session.press_observation(1)
    session.press_observation(0)
    session.press_observation(2)


def test_bag_record_topic_of_another_type_is_refused_at_load(bag_session: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    store = typestore()
    msg = store.types["std_msgs/msg/Float32MultiArray"](
        layout=_record_message(*GOOD).layout, data=np.zeros(8, dtype=np.float32))
    _replace_bag(bag_session, synthetic, records={0: [msg]},
                 record_type="std_msgs/msg/Float32MultiArray")
    with pytest.raises(FileFormatError, match="force_travel' carries std_msgs/msg/Float32"):
        load_session(bag_session)
