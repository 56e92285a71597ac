"""One writer per run folder: an OS file lock held for the run's life.

:func:`lock_run_folder` takes an exclusive, non-blocking :func:`fcntl.flock` on
:data:`LOCK_NAME` in the folder and writes the holder's PID into it. The kernel releases the lock
when the holder's process ends, however it ends (a ``kill -9`` too), so a killed run never leaves
its folder locked; a second writer while it lives is refused in one line naming the holder's PID
(:class:`~deformap.errors.ConfigError`). Released normally, the lock file is removed; a new holder
checks that the file it locked is still the one under the name, so a removal racing with it
never gives two holders.

Where Python has no :mod:`fcntl` (Windows) folders are not locked: two runs in one folder are not
refused there. A file system that does not take locks (some network mounts) is used unlocked, with
a warning.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from pathlib import Path
from types import TracebackType

from deformap._files import LOCK_NAME, os_error_cause
from deformap.errors import ConfigError, FileWriteError

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_NAME", "RunFolderLock", "folder_holder", "lock_run_folder"]

logger = logging.getLogger(__name__)



class RunFolderLock:
    """The lock a run holds on its folder (:func:`lock_run_folder`); :meth:`release` it, or use it
    as a context manager."""

    def __init__(self, folder: Path, fd: int | None) -> None:
        self.folder = folder
        self._fd = fd

    @property
    def held(self) -> bool:
        """Whether an OS lock is held (False where folders are not locked, and once released)."""
        return self._fd is not None

    def release(self) -> None:
        """Remove the lock file and release the lock (again: nothing)."""
        if self._fd is None:
            return
        with contextlib.suppress(OSError):  # a folder removed or made read-only meanwhile
            (self.folder / LOCK_NAME).unlink()
        os.close(self._fd)  # closing the last descriptor releases the flock
        self._fd = None

    def __enter__(self) -> RunFolderLock:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        self.release()


#: How long [s] to wait for a new holder to write its PID, which it does right after locking.
_PID_WAIT_S = 0.5


def _pid_in(fd: int) -> str:
    """The PID a lock file holds, as text; a holder that has locked the file but not yet written
    its PID is waited for up to :data:`_PID_WAIT_S` ("unknown" after that)."""
    deadline = time.monotonic() + _PID_WAIT_S
    while True:
        with contextlib.suppress(OSError):
            text = os.pread(fd, 32, 0).decode("ascii", errors="replace").strip()
            if text.isdigit():
                return text
        if time.monotonic() >= deadline:
            return "unknown"
        time.sleep(0.01)


def _in_use(folder: Path, what: str, pid: str) -> ConfigError:
    return ConfigError(f"{what} folder {str(folder)!r} is in use by another deformap process "
                       f"(PID {pid}); wait for it to end, or stop it, and try again")


def folder_holder(folder: Path) -> str | None:
    """The PID (as text, "unknown" if not yet written) of the process holding ``folder``'s lock,
    or None when no process holds it."""
    if fcntl is None:  # pragma: no cover - Windows
        return None
    try:
        fd = os.open(folder / LOCK_NAME, os.O_RDONLY)
    except OSError:
        return None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return _pid_in(fd)
        except OSError:
            return None
        return None
    finally:
        os.close(fd)


def lock_run_folder(folder: Path, *, what: str = "run") -> RunFolderLock:
    """Lock the existing ``folder`` for this process (module docstring).

    ``what`` names the folder in the messages ("run", "output", "result"). Another process
    holding it raises :class:`ConfigError` naming its PID; a folder where the lock file cannot be
    written (read-only, full, no permission) raises :class:`FileWriteError` naming the folder and
    the cause, before any work.
    """
    if fcntl is None:  # pragma: no cover - Windows
        return RunFolderLock(folder, None)
    path = folder / LOCK_NAME
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        except (FileNotFoundError, NotADirectoryError):
            raise ConfigError(f"{what} folder {str(folder)!r} does not exist") from None
        except OSError as exc:
            raise _unwritable(folder, what, exc) from exc
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = _pid_in(fd)
            os.close(fd)
            raise _in_use(folder, what, pid) from None
        except OSError as exc:  # a file system without locks
            os.close(fd)
            logger.warning("%s folder %s cannot be locked (%s); a second run there would not be "
                           "refused", what, folder, os_error_cause(exc))
            return RunFolderLock(folder, None)
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # the holder before removed the file as this process locked it: again
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
    except OSError as exc:
        os.close(fd)
        raise _unwritable(folder, what, exc) from exc
    return RunFolderLock(folder, fd)


def _unwritable(folder: Path, what: str, error: OSError) -> FileWriteError:
    out = FileWriteError(f"cannot write in {what} folder {str(folder)!r}: "
                         f"{os_error_cause(error)}")
    out.errno = error.errno
    return out
