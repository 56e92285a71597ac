"""The paper's squared-exponential kernel and the regular-grid helper.

The kernel is k(xᵢ, xⱼ) = σₑ² exp(−‖xᵢ − xⱼ‖² / σ_w²) (Caccamo et al. 2016), with *no* factor 2
in the denominator: ``length_scale`` σ_w here equals √2 times the ℓ of scikit-learn's ``RBF``.
The kernel is separable, k = σₑ² k₁(x, x') k₁(y, y') with k₁(a, b) = exp(−(a − b)² / σ_w²); the
grid method (``_grid.py``) relies on that.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive

__all__ = ["grid_points", "squared_exponential"]


def _sqdist(x1: NDArray[np.float64], x2: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(n, m)`` squared distances between validated ``(n, d)`` and ``(m, d)`` arrays."""
    # Differences, not the expanded quadratic form: at 1e-10 relative accuracy the expansion
    # cancels badly for coordinates far from the origin (0.6 m apart, σ_w a few cm).
    d2 = (x1[:, 0, None] - x2[None, :, 0]) ** 2
    for axis in range(1, x1.shape[1]):
        d2 += (x1[:, axis, None] - x2[None, :, axis]) ** 2
    return d2


def _se_of_sqdist(d2: NDArray[np.float64], length_scale: float) -> NDArray[np.float64]:
    """Unit-variance squared exponential exp(−d² / σ_w²) of squared distances ``d2``."""
    return np.exp(-d2 / length_scale**2)


def _se(
    x1: NDArray[np.float64], x2: NDArray[np.float64], length_scale: float
) -> NDArray[np.float64]:
    """Unit-variance squared exponential between validated ``(n, d)`` and ``(m, d)`` arrays."""
    return _se_of_sqdist(_sqdist(x1, x2), length_scale)


def _se_1d(
    a: NDArray[np.float64], b: NDArray[np.float64], length_scale: float
) -> NDArray[np.float64]:
    """``(n, m)`` one-dimensional unit factor k₁(aᵢ, bⱼ) = exp(−(aᵢ − bⱼ)² / σ_w²)."""
    return np.exp(-((a[:, None] - b[None, :]) ** 2) / length_scale**2)


def squared_exponential(
    x1: Any, x2: Any, *, length_scale: float, signal_std: float
) -> NDArray[np.float64]:
    """The paper's kernel matrix k(x1ᵢ, x2ⱼ) = σₑ² exp(−‖x1ᵢ − x2ⱼ‖² / σ_w²).

    Parameters
    ----------
    x1 : (n, 2) float, metres
    x2 : (m, 2) float, metres
    length_scale : float, metres
        σ_w (no factor 2 in the denominator).
    signal_std : float, metres
        σₑ, the prior standard deviation of the field.

    Returns
    -------
    (n, m) float, square metres

    References
    ----------
    Caccamo et al. 2016 (the GP surface model); Rasmussen & Williams 2006, Eq. 2.31, σ_w² = 2ℓ².
    """
    a = check_array("x1", x1, (None, 2), what="coordinates in metres")
    b = check_array("x2", x2, (None, 2), what="coordinates in metres")
    w = check_positive("length_scale", length_scale)
    s = check_positive("signal_std", signal_std)
    return s**2 * _se(a, b, w)


def grid_points(xs: Any, ys: Any) -> NDArray[np.float64]:
    """``(ny*nx, 2)`` points of the regular grid ``xs × ys``, row-major: row = y, column = x.

    Point ``iy * nx + ix`` is ``(xs[ix], ys[iy])``, so ``values.reshape(ny, nx)`` turns a vector of
    per-point values into an image whose rows run along y, as ``predict_grid`` returns it.

    Parameters
    ----------
    xs : (nx,) float, metres
    ys : (ny,) float, metres
    """
    x = check_array("xs", xs, (None,), what="x coordinates in metres", min_rows=1)
    y = check_array("ys", ys, (None,), what="y coordinates in metres", min_rows=1)
    gx, gy = np.meshgrid(x, y)
    return np.column_stack([gx.ravel(), gy.ravel()])
