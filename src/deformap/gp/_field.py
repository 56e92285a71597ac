"""``GaussianRandomField``: the surface and β-field regressor of the paper, exact or grid-sparse."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive, describe
from deformap.errors import InvalidArgumentError
from deformap.gp._exact import ExactState, fit_exact, predict_exact
from deformap.gp._grid import (
    GRID_SPACING_FRACTION,
    GridState,
    fit_grid,
    grid_blas_threads,
    predict_grid_points,
    predict_on_grid,
)
from deformap.gp._kernels import _check_data, check_allocation, grid_points

__all__ = ["AUTO_EXACT_MAX_POINTS", "GaussianRandomField"]

Array = NDArray[np.float64]

_LOG = logging.getLogger(__name__)

#: ``method="auto"``'s largest exact fit: the exact cost grows as n³, the grid's with extent / σ_w.
AUTO_EXACT_MAX_POINTS = 1000
_METHODS = ("auto", "exact", "grid")
#: Range of every hyperparameter and noise: the covariance neither overflows nor turns singular.
HYPERPARAMETER_RANGE = (1e-12, 1e12)


def _hyperparameter(name: str, value: Any) -> float:
    out = check_positive(name, value)
    lo, hi = HYPERPARAMETER_RANGE
    if not lo <= out <= hi:
        raise InvalidArgumentError(f"`{name}` must lie in [{lo:g}, {hi:g}]; got {out:g}")
    return out


class GaussianRandomField:
    """GP regression of a scalar field z(x, y) with the paper's squared-exponential kernel.

    f ~ GP(m, k) with a constant mean m, the inverse-noise-variance weighted data mean, subtracted
    before the fit and added back to every prediction; z = f + ε, ε ~ N(0, σₙ²) (or per point).
    scikit-learn's estimator API (``get_params``, ``set_params``, ``clone``).

    Parameters
    ----------
    length_scale, signal_std, noise_std : float
        σ_w in metres (√2 × scikit-learn's RBF ℓ); σₑ and σₙ in units of z (σₙ where ``fit`` gets
        no per-point noise).
    method : {"auto", "exact", "grid"}
        ``"exact"``: Cholesky, O(n³); ``"grid"``: DTC/SGPR on a regular inducing grid
        (:mod:`deformap.gp._grid`); ``"auto"``: exact up to ``AUTO_EXACT_MAX_POINTS`` points.
    inducing_spacing : float, metres, optional
        Grid method's node spacing; default σ_w / 3.
    jitter, max_jitter : float
        Diagonal jitter relative to σₑ² (:func:`cholesky_with_jitter`).

    A fit sets ``xy_``, ``mean_``, ``method_`` (what ``auto`` resolved to), ``jitter_used_``,
    ``n_inducing_`` (0 for exact) and ``log_marginal_likelihood_`` (RW2006 Eq. 2.30; None for grid).

    References
    ----------
    Caccamo et al. 2016; Rasmussen & Williams 2006, Alg. 2.1 and §8.3; Quiñonero-Candela &
    Rasmussen 2005; Titsias 2009.
    """

    _PARAMS = ("length_scale", "signal_std", "noise_std", "method", "inducing_spacing", "jitter",
               "max_jitter")  # fmt: skip
    _FITTED = ("xy_", "mean_", "method_", "jitter_used_", "n_inducing_",
               "log_marginal_likelihood_")  # fmt: skip

    def __init__(self, *, length_scale: float, signal_std: float, noise_std: float,
                 method: str = "auto", inducing_spacing: float | None = None,
                 jitter: float = 1e-10, max_jitter: float = 1e-4) -> None:  # fmt: skip
        self.length_scale = _hyperparameter("length_scale", length_scale)
        self.signal_std = _hyperparameter("signal_std", signal_std)
        self.noise_std = _hyperparameter("noise_std", noise_std)
        if method not in _METHODS:
            raise InvalidArgumentError(
                f"`method` must be one of {_METHODS}; got {describe(method)}")
        self.method = method
        self.inducing_spacing = (None if inducing_spacing is None
                                 else check_positive("inducing_spacing", inducing_spacing))
        self.jitter = check_positive("jitter", jitter)
        self.max_jitter = check_positive("max_jitter", max_jitter)
        if self.max_jitter < self.jitter:
            raise InvalidArgumentError(
                f"`max_jitter` must be >= `jitter` ({self.jitter:g}); got {self.max_jitter:g}")
        self._state: ExactState | GridState | None = None

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The constructor's parameters (``deep`` is accepted for scikit-learn's API)."""
        return {name: getattr(self, name) for name in self._PARAMS}

    def set_params(self, **params: Any) -> GaussianRandomField:
        """Set constructor parameters, all checked before any is set; returns ``self``, unfitted."""
        unknown = sorted(set(params) - set(self._PARAMS))
        if unknown:
            raise InvalidArgumentError(
                f"`set_params` takes parameters of {list(self._PARAMS)}; got {unknown}")
        checked = GaussianRandomField(**{**self.get_params(), **params})
        for name in self._PARAMS:
            setattr(self, name, getattr(checked, name))
        self._state = None
        for name in self._FITTED:
            self.__dict__.pop(name, None)
        return self

    def __repr__(self) -> str:
        return (f"GaussianRandomField(length_scale={self.length_scale!r}, "
                f"signal_std={self.signal_std!r}, noise_std={self.noise_std!r}, "
                f"method={self.method!r})")

    def fit(self, xy: Any, z: Any, noise_std: Any = None) -> GaussianRandomField:
        """Condition on ``z (n,)`` at ``xy (n, 2)`` metres with ``noise_std`` (float or ``(n,)``;
        default the constructor's); returns ``self``."""
        pts, vals = _check_data(xy, z, min_rows=1)
        noise_var = self._noise(noise_std, pts.shape[0]) ** 2
        weights = 1.0 / noise_var
        self.mean_ = float(np.sum(weights * vals) / np.sum(weights))
        resid = vals - self.mean_
        method = self.method
        if method == "auto":
            method = "exact" if pts.shape[0] <= AUTO_EXACT_MAX_POINTS else "grid"
        hyper = {"length_scale": self.length_scale, "signal_std": self.signal_std,
                 "jitter": self.jitter, "max_jitter": self.max_jitter}
        state: ExactState | GridState
        if method == "exact":
            n = pts.shape[0]
            check_allocation("GaussianRandomField.fit(xy, z) with method 'exact'", (n, n),
                             copies=3)  # the kernel, its Cholesky factor and a difference
            state = fit_exact(pts, resid, noise_var, **hyper)
            self.n_inducing_ = 0
            self.log_marginal_likelihood_: float | None = state.log_marginal_likelihood
        else:
            spacing = self.inducing_spacing or GRID_SPACING_FRACTION * self.length_scale
            with grid_blas_threads():
                state = fit_grid(pts, resid, noise_var, spacing=spacing, **hyper)
            self.n_inducing_ = state.n_inducing
            self.log_marginal_likelihood_ = None
        _LOG.debug("fitted %s GP on %d points", method, pts.shape[0])
        self._state = state
        self.xy_ = pts
        self.method_ = method
        self.jitter_used_ = state.jitter_used
        return self

    def _noise(self, noise_std: Any, n: int) -> Array:
        if noise_std is None:
            return np.full(n, self.noise_std)
        if np.ndim(noise_std) == 0:
            return np.full(n, _hyperparameter("noise_std", noise_std))
        noise = check_array("noise_std", noise_std, (n,), what="noise standard deviations")
        lo, hi = HYPERPARAMETER_RANGE
        if np.any(noise < lo) or np.any(noise > hi):
            raise InvalidArgumentError(
                f"`noise_std` must lie in [{lo:g}, {hi:g}] everywhere; got {noise.min():g} to "
                f"{noise.max():g}")
        return noise

    def _fitted(self) -> ExactState | GridState:
        if self._state is None:
            raise InvalidArgumentError(
                "this GaussianRandomField is not fitted yet; call `fit(xy, z)` before predicting")
        return self._state

    def predict(self, xy: Any, return_std: bool = False) -> Array | tuple[Array, Array]:
        """Posterior mean ``(m,)`` at ``xy (m, 2)`` metres, and with ``return_std`` the latent f's
        std ``(m,)`` (without noise); on a regular grid :meth:`predict_grid` is much faster."""
        state = self._fitted()
        pts = check_array("xy", xy, (None, 2), what="coordinates in metres")
        s = self.signal_std
        if isinstance(state, ExactState):
            mean, std = predict_exact(state, pts, length_scale=self.length_scale, signal_std=s,
                                      return_std=return_std)  # fmt: skip
        else:
            with grid_blas_threads():
                mean, std = predict_grid_points(state, pts, signal_std=s, return_std=return_std)
        mean += self.mean_
        return (mean, std) if return_std and std is not None else mean

    def predict_grid(self, xs: Any, ys: Any, return_std: bool = False
                     ) -> Array | tuple[Array, Array]:  # fmt: skip
        """Posterior mean (and latent std) ``(ny, nx)`` on the grid ``xs (nx,) × ys (ny,)`` metres,
        row = y, column = x (``grid_points`` order reshaped)."""
        state = self._fitted()
        x = check_array("xs", xs, (None,), what="x coordinates in metres", min_rows=1)
        y = check_array("ys", ys, (None,), what="y coordinates in metres", min_rows=1)
        # the points (2 columns), mean and std per cell, and the std's intermediate images
        check_allocation("GaussianRandomField.predict_grid(xs, ys)", (y.size, x.size),
                         copies=6 if return_std else 3)
        s = self.signal_std
        if isinstance(state, ExactState):
            mean, std = predict_exact(state, grid_points(x, y), length_scale=self.length_scale,
                                      signal_std=s, return_std=return_std)  # fmt: skip
            mean = mean.reshape(y.size, x.size)
            std = None if std is None else std.reshape(y.size, x.size)
        else:
            with grid_blas_threads():
                mean, std = predict_on_grid(state, x, y, signal_std=s, return_std=return_std)
        mean = mean + self.mean_
        return (mean, std) if return_std and std is not None else mean
