"""The one policy for the folders runs write into, and for the files written there.

- **Naming**: a run without ``--out`` goes to ``runs/<stem>-<kind>-s<seed>-<YYYYmmdd-HHMMSS>``
  (:func:`default_run_folder`), whatever its kind.
- **Creating**: :func:`create_run_folder` makes the folder before any work; an existing one must
  be empty, so that no earlier result is overwritten (a resumed run reuses its own).
- **Holding**: a run holds its folder's lock for its life (:func:`claim_run_folder`,
  :mod:`deformap.run._lock`): a second writer there is refused naming the holder's PID. A
  resumed run removes the temporaries of the writes a kill cut short.
- **Writing**: every file is written atomically (:mod:`deformap._files`): a run killed at any
  moment leaves the old file or the new one, never half of one; a write the machine refuses (a
  full disk, a read-only file system, a quota, no permission) is one
  :class:`~deformap.errors.FileWriteError` line naming the file and the cause.
"""

from __future__ import annotations

import datetime
import json
import logging
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from deformap._files import atomic_path, remove_temporaries, write_text_atomically
from deformap.cloud.io import path_kind
from deformap.errors import ConfigError
from deformap.run._lock import LOCK_NAME, RunFolderLock, folder_holder, lock_run_folder

__all__ = [
    "RUNS_ROOT", "atomic_path", "claim_run_folder", "create_run_folder", "default_run_folder",
    "run_stem", "to_json", "write_json", "write_text",
]

logger = logging.getLogger(__name__)

RUNS_ROOT = Path("runs")
"""Where runs without ``--out`` go, relative to the working directory."""


def run_stem(name: str | Path) -> str:
    """The stem of a run's folder name: a scenario name, or a file's or folder's own name."""
    text = str(name)
    if text.endswith((".yaml", ".yml")):
        return Path(text).stem
    return Path(text).name or text.strip("/") or "run"


def default_run_folder(stem: str, kind: str, seed: int, *, root: Path = RUNS_ROOT,
                       when: float | None = None) -> Path:
    """``root/<stem>-<kind>-s<seed>-<YYYYmmdd-HHMMSS>``, local time ``when`` (default: now)."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(when))
    return root / f"{stem}-{kind}-s{seed}-{stamp}"


def create_run_folder(folder: Path, *, what: str = "run", resume_hint: bool = False) -> Path:
    """Create ``folder`` (and its parents) for a new run; it may exist only as an empty folder
    (or holding only the lock file of a run killed before it wrote anything).

    ``what`` names what it holds in the messages ("run", "session", "result"); ``resume_hint``
    says that ``--resume`` continues the run already there. A folder that is not empty, a file,
    or one that cannot be created raises :class:`ConfigError` naming ``--out``.
    """
    kind = path_kind(folder)
    if kind == "dir" and (pid := folder_holder(folder)) is not None:
        raise ConfigError(f"{what} folder {str(folder)!r} is in use by another deformap process "
                          f"(PID {pid}); choose another --out")
    if kind == "dir" and any(p.name != LOCK_NAME for p in folder.iterdir()):  # a lock file
        # no process holds is what a run killed before writing anything left
        hint = " or pass --resume" if resume_hint else ""
        raise ConfigError(
            f"{what} folder {str(folder)!r} exists and is not empty; choose another --out{hint}")
    if kind in ("file", "other"):
        raise ConfigError(f"cannot create {what} folder {str(folder)!r} (--out): something that "
                          "is not a folder has that name")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot create {what} folder {str(folder)!r} (--out): "
                          f"{exc.strerror or exc}") from None
    return folder


def claim_run_folder(folder: Path, *, resume: bool = False, what: str = "run",
                     resume_hint: bool = False) -> RunFolderLock:
    """The lock of ``folder`` for this run, to hold (``with``) until the run ends.

    A new run (``resume`` False) creates the folder (:func:`create_run_folder`, ``what`` and
    ``resume_hint`` as there), locks it, and refuses it if another process put a file there
    meanwhile. A resumed run locks the existing folder and removes the temporaries of writes a
    kill cut short. A folder another process holds raises :class:`ConfigError` naming its PID; one
    that cannot be written, :class:`~deformap.errors.FileWriteError` naming the cause; both
    before any work.
    """
    if not resume:
        create_run_folder(folder, what=what, resume_hint=resume_hint)
    lock = lock_run_folder(folder, what=what)
    try:
        if not resume and any(p.name != LOCK_NAME for p in folder.iterdir()):
            raise ConfigError(f"{what} folder {str(folder)!r} was written by another process "
                              "as this run started; choose another --out")
        if resume:
            for path in remove_temporaries(folder):
                logger.info("%s: removed %s, left by a write cut short", folder, path.name)
    except BaseException:
        lock.release()
        raise
    return lock


write_text = write_text_atomically  # ``text`` (UTF-8) to ``path`` atomically; returns ``path``


def _plain(value: Any) -> Any:
    """``value`` as strict JSON data: numpy values as lists and numbers, a non-finite number as
    ``null``, dates and times in ISO 8601 (a YAML date in a session's ``source``)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, (datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, Path):
        return str(value)
    if value is None or isinstance(value, (str, int)):
        return value
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def to_json(data: Any, *, indent: int | None = 2) -> str:
    """``data`` as strict JSON (:func:`_plain`; indented, or one line with ``indent=None``)."""
    return json.dumps(_plain(data), indent=indent, allow_nan=False)


def write_json(path: Path, data: Any) -> Path:
    """Write ``data`` as indented JSON to ``path`` atomically (see :func:`to_json`)."""
    return write_text(path, to_json(data))
