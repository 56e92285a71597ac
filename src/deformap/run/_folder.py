"""The one policy for the folders runs write into, and for the files written there.

- **Naming**: a run without ``--out`` goes to ``runs/<stem>-<kind>-s<seed>-<YYYYmmdd-HHMMSS>``
  (:func:`default_run_folder`), whatever its kind (explore, record, map, study, reproduce).
- **Creating**: :func:`create_run_folder` makes the folder before any work, so that one that
  cannot be made fails at once (naming ``--out``); an existing folder must be empty, so that no
  result of an earlier run is ever overwritten. A run that is resumed reuses its own folder.
- **Writing**: every file goes to a temporary file in the same folder, is flushed and fsynced,
  renamed onto its name (``os.replace``) and the folder fsynced (:func:`write_text`,
  :func:`write_json`, :func:`atomic_path`): a run killed at any moment leaves the old file or the
  new one, never half of one.
"""

from __future__ import annotations

import datetime
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from deformap._files import atomic_path, write_text_atomically
from deformap.cloud.io import path_kind
from deformap.errors import ConfigError

__all__ = [
    "RUNS_ROOT",
    "atomic_path",
    "create_run_folder",
    "default_run_folder",
    "run_stem",
    "to_json",
    "write_json",
    "write_text",
]

RUNS_ROOT = Path("runs")
"""Where runs without ``--out`` go, relative to the working directory."""


def run_stem(name: str | Path) -> str:
    """The stem of a run's folder name: a scenario name, or a file's or folder's own name."""
    text = str(name)
    if text.endswith((".yaml", ".yml")):
        return Path(text).stem
    return Path(text).name or text.strip("/") or "run"


def default_run_folder(
    stem: str, kind: str, seed: int, *, root: Path = RUNS_ROOT, when: float | None = None
) -> Path:
    """``root/<stem>-<kind>-s<seed>-<YYYYmmdd-HHMMSS>``, local time ``when`` (default: now)."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(when))
    return root / f"{stem}-{kind}-s{seed}-{stamp}"


def create_run_folder(folder: Path, *, what: str = "run", resume_hint: bool = False) -> Path:
    """Create ``folder`` (and its parents) for a new run; it may exist only as an empty folder.

    Parameters
    ----------
    folder : Path
    what : str
        What the folder holds, for the messages ("run", "session", "result").
    resume_hint : bool
        Say that ``--resume`` continues the run already there.

    Raises
    ------
    ConfigError
        ``folder`` is a folder that is not empty, or a file, or cannot be created; the message
        names ``--out``.
    """
    kind = path_kind(folder)
    if kind == "dir" and any(folder.iterdir()):
        hint = " or pass --resume" if resume_hint else ""
        raise ConfigError(
            f"{what} folder {str(folder)!r} exists and is not empty; choose another --out{hint}"
        )
    if kind in ("file", "other"):
        raise ConfigError(
            f"cannot create {what} folder {str(folder)!r} (--out): something that is not a "
            "folder has that name"
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(
            f"cannot create {what} folder {str(folder)!r} (--out): {exc.strerror or exc}"
        ) from None
    return folder


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns ``path``."""
    return write_text_atomically(path, text)


def _plain(value: Any) -> Any:
    """``value`` as strict JSON data: numpy arrays and scalars as lists and numbers, a non-finite
    number as ``null`` (JSON has no NaN or infinity), dates and times in ISO 8601 (a YAML date a
    user wrote in a session's ``source``), tuples as lists."""
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
    """``data`` as strict JSON (indented, or on one line with ``indent=None``), see
    :func:`_plain`: never a bare ``NaN``."""
    return json.dumps(_plain(data), indent=indent, allow_nan=False)


def write_json(path: Path, data: Any) -> Path:
    """Write ``data`` as indented JSON to ``path`` atomically (see :func:`to_json`)."""
    return write_text(path, to_json(data))
