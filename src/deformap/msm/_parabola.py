"""The vertex of a parabola through three points: the refinement and the uncertainty both use it."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["parabola_vertex"]


def parabola_vertex(x: NDArray[np.float64], e: NDArray[np.float64]
                    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:  # fmt: skip
    """Abscissa of the vertex of the parabola through ``(x[..., k], e[..., k])``, k = 0, 1, 2.

    ``x`` must increase along the last axis. Returns the vertices and whether each parabola opens
    upwards (has a minimum); where it does not, the vertex is NaN.
    """
    x0, x1, x2 = x[..., 0], x[..., 1], x[..., 2]
    e0, e1, e2 = e[..., 0], e[..., 1], e[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        curv = ((e2 - e1) / (x2 - x1) - (e1 - e0) / (x1 - x0)) / (x2 - x0)
        slope = (e1 - e0) / (x1 - x0) - curv * (x0 + x1)
        ok = curv > 0.0
        vertex = np.where(ok, -slope / (2.0 * curv), np.nan)
    return np.asarray(vertex, dtype=float), np.asarray(ok, dtype=bool)
