"""Seeded mutators of the reader mutants of :mod:`deformap.testing.mutants`.

Every mutator takes the bytes (or a session folder, or a raw bag's folder) and a
``numpy.random.Generator`` and returns (or writes) the damaged copy; the same seed gives the same
mutant. :data:`KINDS` names the kinds tried on each reader.
"""

from __future__ import annotations

import io
import os
import re
import shutil
import struct
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from deformap.testing._mutant_templates import RAW_CHUNK_BYTES

__all__ = ["FILE_MUTATORS", "KINDS", "alias_bomb", "kinds_of", "mutate_file", "mutate_raw",
           "mutate_session"]

Mutator = Callable[[bytes, np.random.Generator], bytes]

#: Reader (``raw-mcap``) or reader family (``pcd`` for ``pcd-ascii``) → the kinds of mutation
#: tried on it (:func:`kinds_of`).
KINDS: dict[str, tuple[str, ...]] = {
    "pcd": ("flip", "truncate", "extend", "header", "count"),
    "ply": ("flip", "truncate", "extend", "header", "count"),
    # an ascii body also cut inside its last number
    "pcd-ascii": ("flip", "truncate", "extend", "header", "count", "cut-number"),
    "ply-ascii": ("flip", "truncate", "extend", "header", "count", "cut-number"),
    "npz": ("flip", "truncate", "extend", "member-flip", "member-truncate", "member-extend",
            "member-npy-header", "member-shape"),
    # "alias": a value replaced by a nested YAML alias bomb
    "session": ("yaml", "file", "link", "alias"),
    "config": ("yaml", "flip", "truncate", "alias"),
    "scenario": ("yaml", "flip", "truncate", "alias"),
    # a bag as a robot records it: its bytes, one record, one message (the CRCs made to match),
    # the settings YAML beside it; as sqlite3 (rosbag2's default before Iron) rows and topics too
    "raw-mcap": ("flip", "truncate", "extend", "record", "message-flip", "message-truncate",
                 "message-extend", "yaml", "alias"),
    "raw-db3": ("flip", "truncate", "extend", "message-flip", "message-truncate",
                "message-extend", "row-delete", "row-repeat", "row-type", "topic", "yaml",
                "alias"),
}


def kinds_of(reader: str) -> tuple[str, ...]:
    """The kinds of mutation tried on ``reader`` (its own entry in :data:`KINDS`, else its
    family's)."""
    return KINDS.get(reader) or KINDS[reader.split("-")[0]]


def _flip(data: bytes, rng: np.random.Generator) -> bytes:
    for _ in range(int(rng.integers(1, 5))):
        data = _flip_at(data, int(rng.integers(len(data))), rng)
    return data


def _flip_at(data: bytes, at: int, rng: np.random.Generator) -> bytes:
    out = bytearray(data)
    out[at] ^= 1 << int(rng.integers(8))
    return bytes(out)


def _truncate(data: bytes, rng: np.random.Generator) -> bytes:
    return data[: int(rng.integers(0, len(data)))]


def _extend(data: bytes, rng: np.random.Generator) -> bytes:
    if rng.random() < 0.5:
        return data + rng.bytes(int(rng.integers(1, 65)))
    k = int(rng.integers(1, 97))
    return data + data[-k:]  # what looks like one more record


_NUMBERS = ("0", "-1", "1", "2", "3", "7", "1000000000", "1000000000000", "4294967296",
            "18446744073709551617", "nan", "1e308", "-0", "x", "")  # fmt: skip


def _header_end(data: bytes) -> int:
    for marker in (b"end_header\n", b"DATA ascii\n", b"DATA binary_compressed\n",
                   b"DATA binary\n"):  # fmt: skip
        at = data.find(marker)
        if at >= 0:
            return at + len(marker)
    return min(len(data), 512)


def _header(data: bytes, rng: np.random.Generator) -> bytes:
    """One header line's token replaced (a number, another word of the header), or the line
    dropped or repeated."""
    end = _header_end(data)
    lines = data[:end].split(b"\n")
    i = int(rng.integers(len(lines)))
    words = lines[i].split(b" ")
    choice = rng.random()
    if choice < 0.15:
        del lines[i]
    elif choice < 0.3:
        lines.insert(i, lines[i])
    else:
        j = int(rng.integers(len(words)))
        vocabulary = [w for line in lines for w in line.split(b" ") if w]
        if rng.random() < 0.7 or not vocabulary:
            words[j] = _NUMBERS[int(rng.integers(len(_NUMBERS)))].encode()
        else:
            words[j] = vocabulary[int(rng.integers(len(vocabulary)))]
        lines[i] = b" ".join(words)
    return b"\n".join(lines) + data[end:]


def _count(data: bytes, rng: np.random.Generator) -> bytes:
    """Change the declared point count (PCD: POINTS and WIDTH together; PLY: element vertex)."""
    pattern = (rb"element vertex (\d+)" if data.startswith(b"ply")
               else rb"POINTS (\d+)")  # fmt: skip
    match = re.search(pattern, data[: _header_end(data)])
    if match is None:
        return _header(data, rng)
    n = int(match.group(1))
    new = [n - 1, n + 1, n // 2, 2 * n, 0, n - 7, 10**9, 10**12][int(rng.integers(8))]
    out = data.replace(match.group(0), match.group(0).replace(match.group(1), str(new).encode()), 1)
    if not data.startswith(b"ply"):
        out = out.replace(f"WIDTH {n}".encode(), f"WIDTH {new}".encode(), 1)
    return out


def _cut_number(data: bytes, rng: np.random.Generator) -> bytes:
    """An ascii file cut inside its last number (between two of its digits): no line break
    after the last row, and the number shorter."""
    body = data.rstrip()
    start = max(body.rfind(b"\n"), body.rfind(b" "), body.rfind(b"\t")) + 1
    inside = [start + m.start() + 1 for m in re.finditer(rb"(?=\d\d)", body[start:])]
    if not inside:
        return body
    return body[: inside[int(rng.integers(len(inside)))]]


FILE_MUTATORS: dict[str, Mutator] = {
    "flip": _flip, "truncate": _truncate, "extend": _extend, "header": _header, "count": _count,
    "cut-number": _cut_number,
}  # fmt: skip


def _npz_member(data: bytes, rng: np.random.Generator, kind: str) -> bytes:
    """Mutate one member's .npy bytes (``kind``: flip, truncate, extend, npy-header, shape) and
    rebuild the zip, so that the member's CRC matches the damage."""
    src = zipfile.ZipFile(io.BytesIO(data))
    names = src.namelist()
    victim = names[int(rng.integers(len(names)))]
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as dst:
        for name in names:
            raw = src.read(name)
            if name == victim:
                raw = {"npy-header": _header_npy, "shape": _shape_npy, **FILE_MUTATORS}[kind](raw, rng)
            dst.writestr(name, raw)
    return buf.getvalue()


def _header_npy(raw: bytes, rng: np.random.Generator) -> bytes:
    end = raw.find(b"\n", 10)
    header = bytearray(raw[10:end])
    for _ in range(int(rng.integers(1, 4))):
        at = int(rng.integers(len(header)))
        header[at] = b"{}()[]',: 0123456789<>fiuUOb"[int(rng.integers(28))]
    return raw[:10] + bytes(header) + raw[end:]


def _shape_npy(raw: bytes, rng: np.random.Generator) -> bytes:
    match = re.search(rb"'shape': \(([^)]*)\)", raw[:200])
    if match is None:
        return raw
    new = [b"0, 3", b"1, 3", b"1000000000, 3", b"119, 3", b"121, 3", b"3,", b"120, 3, 1",
           b"-1, 3", b"10000000000000, 3"][int(rng.integers(9))]  # fmt: skip
    padded = match.group(0).replace(match.group(1), new)
    return raw.replace(match.group(0), padded, 1)


def _yaml_edit(text: str, rng: np.random.Generator) -> str:
    lines = text.split("\n")
    choice = rng.random()
    if choice < 0.2:  # cut after a random line
        return "\n".join(lines[: int(rng.integers(1, len(lines)))]) + "\n"
    if choice < 0.35:  # cut at a poke boundary
        starts = [i for i, line in enumerate(lines) if line.startswith("- ")]
        if starts:
            return "\n".join(lines[: starts[int(rng.integers(len(starts)))]]) + "\n"
    i = int(rng.integers(len(lines)))
    if choice < 0.5:
        del lines[i]
    elif choice < 0.6:
        lines.insert(i, lines[i])
    elif choice < 0.75:  # a file name outside the folder
        names = [j for j, line in enumerate(lines) if ".pcd" in line or ".npz" in line
                 or line.startswith("bag:")]  # fmt: skip
        if names:
            j = names[int(rng.integers(len(names)))]
            key, _, value = lines[j].partition(":")
            bad = ("../", "/tmp/", "./../s/", "sub/../../")[int(rng.integers(4))]
            lines[j] = f"{key}: {bad}{value.strip()}"
    else:  # a number replaced
        numbers = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", lines[i]))
        if numbers:
            m = numbers[int(rng.integers(len(numbers)))]
            new = _NUMBERS[int(rng.integers(len(_NUMBERS)))] or "1"
            lines[i] = lines[i][: m.start()] + new + lines[i][m.end():]
    return "\n".join(lines)


def alias_bomb(depth: int = 9, width: int = 9) -> str:
    """A flow sequence of YAML anchors, each level ``width`` aliases of the one before ("billion
    laughs"): a few hundred characters that expand to ``width ** depth`` strings."""
    levels = ["&l0 [" + ", ".join(["lol"] * width) + "]"]
    for i in range(1, depth):
        levels.append(f"&l{i} [" + ", ".join([f"*l{i - 1}"] * width) + "]")
    return "[" + ", ".join(levels) + "]"


_KEY_LINE = re.compile(r"^(\s*(?:- )?[A-Za-z_][\w.]*:)[ \t]+\S.*$")


def _alias_edit(text: str, rng: np.random.Generator) -> str:
    """The value of a random ``key: value`` line replaced by :func:`alias_bomb` (a plain anchor
    and its alias elsewhere when no line has a value)."""
    lines = text.split("\n")
    keyed = [i for i, line in enumerate(lines) if _KEY_LINE.match(line)]
    if not keyed:
        return "&a " + text
    i = keyed[int(rng.integers(len(keyed)))]
    key = _KEY_LINE.match(lines[i]).group(1)  # type: ignore[union-attr]
    depth, width = int(rng.integers(2, 10)), int(rng.integers(2, 10))
    lines[i] = f"{key} {alias_bomb(depth, width)}"
    return "\n".join(lines)


def mutate_session(template: Path, out: Path, kind: str, rng: np.random.Generator) -> None:
    """Copy the session folder ``template`` to ``out`` and damage it (``kind``)."""
    shutil.copytree(template, out, symlinks=True)
    data_files = sorted(p for p in out.rglob("*") if p.is_file() and p.name != "session.yaml")
    if kind in ("yaml", "alias"):
        file = out / "session.yaml"
        edit = _yaml_edit if kind == "yaml" else _alias_edit
        file.write_text(edit(file.read_text(), rng))
    elif kind == "link":
        victim = data_files[int(rng.integers(len(data_files)))]
        outside = out.parent / f"{out.name}-outside-{victim.name}"
        shutil.move(victim, outside)
        os.symlink(outside, victim)
    else:
        victim = data_files[int(rng.integers(len(data_files)))]
        name = tuple(FILE_MUTATORS)[int(rng.integers(5))]
        victim.write_bytes(FILE_MUTATORS[name](victim.read_bytes(), rng))


_MCAP_MAGIC = b"\x89MCAP0\r\n"


def _mcap_record(data: bytes, rng: np.random.Generator) -> bytes:
    """Damage one record of an MCAP file (opcode, u64 length, content): a byte of its content
    flipped, its length field changed, the record left out or repeated."""
    spans, at = [], len(_MCAP_MAGIC)
    while at + 9 <= len(data) - len(_MCAP_MAGIC):
        (length,) = struct.unpack_from("<Q", data, at + 1)
        spans.append((at, at + 9 + length))
        at += 9 + length
    start, end = spans[int(rng.integers(len(spans)))]
    choice = rng.random()
    if choice < 0.4 and end > start + 9:
        return _flip_at(data, int(rng.integers(start + 9, end)), rng)
    if choice < 0.6:
        length = end - start - 9
        new = [length - 1, length + 1, 0, length // 2, 2**63, 2**64 - 1][int(rng.integers(6))]
        return data[: start + 1] + struct.pack("<Q", max(new, 0)) + data[start + 9:]
    if choice < 0.8:
        return data[:start] + data[end:]
    return data[:end] + data[start:]


def _mcap_message(data: bytes, rng: np.random.Generator, kind: str) -> bytes:
    """The MCAP rewritten with one message's bytes damaged (``kind``: flip, truncate, extend) and
    every CRC computed anew; the topic is drawn first, then one of its messages."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    records = list(make_reader(io.BytesIO(data)).iter_messages(log_time_order=False))
    topics = sorted({channel.topic for _, channel, _ in records})
    topic = topics[int(rng.integers(len(topics)))]
    mine = [i for i, (_, channel, _) in enumerate(records) if channel.topic == topic]
    victim = mine[int(rng.integers(len(mine)))]
    out = io.BytesIO()
    writer = Writer(out, chunk_size=RAW_CHUNK_BYTES)
    writer.start(profile="ros2", library="deformap robustness")
    schemas: dict[int, int] = {}
    channels: dict[int, int] = {}
    for i, (schema, channel, message) in enumerate(records):
        if schema is not None and schema.id not in schemas:
            schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channels:
            channels[channel.id] = writer.register_channel(
                channel.topic, channel.message_encoding,
                schemas[schema.id] if schema is not None else 0, channel.metadata)
        payload = FILE_MUTATORS[kind](message.data, rng) if i == victim else message.data
        writer.add_message(channels[channel.id], message.log_time, payload, message.publish_time,
                           message.sequence)  # fmt: skip
    writer.finish()
    return out.getvalue()


def _db3_edit(bag: Path, kind: str, rng: np.random.Generator) -> None:
    """Edit the sqlite3 bag in place through SQL (``kind``: message-flip, -truncate or -extend of
    one row's data, row-delete, row-repeat, row-type: another SQL type in a row, topic: another
    value in a ``topics`` row); the topic is drawn first, then one of its messages."""
    import sqlite3

    conn = sqlite3.connect(bag)
    try:
        topics = conn.execute("SELECT id, name, type FROM topics ORDER BY id").fetchall()
        tid, name, msgtype = topics[int(rng.integers(len(topics)))]
        if kind == "topic":
            others = [t for t in topics if t[0] != tid] or topics
            other = others[int(rng.integers(len(others)))]
            column, values = [
                ("name", [other[1], name + "x", "", "/", name.upper()]),
                ("type", [other[2], "std_msgs/msg/String", msgtype + "x", ""]),
                ("serialization_format", ["", "json", "ros1", "cdr\x00"]),
                ("offered_qos_profiles", ["", "- x", "[", "- history: 99", "{a: [}"]),
                ("type_description_hash", ["", "RIHS01_00", "x"]),
                ("id", [tid + 100, -1, 0]),
            ][int(rng.integers(6))]  # fmt: skip
            value = values[int(rng.integers(len(values)))]
            conn.execute(f"UPDATE topics SET {column} = ? WHERE id = ?", (value, tid))
        else:
            ids = [r[0] for r in conn.execute(
                "SELECT id FROM messages WHERE topic_id = ? ORDER BY id", (tid,))]
            victim = ids[int(rng.integers(len(ids)))]
            if kind == "row-delete":
                conn.execute("DELETE FROM messages WHERE id = ?", (victim,))
            elif kind == "row-type":  # sqlite3 stores any type in any column
                column = ("data", "timestamp")[int(rng.integers(2))]
                value = [7, 10**12, -1, 2.5, 1e300, "x", "1700000000000000000",
                         b"\x00\x01"][int(rng.integers(8))]
                conn.execute(f"UPDATE messages SET {column} = ? WHERE id = ?", (value, victim))
            elif kind == "row-repeat":
                conn.execute("INSERT INTO messages (topic_id, timestamp, data) SELECT topic_id, "
                             "timestamp, data FROM messages WHERE id = ?", (victim,))
            else:
                (data,) = conn.execute("SELECT data FROM messages WHERE id = ?",
                                       (victim,)).fetchone()  # fmt: skip
                payload = FILE_MUTATORS[kind.removeprefix("message-")](bytes(data), rng)
                conn.execute("UPDATE messages SET data = ? WHERE id = ?", (payload, victim))
        conn.commit()
    finally:
        conn.close()


def mutate_raw(template: Path, out: Path, kind: str, rng: np.random.Generator) -> Path:
    """Copy the folder of the raw bag ``template`` (the bag and its settings YAML) to ``out``
    and damage the bag or, for ``yaml``, the settings; returns the damaged bag's path."""
    shutil.copytree(template.parent, out)
    bag = out / template.name
    if kind in ("yaml", "alias"):
        settings = bag.with_name(f"{bag.stem}.deformap.yaml")
        edit = _yaml_edit if kind == "yaml" else _alias_edit
        settings.write_text(edit(settings.read_text(), rng))
    elif bag.suffix == ".db3" and kind not in FILE_MUTATORS:
        _db3_edit(bag, kind, rng)
    elif kind == "record":
        bag.write_bytes(_mcap_record(bag.read_bytes(), rng))
    elif kind.startswith("message-"):
        bag.write_bytes(_mcap_message(bag.read_bytes(), rng, kind.removeprefix("message-")))
    else:
        bag.write_bytes(FILE_MUTATORS[kind](bag.read_bytes(), rng))
    return bag


def mutate_file(data: bytes, kind: str, rng: np.random.Generator) -> bytes:
    """One file mutant: a ``FILE_MUTATORS`` kind, or ``member-KIND`` inside an NPZ member."""
    if kind.startswith("member-"):
        return _npz_member(data, rng, kind.removeprefix("member-"))
    if kind in ("yaml", "alias"):
        edit = _yaml_edit if kind == "yaml" else _alias_edit
        return edit(data.decode("utf-8"), rng).encode("utf-8")
    return FILE_MUTATORS[kind](data, rng)
