"""Exact Gaussian-process regression by Cholesky factorisation (RW2006 Alg. 2.1), on the
unit-variance kernel K̂ = K / σₑ² so that the jitter is relative to the signal variance.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from deformap.errors import NotPositiveDefiniteError
from deformap.gp._kernels import _se

__all__: list[str] = []

Array = NDArray[np.float64]
Factor = tuple[Array, bool]

_LOG = logging.getLogger(__name__)
_CHUNK = 2048  # test points per block: bounds the (n, chunk) cross-covariance in memory


def cholesky_with_jitter(matrix: Array, *, jitter: float, max_jitter: float, what: str
                         ) -> tuple[Factor, float]:  # fmt: skip
    """``cho_factor``'s lower factor of ``matrix + j·I`` and ``j``, ×10 from ``jitter`` to
    ``max_jitter`` (relative to σₑ²); beyond it :class:`NotPositiveDefiniteError`."""
    diag = np.arange(matrix.shape[0])
    base = matrix[diag, diag].copy()
    j = jitter
    while True:
        matrix[diag, diag] = base + j
        try:
            factor = sla.cho_factor(matrix, lower=True, overwrite_a=False, check_finite=False)
        except np.linalg.LinAlgError:
            if j >= max_jitter:
                break
            j = min(j * 10.0, max_jitter)
            continue
        if j > jitter:
            _LOG.info("%s needed jitter %.1e (relative to σe²)", what, j)
        return factor, j
    matrix[diag, diag] = base
    raise NotPositiveDefiniteError(
        f"{what} is not positive definite even with jitter {max_jitter:g} × σe² added to its "
        "diagonal; increase `noise_std`, check for duplicate or nearly coincident points, or raise "
        "`max_jitter`")


@dataclass(frozen=True, kw_only=True)
class ExactState:
    """What an exact fit keeps: data, the Cholesky factor of K̂ + Λ/σₑ², and α̂."""

    xy: Array
    factor: Factor
    alpha: Array  # (K̂ + Λ/σₑ²)⁻¹ (z − mean)
    jitter_used: float
    log_marginal_likelihood: float


def fit_exact(xy: Array, resid: Array, noise_var: Array, *, length_scale: float,
              signal_std: float, jitter: float, max_jitter: float) -> ExactState:  # fmt: skip
    """Factorise K̂ + Λ/σₑ² and solve for α̂ (RW2006 Alg. 2.1, lines 2–3)."""
    s2 = signal_std**2
    kmat = _se(xy, xy, length_scale)
    kmat[np.diag_indices_from(kmat)] += noise_var / s2
    factor, used = cholesky_with_jitter(
        kmat, jitter=jitter, max_jitter=max_jitter, what="the data covariance K + σn²I")
    alpha = sla.cho_solve(factor, resid, check_finite=False)
    # The factor is of K/σe²: log|K| = log|K̂| + n log σe², and yᵀK⁻¹y = yᵀK̂⁻¹y / σe².
    n = resid.size
    logdet = 2.0 * np.sum(np.log(np.diag(factor[0]))) + n * np.log(s2)
    lml = -0.5 * float(resid @ alpha) / s2 - 0.5 * logdet - 0.5 * n * np.log(2 * np.pi)
    return ExactState(xy=xy, factor=factor, alpha=alpha, jitter_used=used,
                      log_marginal_likelihood=float(lml))  # fmt: skip


def predict_exact(state: ExactState, points: Array, *, length_scale: float, signal_std: float,
                  return_std: bool) -> tuple[Array, Array | None]:  # fmt: skip
    """Posterior mean (without the constant) and latent std at ``points`` (RW2006 Alg. 2.1, 4–6)."""
    mean = np.empty(points.shape[0])
    std = np.empty(points.shape[0]) if return_std else None
    for start in range(0, points.shape[0], _CHUNK):
        block = slice(start, start + _CHUNK)
        kstar = _se(state.xy, points[block], length_scale)  # (n, chunk), unit variance
        mean[block] = kstar.T @ state.alpha
        if std is not None:
            v = sla.solve_triangular(state.factor[0], kstar, lower=True, check_finite=False)
            var = 1.0 - np.einsum("ij,ij->j", v, v)
            std[block] = signal_std * np.sqrt(np.maximum(var, 0.0))
    return mean, std
