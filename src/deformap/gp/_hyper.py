"""Hyperparameters by maximum marginal likelihood (RW2006 §5.4.1).

θ = (log σ_w, log σₑ, log σₙ); the constant mean (the data mean) is subtracted first, as in
``GaussianRandomField``. The objective is the exact log marginal likelihood with its analytic
gradient ∂L/∂θⱼ = ½ tr((ααᵀ − K⁻¹) ∂K/∂θⱼ) (RW2006 Eq. 5.9), maximised by L-BFGS-B in log space
from several starting points on a seeded random subset of the data.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy.optimize import minimize

from deformap._validation import check_array, check_int, check_positive, describe
from deformap.errors import InvalidArgumentError, NotPositiveDefiniteError
from deformap.gp._kernels import _check_data, _sqdist, check_allocation

__all__ = ["GPHyperparameters", "default_bounds", "fit_hyperparameters", "log_marginal_likelihood"]

Array = NDArray[np.float64]

_LOG = logging.getLogger(__name__)
_NAMES = ("length_scale", "signal_std", "noise_std")


@dataclass(frozen=True)
class GPHyperparameters:
    """σ_w (metres), σₑ and σₙ (units of z), and log p(z | θ) on the fitted points (nan if none)."""

    length_scale: float
    signal_std: float
    noise_std: float
    log_marginal_likelihood: float = float("nan")


def _lml_and_grad(theta: Array, d2: Array, resid: Array) -> tuple[float, Array]:
    """log p(r | θ) and its gradient in θ = log(σ_w, σₑ, σₙ); ``d2`` are squared distances."""
    w, s, sn = np.exp(theta)
    unit = np.exp(-d2 / w**2)  # the kernel of _kernels, on distances computed once
    kmat = s**2 * unit
    kmat[np.diag_indices_from(kmat)] += sn**2
    try:
        factor = sla.cho_factor(kmat, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        raise NotPositiveDefiniteError(
            f"K + σn²I is not positive definite at σw={w:g}, σe={s:g}, σn={sn:g}; "
            "raise the lower bound of `noise_std`") from None
    alpha = sla.cho_solve(factor, resid, check_finite=False)
    n = resid.size
    lml = -0.5 * resid @ alpha - np.sum(np.log(np.diag(factor[0]))) - 0.5 * n * np.log(2 * np.pi)
    inner = np.outer(alpha, alpha) - sla.cho_solve(factor, np.eye(n), check_finite=False)
    grads = np.array([
        0.5 * np.sum(inner * (s**2 * unit * 2.0 * d2 / w**2)),  # ∂K/∂log σw
        0.5 * np.sum(inner * (2.0 * kmat - 2.0 * sn**2 * np.eye(n))),  # ∂K/∂log σe
        0.5 * np.trace(inner) * 2.0 * sn**2,  # ∂K/∂log σn
    ])  # fmt: skip
    return float(lml), grads


def log_marginal_likelihood(xy: Any, z: Any, *, length_scale: float, signal_std: float,
                            noise_std: float, eval_gradient: bool = False
                            ) -> float | tuple[float, Array]:  # fmt: skip
    """Exact log p(z | θ) of the constant-mean GP (data mean subtracted), RW2006 Eq. 2.30, for
    ``z (n,)`` at ``xy (n, 2)``; with ``eval_gradient`` also its gradient in
    (log σ_w, log σₑ, log σₙ), RW2006 Eq. 5.9."""
    pts, vals = _check_data(xy, z, min_rows=2)
    # the distances, the kernel, K + Σ's factor, its inverse and the gradient's products
    check_allocation("log_marginal_likelihood(xy, z)", (pts.shape[0], pts.shape[0]), copies=6)
    values = (length_scale, signal_std, noise_std)
    theta = np.log([check_positive(n, v) for n, v in zip(_NAMES, values, strict=True)])
    lml, grad = _lml_and_grad(theta, _sqdist(pts, pts), vals - vals.mean())
    return (lml, grad) if eval_gradient else lml


def _diagonal_and_spread(xy: Any, z: Any) -> tuple[float, float]:
    """The bounding-box diagonal D of ``xy`` and the std s of ``z``."""
    return float(np.hypot(*np.ptp(xy, axis=0))), float(np.std(z))


def default_bounds(xy: Any, z: Any) -> Array:
    """``(3, 2)`` bounds (low, high) on (σ_w, σₑ, σₙ) for ``xy (n, 2)``, ``z (n,)``: σ_w in D/1000
    to 2D, D the box diagonal (shorter is noise, longer a plane); σₑ in s/100 to 100s, s the std
    of z; σₙ in 1e-4 s (a near-interpolant a Cholesky still factorises) to 10 s."""
    diag, spread = _diagonal_and_spread(np.asarray(xy, dtype=float), np.asarray(z, dtype=float))
    return np.array(
        [[1e-3 * diag, 2.0 * diag], [1e-2 * spread, 1e2 * spread], [1e-4 * spread, 1e1 * spread]])


def fit_hyperparameters(xy: Any, z: Any, *, rng: np.random.Generator,
                        init: GPHyperparameters | None = None, n_restarts: int = 3,
                        max_points: int = 2000, bounds: Any = None) -> GPHyperparameters:  # fmt: skip
    """The (σ_w, σₑ, σₙ) of largest log marginal likelihood of ``z (n,)`` at ``xy (n, 2)``, and it.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the subset and the restart points (same seed, same result).
    init : GPHyperparameters, optional
        First start; default (D/10, s, s/10) in the terms of :func:`default_bounds`.
    n_restarts : int
        Further starts, log-uniform within ``bounds`` ((3, 2); default :func:`default_bounds`).
    max_points : int
        At most this many points (a random subset) enter the O(n³) objective.
    """
    pts, vals = _check_data(xy, z, min_rows=2)
    if not isinstance(rng, np.random.Generator):
        raise InvalidArgumentError(f"`rng` must be a numpy.random.Generator; got {describe(rng)}")
    n_restarts = check_int("n_restarts", n_restarts, minimum=0)
    max_points = check_int("max_points", max_points, minimum=2)
    if np.std(vals) == 0:
        raise InvalidArgumentError("`z` is constant; there is no signal to fit hyperparameters to")
    if pts.shape[0] > max_points:
        keep = np.sort(rng.choice(pts.shape[0], size=max_points, replace=False))
        pts, vals = pts[keep], vals[keep]
    if bounds is None:
        box = default_bounds(pts, vals)
    else:
        box = check_array("bounds", bounds, (3, 2), what="(low, high) pairs")
        if np.any(box[:, 0] <= 0) or np.any(box[:, 1] < box[:, 0]):
            raise InvalidArgumentError(f"`bounds` must have 0 < low <= high per row; got {box}")
    log_box = np.log(box)
    resid = vals - vals.mean()
    check_allocation("fit_hyperparameters(xy, z) on `max_points`", (pts.shape[0],) * 2, copies=6)
    d2 = _sqdist(pts, pts)
    starts = [_first_start(init, pts, vals, log_box)]
    starts += [rng.uniform(log_box[:, 0], log_box[:, 1]) for _ in range(n_restarts)]
    results = [r for r in (_optimise(t, d2, resid, log_box) for t in starts) if r is not None]
    if not results:
        raise NotPositiveDefiniteError(
            "every start of the likelihood optimisation failed; raise the lower bound of "
            "`noise_std` in `bounds`")
    best = max(results, key=lambda r: r[0])
    w, s, sn = np.exp(best[1])
    _LOG.info("fitted σw=%.4g σe=%.4g σn=%.4g (lml %.4g)", w, s, sn, best[0])
    return GPHyperparameters(float(w), float(s), float(sn), best[0])


def _first_start(init: GPHyperparameters | None, xy: Array, z: Array, log_box: Array) -> Array:
    if init is None:
        diag, spread = _diagonal_and_spread(xy, z)
        guess = np.array([diag / 10, spread, spread / 10])
    elif isinstance(init, GPHyperparameters):
        guess = np.array([check_positive(f"init.{name}", getattr(init, name)) for name in _NAMES])
    else:
        raise InvalidArgumentError(f"`init` must be a GPHyperparameters; got {describe(init)}")
    return np.clip(np.log(guess), log_box[:, 0], log_box[:, 1])


def _optimise(theta0: Array, d2: Array, resid: Array, log_box: Array
              ) -> tuple[float, Array] | None:  # fmt: skip
    def objective(theta: Array) -> tuple[float, Array]:
        try:
            lml, grad = _lml_and_grad(theta, d2, resid)
        except NotPositiveDefiniteError:
            return 1e300, np.zeros(3)
        return -lml, -grad

    res = minimize(objective, theta0, jac=True, method="L-BFGS-B", bounds=log_box)
    if not np.isfinite(res.fun) or res.fun >= 1e300:
        return None
    return -float(res.fun), res.x
