"""Writing files so that a kill or a power cut leaves the old file or the new one, never half.

One home for every durable write of the package: the journal's header and rewrites, the files of
a run folder (``config.yaml``, ``report.json``, ...), figures and recordings. A file is written
under a temporary name beside its destination (same folder, so the same file system), fsynced,
renamed onto the destination with :func:`os.replace`, and the folder is fsynced so that the rename
itself is durable (POSIX keeps it in the folder's cache until then).
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_path", "replace_durably", "write_text_atomically"]


def _fsync_folder(folder: Path) -> None:
    if os.name == "posix":  # folders cannot be opened for fsync on Windows
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def replace_durably(tmp: Path, path: Path) -> None:
    """Rename the written and fsynced ``tmp`` onto ``path``, then fsync the folder."""
    os.replace(tmp, path)
    _fsync_folder(path.parent)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix) for a writer to create; when the
    block ends without an error it is fsynced and renamed onto ``path``.

    If the block raises, the temporary file is removed and ``path`` is left as it was.
    """
    out = Path(path)
    # a hidden name unique to this write, created by the writer: open() honours the umask, so the
    # file gets the permissions a plain write would (mkstemp's are owner-only)
    tmp = out.with_name(f".{out.stem}.{secrets.token_hex(4)}.tmp{out.suffix}")
    try:
        yield tmp
        with open(tmp, "r+b") as fh:  # writable: Windows cannot fsync a read-only handle
            os.fsync(fh.fileno())
        replace_durably(tmp, out)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_text_atomically(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_path`; returns ``path``."""
    out = Path(path)
    with atomic_path(out) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    return out
