"""Writing files so that a kill or a power cut leaves the old file or the new one, never half.

Every durable write (journal header and rewrites, run-folder files, figures, recordings) goes to
a temporary file beside the destination, fsynced, renamed onto it with :func:`os.replace`, the
folder fsynced. A destination that exists must be a regular file (renaming onto a FIFO, device,
socket, link or folder would replace the node, not write it); such a destination, or a path that
names no file, is refused before anything is written.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path

from deformap.errors import InvalidArgumentError

__all__ = ["atomic_path", "check_destination", "replace_durably", "write_text_atomically"]

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a device"),
          (stat.S_ISBLK, "a device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISLNK, "a symbolic link (name its target, or a new file)"))


def check_destination(path: str | Path) -> Path:
    """``path`` as a :class:`~pathlib.Path` if a file may be written there by renaming onto it;
    else an InvalidArgumentError (no file name, or an existing non-regular file)."""
    out = Path(path)
    if str(path) == "" or out.name in ("", ".", ".."):
        raise InvalidArgumentError(f"{str(path)!r}: expected the name of a file to write")
    try:
        mode = os.lstat(out).st_mode
    except FileNotFoundError:
        return out
    except OSError as error:  # a name too long, a parent that is a file, no permission
        raise InvalidArgumentError(f"{out}: cannot be written ({error.strerror})") from None
    for test, kind in _KINDS:
        if test(mode):
            raise InvalidArgumentError(
                f"{out}: expected a regular file or a new name to write, got {kind}")
    return out


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
    """Yield a temporary path beside ``path`` (same suffix) for a writer to create; when the block
    ends without an error it is fsynced and renamed onto ``path``, else removed."""
    out = check_destination(path)
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
