"""Writing a figure (or a recording) to a file atomically, without matplotlib's global state.

Through :func:`deformap._files.atomic_path`: a run killed while a file is being written leaves
either the previous file or the new one, never a truncated one.

The format comes from the file's suffix and is rendered by the figure's own canvas (Agg for raster
formats), so no backend is selected and ``pyplot`` is never imported.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from deformap._files import atomic_path
from deformap.errors import InvalidArgumentError

__all__ = ["save_figure"]


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
    with atomic_path(out) as tmp, open(tmp, "xb") as fh:
        fig.savefig(fh, format=fmt, dpi=dpi, **savefig_kwargs)
    return out
