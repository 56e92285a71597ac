"""The paper's squared-exponential kernel and the regular-grid helper.

k(xᵢ, xⱼ) = σₑ² exp(−‖xᵢ − xⱼ‖² / σ_w²) (Caccamo et al. 2016), no factor 2: σ_w is √2 × the ℓ of
scikit-learn's ``RBF`` (RW2006 Eq. 2.31). It is separable, σₑ² k₁(x, x') k₁(y, y') with
k₁(a, b) = exp(−(a − b)² / σ_w²), which the grid method relies on.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError

__all__ = ["MAX_ALLOCATION_BYTES", "check_allocation", "grid_points", "squared_exponential"]

Array = NDArray[np.float64]

#: Most bytes one call of a public function of :mod:`deformap.gp` may allocate for its arrays,
#: checked before it allocates them: far above a map's (a million cells is 8 MB a layer, a
#: thousand pokes' covariance 8 MB), far below what a mistaken size asks for.
MAX_ALLOCATION_BYTES = 8 * 2**30


def check_allocation(what: str, shape: tuple[int, ...], *, copies: int = 1) -> None:
    """Refuse, before it is allocated, ``copies`` float64 arrays of ``shape`` (the largest a
    call holds at once) beyond :data:`MAX_ALLOCATION_BYTES`, in one line naming ``what`` (the
    call and its arguments), the shape and the size."""
    need = 8 * copies * int(np.prod([int(n) for n in shape], dtype=object))
    if need > MAX_ALLOCATION_BYTES:
        dims = " × ".join(f"{int(n):,}" for n in shape)
        raise InvalidArgumentError(
            f"{what} needs {need / 2**30:,.1f} GiB ({copies} float64 array(s) of {dims}); at "
            f"most {MAX_ALLOCATION_BYTES / 2**30:g} GiB: use a coarser grid or fewer points")


def _check_data(xy: Any, z: Any, *, min_rows: int) -> tuple[Array, Array]:
    """Observations ``z (n,)`` at ``xy (n, 2)`` metres, at least ``min_rows`` of them."""
    pts = check_array("xy", xy, (None, 2), what="coordinates in metres", min_rows=min_rows)
    vals = check_array("z", z, (None,), what="values", min_rows=min_rows)
    if vals.size != pts.shape[0]:
        raise InvalidArgumentError(
            f"`z` must have one value per row of `xy` ({pts.shape[0]}); got {vals.size}")
    return pts, vals


def _sqdist(x1: Array, x2: Array) -> Array:
    """``(n, m)`` squared distances between ``(n, d)`` and ``(m, d)`` arrays."""
    # differences, not the expanded quadratic form, which cancels far from the origin
    d2 = (x1[:, 0, None] - x2[None, :, 0]) ** 2
    for axis in range(1, x1.shape[1]):
        d2 += (x1[:, axis, None] - x2[None, :, axis]) ** 2
    return d2


def _se(x1: Array, x2: Array, length_scale: float) -> Array:
    """Unit-variance kernel matrix exp(−‖x1ᵢ − x2ⱼ‖² / σ_w²)."""
    return np.exp(-_sqdist(x1, x2) / length_scale**2)


def _se_1d(a: Array, b: Array, length_scale: float) -> Array:
    """``(n, m)`` one-dimensional factor k₁(aᵢ, bⱼ)."""
    return np.exp(-((a[:, None] - b[None, :]) ** 2) / length_scale**2)


def squared_exponential(x1: Any, x2: Any, *, length_scale: float, signal_std: float) -> Array:
    """The kernel matrix ``(n, m)`` between ``x1 (n, 2)`` and ``x2 (m, 2)`` metres."""
    a = check_array("x1", x1, (None, 2), what="coordinates in metres")
    b = check_array("x2", x2, (None, 2), what="coordinates in metres")
    w = check_positive("length_scale", length_scale)
    s = check_positive("signal_std", signal_std)
    check_allocation("squared_exponential(x1, x2)", (a.shape[0], b.shape[0]), copies=2)
    return s**2 * _se(a, b, w)


def grid_points(xs: Any, ys: Any) -> Array:
    """``(ny*nx, 2)`` points of the grid ``xs (nx,) × ys (ny,)``, point ``iy * nx + ix`` at
    ``(xs[ix], ys[iy])``: ``values.reshape(ny, nx)`` is ``predict_grid``'s image."""
    x = check_array("xs", xs, (None,), what="x coordinates in metres", min_rows=1)
    y = check_array("ys", ys, (None,), what="y coordinates in metres", min_rows=1)
    check_allocation("grid_points(xs, ys)", (y.size, x.size), copies=4)
    gx, gy = np.meshgrid(x, y)
    return np.column_stack([gx.ravel(), gy.ravel()])
