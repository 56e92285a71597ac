"""The ``sha256`` manifest of a session, written by ``write_session`` and checked as each file is
read: a file whose digest differs, or that a manifest does not list, is refused. A session
without one is read unchecked."""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from pathlib import Path

from deformap.errors import FileFormatError
from deformap.replay._format import SessionHeader

__all__ = ["manifest_of", "sha256_file", "verify_digest"]

_CHUNK = 1 << 20


def sha256_file(path: Path) -> str:
    """The SHA-256 of a file's bytes, as 64 lowercase hex digits."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while chunk := fh.read(_CHUNK):
                digest.update(chunk)
    except OSError as exc:
        raise FileFormatError(f"{path}: cannot read it: {exc.strerror or exc}") from None
    return digest.hexdigest()


def manifest_of(root: Path, files: Iterable[Path]) -> dict[str, str]:
    """``{name relative to root (posix): digest}`` of ``files``, sorted by name."""
    return {p.relative_to(root).as_posix(): sha256_file(p)
            for p in sorted(files, key=lambda p: p.relative_to(root).as_posix())}  # fmt: skip


def verify_digest(header: SessionHeader, path: Path) -> None:
    """Refuse ``path`` when the session has a manifest that does not list it or disagrees."""
    if not header.sha256:
        return
    want = header.sha256.get(path)
    if want is None:
        raise FileFormatError(
            f"{path}: not in the session's `sha256` manifest ({len(header.sha256)} files); "
            "every file a session with a manifest reads must be listed")
    got = sha256_file(path)
    if got != want:
        raise FileFormatError(
            f"{path}: SHA-256 is {got[:16]}…, the session's manifest says {want[:16]}…; the "
            "file changed after it was recorded")
