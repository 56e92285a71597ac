"""The one ROS 2 bag reader: a bag (sqlite3 or MCAP) opened through the optional ``rosbags``
(extra ``ros``), its topics checked, its messages yielded raw in the bag's order.

What rosbags does not check is checked first: the CRC-32s of an MCAP file's summary and data
sections (rosbags checks only each chunk's), and the per-topic message counts in a sqlite3 bag's
``metadata`` table. Whatever rosbags, its drivers or the CDR decoder raise on a damaged bag
(:func:`bag_read_errors`) becomes one :class:`~deformap.errors.FileFormatError` naming the file.
"""

from __future__ import annotations

import importlib
import sqlite3
import struct
import zlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

from deformap._validation import check_path
from deformap.cloud.io._common import path_kind
from deformap.errors import DeformapError, FileFormatError, InvalidArgumentError, missing_extra

__all__ = ["BAG_STORAGES", "ROS_DISTRO", "RawBagMessage", "bag_error_text", "bag_read_errors",
           "bag_topics",
           "header_message", "header_stamp_ns", "iter_bag_messages", "typestore"]


BAG_STORAGES = ("mcap", "sqlite3")

#: The message definitions used to write and, for bags that carry none, read messages. The
#: messages deformap uses (PointCloud2, WrenchStamped, TFMessage) are identical from Humble on.
ROS_DISTRO = "ros2_humble"


def _rosbag2() -> Any:
    try:
        import rosbags.rosbag2 as rosbag2
    except ImportError:
        raise missing_extra("rosbags", "ros", "reading ROS 2 bags") from None
    return rosbag2


@cache
def typestore() -> Any:
    """Return rosbags' typestore for :data:`ROS_DISTRO`, or raise MissingDependencyError."""
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise missing_extra("rosbags", "ros", "reading and writing ROS 2 messages") from None
    return get_typestore(Stores(ROS_DISTRO))


def header_message(stamp_ns: int, frame_id: str) -> Any:
    """A ``std_msgs/msg/Header`` of ``stamp_ns`` [ns] and ``frame_id``."""
    types = typestore().types
    time = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    return types["std_msgs/msg/Header"](stamp=time, frame_id=frame_id)


def header_stamp_ns(header: Any) -> int:
    """The stamp [ns] of a ``std_msgs/msg/Header``."""
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


@cache
def bag_read_errors() -> tuple[type[BaseException], ...]:
    """What rosbags, its SQLite drivers (``apsw``'s errors included), the MCAP chunk
    decompressors (zstd's ``ZstdError``, lz4's ``RuntimeError``) and the CDR decoder raise on a
    damaged bag (a corrupted length may ask for an absurd allocation: MemoryError)."""
    from rosbags.serde import SerdeError

    errors: list[type[BaseException]] = [
        _rosbag2().ReaderError, SerdeError, sqlite3.Error, OSError, ValueError, KeyError,
        IndexError, TypeError, AssertionError, EOFError, struct.error, MemoryError,
        OverflowError, UnicodeDecodeError, RuntimeError]  # fmt: skip
    # the zstd module rosbags uses, whichever is installed, and apsw if it is
    for module, name in (("compression.zstd", "ZstdError"), ("backports.zstd", "ZstdError"),
                         ("apsw", "Error")):  # fmt: skip
        try:
            errors.append(getattr(importlib.import_module(module), name))
        except ImportError:
            continue
    return tuple(errors)


def bag_error_text(exc: BaseException, limit: int = 200) -> str:
    """``exc`` as ``"TypeName: message"`` on one line, the message cut at ``limit`` characters.

    ``NotImplementedError`` and ``RecursionError`` (``RuntimeError`` subclasses, a program's faults,
    not a bag's) are raised again instead.
    """
    if isinstance(exc, (NotImplementedError, RecursionError)):
        raise exc
    return f"{type(exc).__name__}: {' '.join(str(exc).split())[:limit]}"


@dataclass(frozen=True)
class RawBagMessage:
    """One message of a bag, not yet deserialised: its ``topic``, when the bag logged it
    [ns], its CDR ``data`` (a view valid only until the next message is read) and its ``number``
    among its topic's messages, from 1."""

    topic: str
    log_time_ns: int
    data: bytes | memoryview
    number: int = 0


def iter_bag_messages(path: Any, topics: Mapping[str, str],
                      optional: Mapping[str, str] | None = None) -> Iterator[RawBagMessage]:
    """The raw messages of ``topics`` (name → message type, at least one) in a ROS 2 bag
    (a rosbag2 folder, ``.mcap`` or ``.db3``), in the bag's order.

    Each topic must be there and carry only its type; ``optional`` topics may be missing. Whatever
    rosbags raises on a damaged bag (:func:`bag_read_errors`) becomes a FileFormatError naming it.
    """
    p = check_path("path", path)
    if not isinstance(topics, Mapping) or not topics:
        raise InvalidArgumentError(f"`topics` must be a non-empty mapping; got {topics!r}")
    rosbag2 = _rosbag2()
    if path_kind(p) == "missing":
        raise FileFormatError(f"{p}: no such bag")
    if optional is not None and not isinstance(optional, Mapping):
        raise InvalidArgumentError(f"`optional` must be a mapping or None; got {optional!r}")
    what = f"topic {next(iter(topics))!r}" if len(topics) == 1 and not optional else "the bag"
    wanted = dict(topics)
    for topic, msgtype in (optional or {}).items():
        wanted.setdefault(topic, msgtype)
    errors = bag_read_errors()
    for file in sorted(p.glob("*.mcap")) if p.is_dir() else [p]:
        check_mcap_crcs(file)
    for file in sorted(p.glob("*.db3")) if p.is_dir() else [p]:
        check_db3_counts(file)
    try:
        with rosbag2.Reader(p) as reader:
            found = sorted({c.topic for c in reader.connections})
            for topic, msgtype in wanted.items():
                conns = [c for c in reader.connections if c.topic == topic]
                if not conns and topic not in topics:
                    continue
                if not conns:
                    raise FileFormatError(
                        f"{p}: bag has no topic {topic!r} (topics: {found}); expected one "
                        f"carrying {msgtype}")
                wrong = [c.msgtype for c in conns if c.msgtype != msgtype]
                if wrong:
                    raise FileFormatError(
                        f"{p}: topic {topic!r} carries {wrong[0] or repr(wrong[0])}, expected "
                        f"{msgtype}")
            conns = [c for c in reader.connections if c.topic in wanted]
            counts: dict[str, int] = {}
            for conn, log_time, raw in reader.messages(connections=conns):
                number = counts[conn.topic] = counts.get(conn.topic, 0) + 1
                _check_row(p, conn.topic, number, log_time, raw)
                yield RawBagMessage(conn.topic, log_time, raw, number)
    except DeformapError:
        raise
    except errors as exc:
        raise FileFormatError(f"{p}: could not read {what}: {bag_error_text(exc)}") from exc


def bag_topics(path: Any) -> dict[str, tuple[str, int]]:
    """``{topic: (message type, message count)}`` of a ROS 2 bag, from its connections (a topic
    written with two types is named with both, joined by `` | ``). A missing or unreadable bag is
    a FileFormatError naming it."""
    p = check_path("path", path)
    rosbag2 = _rosbag2()
    if path_kind(p) == "missing":
        raise FileFormatError(f"{p}: no such bag")
    if p.suffix == ".bag" and path_kind(p) == "file":
        raise FileFormatError(
            f"{p}: a ROS 1 bag; deformap reads ROS 2 bags only (.mcap, .db3 or a rosbag2 folder): "
            "convert it with `rosbags-convert --src FILE.bag --dst FOLDER`")
    out: dict[str, tuple[str, int]] = {}
    try:
        with rosbag2.Reader(p) as reader:
            for conn in reader.connections:
                kind, count = out.get(conn.topic, ("", 0))
                kinds = [k for k in kind.split(" | ") if k]
                if conn.msgtype not in kinds:
                    kinds.append(str(conn.msgtype))
                out[conn.topic] = (" | ".join(kinds), count + int(conn.msgcount or 0))
    except DeformapError:
        raise
    except bag_read_errors() as exc:
        raise FileFormatError(f"{p}: could not read the bag: {bag_error_text(exc)}") from exc
    return out


def _check_row(path: Path, topic: str, number: int, log_time: Any, data: Any) -> None:
    """Refuse a row whose log time is no integer or whose data is no bytes (sqlite3 stores any
    type in any column: ``bytes(10**12)`` would allocate a terabyte)."""
    if not isinstance(data, (bytes, bytearray, memoryview)):
        what, value = "its data as bytes", data
    elif not isinstance(log_time, int) or isinstance(log_time, bool):
        what, value = "an integer log time [ns]", log_time
    else:
        return
    raise FileFormatError(f"{path} [{topic} message {number}]: expected {what}; got "
                          f"{type(value).__name__} {str(value)[:40]!r}")


_MCAP_MAGIC = b"\x89MCAP0\r\n"
_FOOTER = struct.Struct("<BQQQI")  # opcode 0x02, length 20, summary start, offsets start, CRC
_DATA_END = struct.Struct("<BQI")  # opcode 0x0F, length 4, the data section's CRC
_BLOCK = 1 << 20
#: The last MCAP files verified, as (path, inode, size, mtime, ctime), for bags read in passes.
_VERIFIED: dict[tuple[str, int, int, int, int], None] = {}
_VERIFIED_KEPT = 256


def _crc32(fh: Any, start: int, end: int) -> int:
    fh.seek(start)
    crc, left = 0, end - start
    while left > 0:
        block = fh.read(min(_BLOCK, left))
        if not block:
            break
        crc, left = zlib.crc32(block, crc), left - len(block)
    return crc


#: The most bytes of a sqlite3 bag's metadata YAML read (rosbag2 writes a few kilobytes).
_DB3_METADATA_BYTES = 16 * 2**20


def check_db3_counts(path: Path) -> None:
    """Compare each topic's messages in a sqlite3 bag with the count its writer left in the
    bag's ``metadata`` table (rosbag2 since Iron; sqlite3 keeps no checksum, so this tells a row lost
    or repeated). A file that is no sqlite3 database, or has no such table, is not checked here.

    Raises
    ------
    FileFormatError
        A topic's count differs from the metadata's, or the metadata is not rosbag2's YAML.
    """
    import yaml

    if path.suffix != ".db3" or path_kind(path) != "file":
        return
    try:
        conn = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
    except sqlite3.Error:
        return
    try:
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not {"metadata", "topics", "messages"} <= tables:
            return
        row = conn.execute("SELECT metadata FROM metadata ORDER BY id DESC LIMIT 1").fetchone()
        rows = conn.execute("SELECT topics.name, count(messages.id) FROM topics LEFT JOIN "
                            "messages ON topics.id == messages.topic_id GROUP BY topics.id")
        found: dict[str, int] = {}
        for name, count in rows:
            found[str(name)] = found.get(str(name), 0) + int(count)
    except sqlite3.Error:
        return  # the reader refuses a damaged database itself, naming it
    finally:
        conn.close()
    if row is None:
        return
    text = row[0]
    if not isinstance(text, str) or len(text) > _DB3_METADATA_BYTES:
        raise FileFormatError(f"{path}: the metadata table must hold rosbag2's metadata YAML; "
                              f"got {type(text).__name__} of {len(text or '')} characters")
    try:
        doc = yaml.safe_load(text)
        # the table holds the bag information itself (metadata.yaml wraps it in this key)
        info = doc.get("rosbag2_bagfile_information", doc)
        declared = {str(t["topic_metadata"]["name"]): int(t["message_count"])
                    for t in info["topics_with_message_count"]}
    except (yaml.YAMLError, AttributeError, KeyError, TypeError, ValueError) as exc:
        raise FileFormatError(f"{path}: the metadata table's YAML is not rosbag2's bag "
                              f"information: {bag_error_text(exc, 120)}") from None
    for name, count in declared.items():
        if name in found and found[name] != count:
            raise FileFormatError(
                f"{path}: topic {name!r} holds {found[name]} messages where the bag's metadata "
                f"says {count}: messages were lost or repeated after it was written")


def check_mcap_crcs(path: Path) -> None:
    """Verify the CRC-32s an MCAP file's writer left in its footer (over the summary
    section) and its ``DataEnd`` record (over the data section). A zero CRC (not written), or a
    file that is no MCAP or has a damaged footer (the reader refuses those), is not checked; a
    mismatch is a FileFormatError naming the section and both values."""
    try:
        stat = path.stat()
    except OSError:
        return
    key = (str(path.resolve()), stat.st_ino, stat.st_size, stat.st_mtime_ns, stat.st_ctime_ns)
    if key in _VERIFIED or stat.st_size < 2 * len(_MCAP_MAGIC) + _FOOTER.size:
        return
    footer_at = stat.st_size - len(_MCAP_MAGIC) - _FOOTER.size
    with path.open("rb") as fh:
        if fh.read(len(_MCAP_MAGIC)) != _MCAP_MAGIC:
            return
        fh.seek(footer_at)
        tail = fh.read()
        if tail[-len(_MCAP_MAGIC):] != _MCAP_MAGIC:
            return
        opcode, length, summary_at, _, summary_crc = _FOOTER.unpack_from(tail)
        if opcode != 0x02 or length != 20 or summary_at > footer_at:
            return
        summary_start = summary_at or footer_at
        if summary_crc:
            # the summary section and the footer up to its CRC field
            got = zlib.crc32(tail[: _FOOTER.size - 4], _crc32(fh, summary_start, footer_at))
            if got != summary_crc:
                raise FileFormatError(
                    f"{path}: the MCAP summary section (schemas, channels, chunk indexes) fails "
                    f"its CRC-32: expected {summary_crc:#010x} (the footer's), got {got:#010x}")
        data_end_at = summary_start - _DATA_END.size
        if data_end_at >= len(_MCAP_MAGIC):
            fh.seek(data_end_at)
            opcode, length, data_crc = _DATA_END.unpack(fh.read(_DATA_END.size))
            if opcode == 0x0F and length == 4 and data_crc:
                got = _crc32(fh, 0, data_end_at)
                if got != data_crc:
                    raise FileFormatError(
                        f"{path}: the MCAP data section fails its CRC-32: expected "
                        f"{data_crc:#010x} (the DataEnd record's), got {got:#010x}")
    _VERIFIED[key] = None
    while len(_VERIFIED) > _VERIFIED_KEPT:
        del _VERIFIED[next(iter(_VERIFIED))]
