"""A durable, append-only journal of a run: one JSON line per completed poke.

The first line is a header holding the run's identity; each later line is one poke, synced to disk
before the loop moves on, so a killed run loses at most the poke in progress. Reading drops a last
line cut mid-write. A line whose write fails (a full disk) is cut off again and the failure raised
as one :class:`~deformap.errors.FileWriteError` line, so the journal still holds whole lines only.
"""

from __future__ import annotations

import contextlib
import errno
import json
import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from deformap._files import atomic_path, writing
from deformap.errors import ConfigError, FileFormatError

__all__ = ["JOURNAL_NAME", "Journal", "JournalContents", "read_journal"]

logger = logging.getLogger(__name__)

JOURNAL_NAME = "journal.jsonl"


@dataclass
class JournalContents:
    """What a journal file holds: the header, complete pokes, and a note on a broken tail."""

    header: dict[str, Any]
    pokes: list[dict[str, Any]] = field(default_factory=list)
    broken_line: str | None = None


def read_journal(path: str | Path) -> JournalContents:
    """Read a journal; a last line cut mid-write is reported in ``broken_line`` and dropped.
    :class:`FileFormatError` if the file is missing, has no header, or another line is broken."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise FileFormatError(f"cannot read journal {str(p)!r}: {exc.strerror or exc}") from None
    lines = raw.decode("utf-8", errors="replace").split("\n")
    complete, tail = lines[:-1], lines[-1]
    records: list[dict[str, Any]] = []
    broken = tail if tail.strip() else None
    for number, line in enumerate(complete, start=1):
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            if number == len(complete) and broken is None:
                broken = line
                break
            raise FileFormatError(
                f"journal {str(p)!r}: line {number} is not valid JSON and is not the last line; "
                "the file was changed by something other than deformap"
            ) from None
        records.append(record)
    if not records or records[0].get("kind") != "header":
        raise FileFormatError(f"journal {str(p)!r} has no header line")
    if broken is not None:
        logger.warning("journal %s: dropped a line cut mid-write (%d bytes)", p, len(broken))
    return JournalContents(header=records[0], pokes=records[1:], broken_line=broken)


class Journal:
    """Append-only JSON-lines journal in ``folder/journal.jsonl`` (:meth:`create`, :meth:`resume`)."""

    def __init__(self, path: Path) -> None:
        self.path = path

    @classmethod
    def create(cls, folder: str | Path, header: dict[str, Any]) -> Journal:
        """Start a journal holding ``header`` (written atomically); :class:`FileExistsError` if
        the folder has one."""
        path = Path(folder) / JOURNAL_NAME
        with writing(path):
            path.parent.mkdir(parents=True, exist_ok=True)
        if path.exists():
            raise FileExistsError(f"{str(path)!r} already exists")
        journal = cls(path)
        with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
            journal._write(fh, {"kind": "header", **header})
        return journal

    @classmethod
    def resume(cls, folder: str | Path, header: dict[str, Any]) -> tuple[Journal, JournalContents]:
        """Open an existing journal whose header must equal ``header``; drop a broken tail."""
        path = Path(folder) / JOURNAL_NAME
        contents = read_journal(path)
        stored = {k: v for k, v in contents.header.items() if k != "kind"}
        if stored != json.loads(json.dumps(header)):
            differing = sorted(k for k in set(stored) | set(header) if stored.get(k) != header.get(k))
            raise ConfigError(f"cannot resume {str(Path(folder))!r}: its run differs from this one "
                              f"in {differing}")
        journal = cls(path)
        if contents.broken_line is not None:
            journal._rewrite(contents)
        return journal, contents

    def append(self, record: dict[str, Any]) -> None:
        """Add ``record`` as one poke line, synced to disk; a line whose write fails is cut off
        (the file keeps its earlier lines) and :class:`FileWriteError` names the journal."""
        line = (json.dumps({"kind": "poke", **record}, allow_nan=False) + "\n").encode("utf-8")
        with writing(self.path):
            fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
            try:
                start = os.fstat(fd).st_size
                try:
                    view = memoryview(line)
                    while view:
                        written = os.write(fd, view)
                        if written == 0:  # nothing taken: the device is full
                            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
                        view = view[written:]
                    os.fsync(fd)
                except OSError:
                    with contextlib.suppress(OSError):  # shrinking needs no space
                        os.ftruncate(fd, start)
                    raise
            finally:
                os.close(fd)

    def _rewrite(self, contents: JournalContents) -> None:
        with atomic_path(self.path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
            for record in [contents.header, *contents.pokes]:
                self._write(fh, record)

    @staticmethod
    def _write(fh: Any, record: dict[str, Any]) -> None:
        fh.write(json.dumps(record, allow_nan=False) + "\n")
        fh.flush()
        os.fsync(fh.fileno())
