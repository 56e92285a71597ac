"""Writing files so that a kill or a power cut leaves the old file or the new one, never half.

Every durable write (journal header and rewrites, run-folder files, figures, recordings) goes to
a temporary file beside the destination, fsynced, renamed onto it with :func:`os.replace`, the
folder fsynced. A destination that exists must be a regular file (renaming onto a FIFO, device,
socket, link or folder would replace the node, not write it); such a destination, or a path that
names no file, is refused before anything is written.

A write that fails on the machine's side (no space left, a read-only file system, a quota, no
permission: any :class:`OSError`) raises one :class:`~deformap.errors.FileWriteError` naming the
file and the cause (:func:`writing`), and leaves no temporary file behind; temporaries left by a
process killed mid-write carry names :func:`is_temporary` knows, for :func:`remove_temporaries`.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path

from deformap.errors import FileWriteError, InvalidArgumentError

__all__ = ["LOCK_NAME", "atomic_path", "check_destination", "is_temporary", "os_error_cause",
           "remove_temporaries", "replace_durably", "write_error", "write_text_atomically",
           "writing"]

LOCK_NAME = ".deformap.lock"
"""The lock file of a folder a deformap process writes (:mod:`deformap.run._lock`), present while
a run holds the folder (or left by a killed one, when it holds no lock); no writer lists it among
what it wrote."""

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a device"),
          (stat.S_ISBLK, "a device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISLNK, "a symbolic link (name its target, or a new file)"))


_CAUSES = {
    errno.ENOSPC: "no space left on the device",
    errno.EROFS: "the file system is read-only",
    errno.EDQUOT: "the disk quota is exceeded",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
}

#: The name :func:`atomic_path` gives a temporary: ``.<stem>.<8 hex digits>.tmp<suffix>``.
_TEMPORARY = re.compile(r"\..+\.[0-9a-f]{8}\.tmp(\.[^.]+)?")


def os_error_cause(error: OSError) -> str:
    """What went wrong, in words, with the system's name for it: ``"no space left on the device
    (ENOSPC)"``; an error without a number gives its own text."""
    code = error.errno
    name = errno.errorcode.get(code) if isinstance(code, int) else None
    text = (_CAUSES.get(code) or error.strerror or os.strerror(code)) if isinstance(code, int) \
        else None
    text = text or error.strerror or str(error) or type(error).__name__
    return f"{text} ({name})" if name else text


def write_error(path: str | Path, error: OSError) -> FileWriteError:
    """``error``, raised while writing ``path``, as one :class:`FileWriteError` line naming
    ``path`` and the cause (a :class:`FileWriteError` already is one, and is returned as is)."""
    if isinstance(error, FileWriteError):
        return error
    out = FileWriteError(f"cannot write {str(path)!r}: {os_error_cause(error)}")
    out.errno = error.errno
    return out


@contextlib.contextmanager
def writing(path: str | Path) -> Iterator[None]:
    """Run the block that writes ``path``; an :class:`OSError` it raises becomes
    :func:`write_error`'s one line (the one path by which every write reports a failure)."""
    try:
        yield
    except OSError as error:
        raise write_error(path, error) from error


def is_temporary(path: Path) -> bool:
    """Whether ``path``'s name is one :func:`atomic_path` gives its temporaries."""
    return _TEMPORARY.fullmatch(path.name) is not None


def remove_temporaries(folder: str | Path) -> list[Path]:
    """Remove the temporaries of writes cut short in ``folder`` (regular files named as
    :func:`atomic_path` names them; the caller must be the folder's only writer); returns them."""
    removed = []
    for path in sorted(Path(folder).iterdir()):
        if is_temporary(path) and stat.S_ISREG(os.lstat(path).st_mode):
            with writing(path):
                path.unlink()
            removed.append(path)
    return removed


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
    ends without an error it is fsynced and renamed onto ``path``, else removed. An
    :class:`OSError` of the block, the sync or the rename raises :class:`FileWriteError` naming
    ``path`` (:func:`writing`); ``path`` then holds what it held before."""
    out = check_destination(path)
    # a hidden name unique to this write, created by the writer: open() honours the umask, so the
    # file gets the permissions a plain write would (mkstemp's are owner-only)
    tmp = out.with_name(f".{out.stem}.{secrets.token_hex(4)}.tmp{out.suffix}")
    try:
        with writing(out):
            yield tmp
            with open(tmp, "r+b") as fh:  # writable: Windows cannot fsync a read-only handle
                os.fsync(fh.fileno())
            replace_durably(tmp, out)
    finally:
        with contextlib.suppress(OSError):  # none made, or a file system that takes no change
            tmp.unlink()


def write_text_atomically(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_path`; returns ``path``."""
    out = Path(path)
    with atomic_path(out) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    return out
