"""A session reads only inside its own folder, and only the files it recorded.

Every file a session names (in ``session.yaml`` and a rosbag2 ``metadata.yaml``) must be a
relative name without ``..`` that, links resolved, lies inside the session folder, with no
opt-out: otherwise whoever wrote a session could make ``deformap map`` read any file. The
``sha256`` manifest ``write_session`` leaves is checked as each file is read: a file whose digest
differs, or that the manifest does not list, is refused, and so is a manifest entry whose file is
missing.

``session.yaml`` itself is covered by its first line, the seal ``# deformap seal: sha256 <hex> of
the lines below`` (:func:`seal`), which YAML reads as a comment. A session with a seal or a
manifest must have both, the seal matching: an edit anywhere in the file, the manifest removed, or
the seal removed while the manifest stays, is refused. A session with neither (written by hand) is
read unchecked; nothing short of a key could tell a session stripped of both from one never sealed.

No file or folder in a session may be a symbolic link (:func:`check_no_links`): a link makes what
is read depend on what lies outside the folder, which the manifest cannot cover.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Iterable
from pathlib import Path, PurePath
from typing import Any

from deformap._config import load_yaml
from deformap.errors import ConfigError, FileFormatError

__all__ = ["check_bag_confined", "check_manifest_complete", "check_no_links", "check_seal",
           "confined_path", "manifest_of", "seal", "sha256_file", "verify_digest"]

_RULE = "a session's files must lie inside its folder, named relative to it without '..'"


def confined_path(where: str, value: Any, root: Path) -> Path:
    """``root / value`` when ``value`` names a file inside the session folder ``root``; else a
    ConfigError naming the entry ``where``."""
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
    """The files rosbags will open for the bag (a single file, or ``metadata.yaml`` and the
    storage files it lists), each refused when outside the folder (rosbags opens the last part of
    each name, so both the name and that part are checked)."""
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


def sha256_file(path: Path) -> str:
    """The SHA-256 of a file's bytes, as 64 lowercase hex digits."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while chunk := fh.read(1 << 20):
                digest.update(chunk)
    except OSError as exc:
        raise FileFormatError(f"{path}: cannot read it: {exc.strerror or exc}") from None
    return digest.hexdigest()


def manifest_of(root: Path, files: Iterable[Path]) -> dict[str, str]:
    """``{name relative to root (posix): digest}`` of ``files``, sorted by name."""
    return {p.relative_to(root).as_posix(): sha256_file(p)
            for p in sorted(files, key=lambda p: p.relative_to(root).as_posix())}  # fmt: skip


def verify_digest(manifest: dict[Path, str], path: Path) -> None:
    """Refuse ``path`` when there is a ``manifest`` (path → digest) that does not list it or
    disagrees."""
    if not manifest:
        return
    want = manifest.get(path)
    if want is None:
        raise FileFormatError(
            f"{path}: not in the session's `sha256` manifest ({len(manifest)} files); "
            "every file a session with a manifest reads must be listed")
    got = sha256_file(path)
    if got != want:
        raise FileFormatError(
            f"{path}: SHA-256 is {got[:16]}…, the session's manifest says {want[:16]}…; the "
            "file changed after it was recorded")


#: The first line of a sealed ``session.yaml``: the SHA-256 of every byte after it.
_SEAL = re.compile(rb"# deformap seal: sha256 ([0-9a-f]{64}) of the lines below")


def seal(body: str) -> str:
    """``body`` (the text of a ``session.yaml``) with its seal line in front."""
    digest = hashlib.sha256(body.encode("utf-8")).hexdigest()
    return f"# deformap seal: sha256 {digest} of the lines below\n{body}"


def check_seal(file: Path, manifest: dict[Path, str]) -> None:
    """Refuse ``file`` (a ``session.yaml`` whose parsed ``sha256`` manifest is ``manifest``) when
    its seal does not match the lines below it, or when exactly one of seal and manifest is there
    (module docstring)."""
    try:
        with open(file, "rb") as fh:
            first = fh.readline(256)
            digest = hashlib.sha256()
            while chunk := fh.read(1 << 20):
                digest.update(chunk)
    except OSError as exc:
        raise FileFormatError(f"{file}: cannot read it: {exc.strerror or exc}") from None
    found = _SEAL.fullmatch(first.rstrip(b"\r\n"))
    if found is None:
        if manifest:
            raise FileFormatError(
                f"{file}: has a `sha256` manifest but its first line is not the seal "
                "('# deformap seal: sha256 …'), so the file itself cannot be checked: it was "
                "rewritten after it was recorded (a session edited by hand drops `sha256`)")
        return
    want, got = found.group(1).decode("ascii"), digest.hexdigest()
    if got != want:
        raise FileFormatError(
            f"{file}: SHA-256 of the lines below its seal is {got[:16]}…, the seal says "
            f"{want[:16]}…; the file changed after it was recorded")
    if not manifest:
        raise FileFormatError(
            f"{file}: is sealed but has no `sha256` manifest: a session recorded with one is "
            "read only with it")


def check_manifest_complete(file: Path, manifest: dict[Path, str]) -> None:
    """Refuse a ``manifest`` that lists files missing from the session, naming them."""
    missing = [p for p in manifest if not p.is_file()]
    if missing:
        shown = ", ".join(repr(p.name) for p in missing[:5])
        more = f" and {len(missing) - 5} more" if len(missing) > 5 else ""
        raise FileFormatError(
            f"{file}: the `sha256` manifest lists {len(missing)} file(s) missing from the "
            f"session: {shown}{more}; the session lost files after it was recorded")


def check_no_links(root: Path) -> None:
    """Refuse a session folder ``root`` holding a symbolic link anywhere (module docstring);
    ``root`` itself may be named through one."""
    for folder, dirs, names in os.walk(root, followlinks=False):
        for name in sorted((*dirs, *names)):
            path = Path(folder) / name
            if path.is_symlink():
                try:
                    target = os.readlink(path)
                except OSError:
                    target = "?"
                raise ConfigError(
                    f"{path}: a symbolic link (to {target!r:.120}) in the session folder; a "
                    "session's files may not be links: copy the file into the folder")
