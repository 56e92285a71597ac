"""A damaged raw bag (``deformap map BAG``) is refused with one line naming the bag: what the raw
bag's seeded mutants in ``benchmarks/robustness.py`` found (issue 14).

- A chunk whose compressed bytes are damaged made zstd raise its own ``ZstdError`` (a traceback);
  lz4 raises a ``RuntimeError``.
- rosbags checks each chunk's CRC but not the footer's CRC of the summary section (schemas,
  channels, chunk indexes, statistics), nor the ``DataEnd`` record's CRC of the data section: a
  chunk index repeated in the summary read every message of that chunk twice, as other data.
- A wrench of 1e200 N or a quaternion component of 1e200 overflowed when squared (a
  RuntimeWarning, then a force of inf); both are damaged messages, refused at once.
- A raw press refused by the contact check named ``BAG/session.yaml: poke 0``, a file that does
  not exist, instead of the bag and the press numbered from 1.

The sqlite3 form (``.db3``, written from the MCAP by rosbags' writer) found, before the fixes:
- a ``topics`` row whose QoS profiles are not YAML refused with the YAML parser's message of
  four lines (every damaged bag's message is now one line);
- a message row whose data is a number (sqlite3 stores any type in any column) taken as that
  many zero bytes, ``bytes(10**12)`` asking for a terabyte (a MemoryError), and text or a real
  refused with Python's words for a conversion (``string argument without an encoding``);
- an observation whose camera frame has no transform (``/tf_static`` lost) refused without
  naming the bag.
"""

from __future__ import annotations

import dataclasses
import re
import struct
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("mcap_ros2.writer")

from deformap.environment import ForceTravel
from deformap.errors import FileFormatError
from deformap.replay import load_raw_bag, load_raw_config, load_session
from deformap.testing.robotbag import raw_settings, write_raw_bag

_MAGIC = b"\x89MCAP0\r\n"


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory, make_synthetic: Any,
            write_synthetic: Any) -> Any:  # fmt: skip
    syn = make_synthetic(n_points=300)
    record = ForceTravel(travel_m=np.linspace(0.0, 0.006, 9), force_n=np.linspace(0.02, 1.0, 9))
    syn.presses[1] = dataclasses.replace(syn.presses[1], force_travel=record)  # it had none
    return load_session(write_synthetic(tmp_path_factory.mktemp("syn") / "s", syn).parent)


def _bag(folder: Path, session: Any, **kwargs: Any) -> Path:
    bag = folder / "lab.mcap"
    write_raw_bag(bag, session, camera_hz=15.0, tf_hz=25.0, wrench_hz=100.0,
                  chunk_size=16 * 1024, **kwargs)  # fmt: skip
    settings = raw_settings(session, force_n=1.0)
    bag.with_name("lab.deformap.yaml").write_text(yaml.safe_dump(settings))
    return bag


def _open(bag: Path) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an overflow is a defect too
        return load_raw_bag(bag, load_raw_config(bag), default_force_n=1.0)


def _records(data: bytes) -> list[tuple[int, int, int]]:
    """``(opcode, start, end)`` of every MCAP record."""
    out, at = [], len(_MAGIC)
    while at + 9 <= len(data) - len(_MAGIC):
        (length,) = struct.unpack_from("<Q", data, at + 1)
        out.append((data[at], at, at + 9 + length))
        at += 9 + length
    return out


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_a_damaged_compressed_chunk_is_refused_naming_the_bag(
        session: Any, tmp_path: Path, compression: str) -> None:  # fmt: skip
    bag = _bag(tmp_path, session, compression=compression)
    data = bytearray(bag.read_bytes())
    _, start, end = next(r for r in _records(bytes(data)) if r[0] == 0x06)  # a chunk
    for at in range(start + 80, end - 8, 97):  # bytes of its compressed records
        data[at] ^= 0x5A
    bag.write_bytes(bytes(data))
    with pytest.raises(FileFormatError) as info:
        _open(bag)
    assert str(bag) in str(info.value) and "\n" not in str(info.value)


def test_a_repeated_chunk_index_fails_the_summary_crc(session: Any, tmp_path: Path) -> None:
    bag = _bag(tmp_path, session)
    data = bag.read_bytes()
    _, start, end = next(r for r in _records(data) if r[0] == 0x08)  # a chunk index
    bag.write_bytes(data[:end] + data[start:end] + data[end:])  # repeated, offsets kept
    # the footer's summary_start still points at the summary: only the CRC tells
    with pytest.raises(FileFormatError, match=r"lab\.mcap: the MCAP summary section .* fails its "
                                              r"CRC-32: expected 0x[0-9a-f]{8} \(the footer's\)"):
        _open(bag)


def test_a_damaged_data_section_fails_its_crc_where_one_was_written(tmp_path: Path) -> None:
    from mcap.writer import Writer

    from deformap.cloud.io import iter_bag_messages
    from deformap.testing.robotbag import MSGDEFS

    bag = tmp_path / "crc.mcap"
    with bag.open("wb") as fh:
        writer = Writer(fh, enable_data_crcs=True)
        writer.start(profile="ros2", library="test")
        kind = "geometry_msgs/msg/WrenchStamped"
        schema = writer.register_schema(kind, "ros2msg", MSGDEFS[kind].encode())
        channel = writer.register_channel("/w", "cdr", schema)
        writer.add_message(channel, 1, b"\x00\x01\x00\x00" + bytes(72), 1)
        writer.finish()
    data = bytearray(bag.read_bytes())
    _, start, _ = next(r for r in _records(bytes(data)) if r[0] == 0x07)  # a message index
    data[start + 12] ^= 0x01  # outside every chunk, and rosbags does not read it
    bag.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match=r"the MCAP data section fails its CRC-32"):
        list(iter_bag_messages(bag, {"/w": kind}))


def test_a_wrench_beyond_any_sensor_is_refused_without_overflow(session: Any,
                                                                tmp_path: Path) -> None:  # fmt: skip
    bag = _bag(tmp_path, session, bias_n=1e200)
    with pytest.raises(FileFormatError, match=r"\[/ft_sensor/wrench message 1\]: "
                                              r"force .* N: expected finite components within "
                                              r"±1e\+06 N"):
        _open(bag)


def test_a_quaternion_of_1e200_is_refused_without_overflow() -> None:
    from types import SimpleNamespace as NS

    from deformap.cloud.io import TransformTree

    tf = NS(header=NS(stamp=NS(sec=0, nanosec=0), frame_id="world"), child_frame_id="tool",
            transform=NS(translation=NS(x=0.0, y=0.0, z=0.0),
                         rotation=NS(x=1e200, y=0.0, z=0.0, w=1.0)))  # fmt: skip
    tree = TransformTree("/tf", tolerance_ns=50_000_000)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(FileFormatError, match=r"m0: transform 'world' -> 'tool' must have "
                                                  r"a finite translation within 1e\+09 m"):
            tree.add(NS(transforms=[tf]), static=False, where="m0")
    tf.transform.rotation.x, tf.transform.translation.x = 0.0, 1e300
    with pytest.raises(FileFormatError, match=r"got translation \(1e\+300, 0.0, 0.0\)"):
        tree.add(NS(transforms=[tf]), static=False, where="m0")


def test_a_raw_press_refused_by_the_contact_check_names_the_bag(session: Any,
                                                                tmp_path: Path) -> None:  # fmt: skip
    bag = _bag(tmp_path, session)
    raw = load_raw_bag(bag, load_raw_config(bag), default_force_n=1.0, contact_gap_m=1e-9)
    with pytest.raises(FileFormatError) as info:
        raw.press_observation(0)
    message = str(info.value)
    assert message.startswith(f"{bag}: press 1") and "session.yaml" not in message


def _db3(folder: Path, session: Any) -> Path:
    """The raw bag as a lone ``.db3`` beside its settings, written by rosbags' writer."""
    pytest.importorskip("rosbags")
    from deformap.testing.robotbag import copy_to_db3

    bag = _bag(folder, session)
    return copy_to_db3(bag, bag.with_suffix(".db3"))


def _sql(bag: Path, statement: str, *args: Any) -> None:
    import sqlite3

    conn = sqlite3.connect(bag)
    try:
        conn.execute(statement, args)
        conn.commit()
    finally:
        conn.close()


def test_a_db3_bag_reads_as_its_mcap(session: Any, tmp_path: Path) -> None:
    db3 = _db3(tmp_path, session)
    raw, mcap = _open(db3), _open(db3.with_suffix(".mcap"))
    assert len(raw) == len(mcap) == 3
    np.testing.assert_array_equal(raw.observation().points, mcap.observation().points)


def test_a_db3_topic_whose_qos_is_not_yaml_is_refused_on_one_line(session: Any,
                                                                  tmp_path: Path) -> None:  # fmt: skip
    bag = _db3(tmp_path, session)
    _sql(bag, "UPDATE topics SET offered_qos_profiles = '[' WHERE name = '/tf'")
    with pytest.raises(FileFormatError) as info:
        _open(bag)
    message = str(info.value)
    assert message.startswith(f"{bag}: could not read the bag: ReaderError: ")
    assert "offered_qos_profiles" in message and "\n" not in message


@pytest.mark.parametrize(("column", "value", "expected"), [
    ("data", 10**12, r"expected its data as bytes; got int '1000000000000'"),
    ("data", "text", r"expected its data as bytes; got str 'text'"),
    ("data", 2.5, r"expected its data as bytes; got float '2.5'"),
    ("timestamp", "x", r"expected an integer log time \[ns\]; got str 'x'"),
])  # fmt: skip
def test_a_db3_message_of_another_sql_type_is_refused_naming_it(
        session: Any, tmp_path: Path, column: str, value: Any, expected: str) -> None:  # fmt: skip
    bag = _db3(tmp_path, session)
    _sql(bag, f"UPDATE messages SET {column} = ? WHERE id = (SELECT max(messages.id) FROM "
              "messages JOIN topics ON topic_id = topics.id WHERE name = '/ft_sensor/wrench')",
         value)  # fmt: skip
    with pytest.raises(FileFormatError, match=rf"^{re.escape(str(bag))} \[/ft_sensor/wrench "
                                              rf"message \d+\]: {expected}$"):
        _open(bag)


def test_an_observation_without_its_camera_transform_names_the_bag(session: Any,
                                                                   tmp_path: Path) -> None:  # fmt: skip
    bag = _bag(tmp_path, session, drop=("/tf_static",))
    with pytest.raises(FileFormatError) as info:
        _open(bag)
    # refused once, as the bag is opened: every frame missing, and the frames there are
    assert str(info.value).startswith(f"{bag}: not on '/tf' or '/tf_static': the world frame "
                                      "'world' (--world-frame), the camera frame "
                                      "'camera_depth_optical_frame'")
    assert str(info.value).endswith("the frames there: ['base_link', 'tool0']")


@pytest.mark.parametrize("edit", [
    "DELETE FROM messages WHERE id = (SELECT max(id) FROM messages WHERE topic_id = "
    "(SELECT id FROM topics WHERE name = '/tf'))",
    "INSERT INTO messages(topic_id, timestamp, data) SELECT topic_id, timestamp, data "
    "FROM messages WHERE id = (SELECT min(id) FROM messages WHERE topic_id = "
    "(SELECT id FROM topics WHERE name = '/tf'))",
])
def test_a_db3_row_lost_or_repeated_is_told_by_the_bags_own_counts(
        session: Any, tmp_path: Path, edit: str) -> None:
    """sqlite3 keeps no checksum; the message counts rosbag2 leaves in the bag's metadata table
    tell a lost or repeated row (it reads as other data otherwise)."""
    bag = _db3(tmp_path, session)
    _open(bag)  # as written: the counts agree
    _sql(bag, edit)
    with pytest.raises(FileFormatError) as info:
        _open(bag)
    message = str(info.value)
    assert message.startswith(f"{bag}: topic '/tf' holds") and "metadata says" in message
    assert len(message.splitlines()) == 1


def test_a_db3_whose_metadata_is_not_rosbag2_yaml_is_refused_on_one_line(
        session: Any, tmp_path: Path) -> None:
    bag = _db3(tmp_path, session)
    _sql(bag, "UPDATE metadata SET metadata = ?", "rosbag2_bagfile_information: [\n  1")
    with pytest.raises(FileFormatError) as info:
        _open(bag)
    assert "metadata table's YAML" in str(info.value)
    assert len(str(info.value).splitlines()) == 1
