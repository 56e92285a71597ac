"""What every reader shares: path checks, the units rule, NaN handling, error wrapping.

Whatever a broken file makes a parser raise becomes one :class:`~deformap.errors.FileFormatError`
naming the file, so callers catch only the ``DeformapError`` family.
"""

from __future__ import annotations

import logging
import struct
import tokenize
import zipfile
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_path
from deformap.cloud._pointcloud import PointCloud
from deformap.errors import DeformapError, FileFormatError, InvalidArgumentError

__all__ = ["MM_EXTENT_THRESHOLD", "UNITS", "check_body_size", "check_colors", "check_text_rows",
           "check_units",
           "finish_cloud", "pack_rgb", "parse_errors", "path_kind", "readable_path",
           "unpack_rgb"]

logger = logging.getLogger(__name__)

#: Unit names accepted by the readers and the factor that turns them into metres.
UNITS = {"m": 1.0, "mm": 1e-3}

#: A cloud read as metres whose largest |coordinate| exceeds this is taken to be in millimetres:
#: a tabletop scene lies within a few metres of any sensible origin, while in millimetres its
#: coordinates reach the hundreds.
MM_EXTENT_THRESHOLD = 20.0

# What numpy, struct, zipfile, zlib, lzf, pydantic and ast (a .npy header) raise on malformed
# bytes; anything else is a bug of ours and must surface as such.
_PARSE_ERRORS: tuple[type[BaseException], ...] = (
    ValueError, TypeError, KeyError, IndexError, EOFError, OverflowError, MemoryError,
    RuntimeError, UnicodeDecodeError, struct.error, zipfile.BadZipFile, zlib.error, OSError,
    SyntaxError, tokenize.TokenError)

# Bytes of ascii numbers and separators. A binary body of at least _TEXT_MIN_BYTES made only of
# them is an ascii body under a binary header: random float bits fall in the set with probability
# 27/256 per byte, so 16 bytes of real binary data do with probability below 1e-15.
_TEXT_BYTES = frozenset(b"0123456789+-.eEnaifNAIF \t\r\n")
_TEXT_MIN_BYTES = 16


def pack_rgb(colors: NDArray[np.float64]) -> NDArray[Any]:
    """``0x00RRGGBB`` words of (n, 3) colours in [0, 1], 8 bits a channel."""
    rgb = np.round(colors * 255).astype(np.uint32)
    return (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]


def unpack_rgb(words: NDArray[Any]) -> NDArray[np.uint8]:
    """(n, 3) uint8 R, G, B of ``0xAARRGGBB`` words (alpha ignored): any 4-byte values, read for
    their bits in their byte order (a float word with an alpha byte may be NaN)."""
    bits = np.ascontiguousarray(words).view(words.dtype.str[0] + "u4").astype(np.uint32)
    return ((bits[:, None] >> np.array([16, 8, 0], dtype=np.uint32)) & 0xFF).astype(np.uint8)


def check_units(units: Any) -> float:
    """Return the metres-per-unit factor of ``units`` (``"m"`` or ``"mm"``)."""
    if not isinstance(units, str) or units not in UNITS:
        raise InvalidArgumentError(f"`units` must be one of {sorted(UNITS)}; got {units!r}")
    return UNITS[units]


def check_body_size(path: Path, what: str, need: int, body: bytes | memoryview | int, *,
                    exact: bool = True, text: bool = False) -> None:
    """Refuse a data section of another size than the ``need`` bytes its header declares.

    Called before anything is allocated for the data, so a forged count cannot ask for gigabytes.
    ``body`` is the bytes present (or only their number: then any surplus is refused); ``exact``
    refuses surplus bytes that are not ASCII whitespace too; a ``text=False`` section made only
    of ascii numbers is refused as an ascii body under a binary header. ``what`` names the
    section in the message.
    """
    have = body if isinstance(body, int) else len(body)
    if (not text and not isinstance(body, int) and have >= _TEXT_MIN_BYTES
            and _TEXT_BYTES.issuperset(bytes(body[:4096]))):  # fmt: skip
        raise FileFormatError(
            f"{path}: {what}: expected {need} bytes of binary data, got {have} bytes of text "
            "(an ascii body under a binary header?)")
    if have < need:
        raise FileFormatError(
            f"{path}: {what}: expected {need} bytes, the file holds {have}; the file is "
            "truncated or the header's count is wrong")
    if exact and have > need and (isinstance(body, int) or bytes(body[need:]).strip()):
        raise FileFormatError(
            f"{path}: {what}: expected {need} bytes, the file holds {have} ({have - need} "
            "more); the header's count is too low or the file is corrupted")


def check_text_rows(path: Path, what: str, body: bytes, values: int | None) -> None:
    """Refuse an ascii body cut short: one that does not end at a line break after its last row
    (a file cut inside its last number would read as another, shorter number), or whose last row
    holds other than ``values`` values (``None``: not checked, the last row being another
    element's). Spaces and tabs after the last line break are allowed; ``what`` names the body.
    """
    if not body.rstrip(b" \t").endswith(b"\n"):
        tail = body.rstrip()[-24:].decode("ascii", "replace")
        raise FileFormatError(
            f"{path}: {what} does not end at a line break after its last row (it ends in "
            f"{tail!r}): the file was cut, perhaps inside its last number")
    if values is None:
        return
    rows = body.rstrip()
    last = rows[rows.rfind(b"\n") + 1:].split()
    if len(last) != values:
        raise FileFormatError(
            f"{path}: {what}: its last row holds {len(last)} values where the header declares "
            f"{values}: the file was cut or the row damaged")


def path_kind(path: str | Path) -> str:
    """``"file"``, ``"dir"``, ``"other"`` or ``"missing"``; a name the system refuses (too long,
    no search permission) is a FileFormatError."""
    path = Path(path)
    try:
        if path.is_file():
            return "file"
        if path.is_dir():
            return "dir"
        return "other" if path.exists() else "missing"
    except OSError as exc:
        raise FileFormatError(f"{path}: cannot look this path up: {exc.strerror or exc}") from None


def readable_path(path: Any) -> Path:
    """Validate that ``path`` names an existing regular file."""
    p = check_path("path", path)
    kind = path_kind(p)
    if kind == "missing":
        raise FileFormatError(f"{p}: no such file")
    if kind != "file":
        raise FileFormatError(f"{p}: not a regular file")
    return p


@contextmanager
def parse_errors(path: Path, what: str) -> Iterator[None]:
    """Turn a parser's exception into a FileFormatError naming ``path`` and ``what`` it read."""
    try:
        yield
    except DeformapError:
        raise
    except _PARSE_ERRORS as exc:
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise FileFormatError(
            f"{path}: could not read {what}: {type(exc).__name__}: {detail[:200]}") from exc


def check_colors(where: Path | str, colors: NDArray[Any], field: str) -> NDArray[np.float64]:
    """``(n, 3)`` float64 colours in [0, 1] from a file's integers in [0, 255] or floats in
    [0, 1]; a NaN or out-of-range value is a FileFormatError naming ``field`` and the point."""
    raw = np.asarray(colors).reshape(-1, 3)
    kind = raw.dtype.kind
    if kind not in "iuf":
        raise FileFormatError(f"{where}: colour field {field!r} has dtype {raw.dtype}, not numbers")
    with np.errstate(invalid="ignore"):
        values = raw.astype(np.float64)
    low, high, what = (0.0, 255.0, "integers") if kind in "iu" else (0.0, 1.0, "floats")
    bad = ~((values >= low) & (values <= high)).all(axis=1)  # NaN fails too
    if bad.any():
        row = int(np.argmax(bad))
        shown = ", ".join(f"{v:g}" for v in values[row])
        raise FileFormatError(
            f"{where}: colour field {field!r} of point {row} is ({shown}); {what} must lie in "
            f"[{low:g}, {high:g}] ({int(bad.sum())} of {len(values)} points are out of range "
            "or NaN)")
    return values / 255.0 if kind in "iu" else values


def finish_cloud(path: Path | str, xyz: NDArray[Any], colors: NDArray[Any] | None,
                 extras: dict[str, NDArray[Any]], *, scale: float, drop_nan: bool,
                 frame: str = "world", color_field: str = "colors"
                 ) -> tuple[PointCloud, dict[str, NDArray[Any]]]:  # fmt: skip
    """Apply the NaN policy, the colour check and the units rule, and build the cloud.

    Rows with a NaN or infinite coordinate are refused, or with ``drop_nan`` dropped (logged)
    from ``colors`` and ``extras`` too; an empty result is refused. ``path`` names the source.
    """
    # Widening a signalling NaN (a corrupted float32) raises "invalid"; NaN is handled just below.
    with np.errstate(invalid="ignore"):
        xyz = np.asarray(xyz, dtype=np.float64).reshape(-1, 3)
    if xyz.shape[0] == 0:
        raise FileFormatError(f"{path}: the cloud is empty (0 points)")
    finite = np.isfinite(xyz).all(axis=1)
    n_bad = int(xyz.shape[0] - finite.sum())
    if n_bad:
        if not drop_nan:
            raise FileFormatError(
                f"{path}: {n_bad} of {xyz.shape[0]} points have a NaN or infinite x/y/z; "
                "pass drop_nan=True to drop them")
        logger.warning(
            "%s: dropped %d of %d points with NaN or infinite x/y/z", path, n_bad, xyz.shape[0])
        xyz = xyz[finite]
        colors = None if colors is None else colors[finite]
        extras = {k: v[finite] for k, v in extras.items()}
        if xyz.shape[0] == 0:
            raise FileFormatError(f"{path}: every point has a NaN or infinite x/y/z")
    if colors is not None:
        colors = check_colors(path, colors, color_field)
    largest = float(np.abs(xyz).max())
    if scale == 1.0 and largest > MM_EXTENT_THRESHOLD:
        raise FileFormatError(
            f"{path}: coordinates reach {largest:.4g}, which looks like millimetres, not metres "
            f"(limit {MM_EXTENT_THRESHOLD:g} m); pass units='mm' if the file is in millimetres")
    try:
        cloud = PointCloud(xyz * scale, colors, frame=frame)
    except InvalidArgumentError as exc:
        raise FileFormatError(f"{path}: {exc}") from exc
    return cloud, extras
