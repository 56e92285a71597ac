"""Writing a figure (or a recording) to a file atomically, without matplotlib's global state.

The file is written under a temporary name beside its destination (same folder, so the same file
system), fsynced, then renamed onto the destination with :func:`os.replace`, and the folder is
fsynced so that the rename itself is durable. A run killed while a file is being written therefore
leaves either the previous file or the new one, never a truncated one; the temporary file of a
failed write is removed.

The format comes from the file's suffix and is rendered by the figure's own canvas (Agg for raster
formats), so no backend is selected and ``pyplot`` is never imported.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from deformap.errors import InvalidArgumentError

__all__ = ["save_figure", "writing_atomically"]


def _fsync_folder(folder: Path) -> None:
    if os.name == "posix":  # folders cannot be opened for fsync on Windows
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextlib.contextmanager
def writing_atomically(out: Path) -> Iterator[Path]:
    """Yield a temporary path to write; on success it is fsynced and renamed onto ``out``.

    If the block raises, the temporary file is removed and ``out`` is left as it was.
    """
    # a hidden name unique to this write; open() honours the umask, unlike mkstemp's 0600
    tmp = out.with_name(f".{out.name}.{secrets.token_hex(4)}.tmp")
    try:
        yield tmp
        with open(tmp, "r+b") as fh:  # writable: Windows cannot fsync a read-only handle
            os.fsync(fh.fileno())
        os.replace(tmp, out)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise
    _fsync_folder(out.parent)


def save_figure(fig: Figure, path: str | Path, *, dpi: float, **savefig_kwargs: Any) -> Path:
    """Write ``fig`` to ``path`` atomically and return ``path`` as a :class:`~pathlib.Path`.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to render.
    path : str or Path
        The destination; its suffix names the format (``.png``, ``.pdf``, ``.svg``, ...). An existing
        file is replaced only once the new one is completely written.
    dpi : float
        Resolution of raster formats.
    **savefig_kwargs
        Passed on to :meth:`matplotlib.figure.Figure.savefig` (e.g. ``bbox_inches="tight"``).

    Raises
    ------
    InvalidArgumentError
        If the suffix of ``path`` is not a format matplotlib writes, or its folder does not exist.
    """
    out = Path(path)
    fmt = out.suffix[1:].lower()
    supported = fig.canvas.get_supported_filetypes()
    if fmt not in supported:
        raise InvalidArgumentError(
            f"`path` must end in a figure format ({', '.join('.' + f for f in sorted(supported))}), "
            f"got {str(out)!r}"
        )
    if not out.parent.is_dir():
        raise InvalidArgumentError(
            f"`path` must be in an existing folder, got {str(out)!r} "
            f"({str(out.parent)!r} does not exist)"
        )
    with writing_atomically(out) as tmp, open(tmp, "xb") as fh:
        fig.savefig(fh, format=fmt, dpi=dpi, **savefig_kwargs)
    return out
