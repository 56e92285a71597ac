"""A session reads only inside its own folder.

Every file a session names (in ``session.yaml``, and in a rosbag2 folder's ``metadata.yaml``) must
be a relative name without ``..`` that, once symbolic links are resolved, lies inside the session
folder, with no opt-out: a session is moved and shared as one folder, and a session that could name
any path would let whoever wrote it make ``deformap map`` read any file the user can read.
"""

from __future__ import annotations

from pathlib import Path, PurePath
from typing import Any

from deformap._config import load_yaml
from deformap.errors import ConfigError, FileFormatError

__all__ = ["check_bag_confined", "confined_path"]

_RULE = "a session's files must lie inside its folder, named relative to it without '..'"


def confined_path(where: str, value: Any, root: Path) -> Path:
    """``root / value`` when ``value`` names a file inside the session folder ``root``.

    Parameters
    ----------
    where : str
        Names the entry in messages (``"session.yaml: `pokes[2].cloud`"``).
    value : Any
        The entry's value; a non-empty string.
    root : Path
        The session folder.

    Raises
    ------
    ConfigError
        The value is not a string, is absolute, has a ``..`` part, or resolves (through symbolic
        links) outside ``root``.
    """
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where} must be a file name (a string); got {value!r}")
    name = PurePath(value)
    if name.is_absolute() or ".." in name.parts:
        raise ConfigError(f"{where} is {value!r}, outside the session folder; {_RULE}")
    path = root / name
    try:
        real, base = path.resolve(), root.resolve()
    except (OSError, RuntimeError, ValueError) as exc:  # a link loop, a NUL, a name too long
        raise ConfigError(f"{where} is {value!r:.120}, which cannot be resolved: {exc}") from None
    if not real.is_relative_to(base):
        raise ConfigError(
            f"{where} is {value!r}, a link to {str(real)!r}, outside the session folder; {_RULE}")
    return path


def check_bag_confined(bag: Path) -> list[Path]:
    """Refuse a rosbag2 folder whose ``metadata.yaml`` names storage files outside it.

    ``bag`` itself has passed :func:`confined_path`, so what lies inside it lies inside the
    session folder.

    Returns
    -------
    list of Path
        The files rosbags will open: the bag file itself, or ``metadata.yaml`` and the storage
        files it lists.

    rosbags opens ``bag / PurePath(name).name`` for each ``relative_file_paths`` entry, so a
    ``../`` or absolute entry would silently read another file than the one named, and a storage
    file may be a link out of the folder: both are refused, naming the entry.
    """
    meta = bag / "metadata.yaml"
    if not bag.is_dir():
        return [bag]  # a single .mcap/.db3 file, already confined
    if not meta.is_file():
        return []  # rosbags reports the missing metadata
    confined_path(f"{meta}", "metadata.yaml", bag)
    data = load_yaml(meta, what="the bag's metadata", unreadable=FileFormatError)
    info = data.get("rosbag2_bagfile_information") if isinstance(data, dict) else None
    names = info.get("relative_file_paths") if isinstance(info, dict) else None
    if not isinstance(names, list):
        return [meta]  # not rosbag2 metadata: rosbags refuses it with its own message
    out = [meta]
    for i, value in enumerate(names):
        where = f"{meta}: `rosbag2_bagfile_information.relative_file_paths[{i}]`"
        confined_path(where, value, bag)
        # What rosbags opens (the last part of the name) must stay inside too.
        out.append(confined_path(where, PurePath(value).name, bag))
    return out
