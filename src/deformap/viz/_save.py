"""Writing a figure to a file atomically (:func:`deformap._files.atomic_path`: a run killed while
writing leaves the previous file or the new one), rendered by the figure's own canvas in the
format of the file's suffix, so that no backend is selected and ``pyplot`` is never imported."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from deformap._files import atomic_path
from deformap.errors import InvalidArgumentError

__all__ = ["save_figure"]


def save_figure(fig: Figure, path: str | Path, *, dpi: float, **savefig_kwargs: Any) -> Path:
    """Write ``fig`` to ``path`` at ``dpi`` (raster formats) and return ``path`` as a ``Path``.

    ``savefig_kwargs`` go to :meth:`matplotlib.figure.Figure.savefig`. Raises
    :class:`InvalidArgumentError` if the suffix is no format matplotlib writes or the folder does
    not exist.
    """
    out = Path(path)
    fmt = out.suffix[1:].lower()
    supported = fig.canvas.get_supported_filetypes()
    if fmt not in supported:
        raise InvalidArgumentError(
            f"`path` must end in a figure format ({', '.join('.' + f for f in sorted(supported))}), "
            f"got {str(out)!r}")
    if not out.parent.is_dir():
        raise InvalidArgumentError(
            f"`path` must be in an existing folder, got {str(out)!r} "
            f"({str(out.parent)!r} does not exist)")
    with atomic_path(out) as tmp, open(tmp, "xb") as fh:
        fig.savefig(fh, format=fmt, dpi=dpi, **savefig_kwargs)
    return out
