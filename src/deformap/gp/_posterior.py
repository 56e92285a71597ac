"""Posterior algebra that needs no observed values: variance of a design, and the linear smoother.

The posterior covariance depends on where the observations are and on their noise, not on their
values (RW2006 Eq. 2.24, 2.26): :class:`PosteriorDesign` conditions on the observations made plus
any subset of candidates, and :func:`variance_after_adding` adds one more at each candidate by the
exact rank-one update ``σ²ₐ(x) = σ²(x) − cov(c, x)² / (σ²(c) + σₙ²)``. The mean is linear in the
data, ``m = K*ₓ (K + Σ)⁻¹ y`` (RW2006 §2.6): :func:`apply_smoother` applies that map to any ``y``
without forming it. Places are ``(n, 2)`` metres; ``length_scale`` σ_w, ``signal_std`` σₑ.

References
----------
Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes for Machine Learning, Eq. 2.24,
2.26 and §2.6.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError
from deformap.gp._exact import cholesky_with_jitter
from deformap.gp._kernels import _se, check_allocation, squared_exponential

__all__ = ["PosteriorDesign", "apply_smoother", "variance_after_adding"]

Array = NDArray[np.float64]


def _per_candidate(name: str, value: Any, shape: tuple[int, ...], *, allow_zero: bool) -> Array:
    """``value``, a number or an array of ``shape``, as one finite number > 0 (≥ 0) per candidate."""
    size = int(np.prod(shape))
    message = (f"`{name}` must be a number {'>=' if allow_zero else '>'} 0 or ({size},) of them; "
               f"got {value!r}")
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidArgumentError(message) from None
    if out.ndim == 0:
        return np.full(size, check_positive(name, float(out), allow_zero=allow_zero))
    if (out.shape != shape or not np.all(np.isfinite(out))
            or np.any(out < 0 if allow_zero else out <= 0)):
        raise InvalidArgumentError(message)
    return out


def variance_after_adding(variance: Any, covariance: Any, candidate_variance: Any,
                          noise_var: float | Array) -> Array:
    """``(c, d)`` posterior variance on the domain after one more observation at each candidate,
    row ``j`` ``variance − covariance[j]² / (candidate_variance[j] + noise_var)``, from the
    posterior now: ``variance (d,)`` on the domain, ``covariance (c, d)`` between candidates and
    domain, ``candidate_variance (c,)``; ``noise_var`` ≥ 0, one for all or ``(c,)``."""
    var = np.asarray(variance, dtype=float)
    cov = np.asarray(covariance, dtype=float)
    var_c = np.asarray(candidate_variance, dtype=float)
    if cov.shape != (var_c.size, var.size):
        raise InvalidArgumentError(
            f"`covariance` must be (candidates, domain) = ({var_c.size}, {var.size}); "
            f"got {cov.shape}")
    noise = _per_candidate("noise_var", noise_var, var_c.shape, allow_zero=True)
    return np.asarray(var[None, :] - cov**2 / (var_c + noise)[:, None])


class PosteriorDesign:
    """A GP's posterior over a domain given noisy observations made and chosen candidates (the
    kernel matrices between observations, candidates and domain are computed once).

    Parameters
    ----------
    observed_xy, observed_noise_std : (p, 2), (p,) float
        The observations made (``p`` may be 0) and their noise standard deviations (> 0).
    candidates, domain : (c, 2), (d, 2) float
        Places where an observation may be added; where the posterior is wanted.
    candidate_noise_std : float or (c,) float
        Noise standard deviation (> 0) of an observation at each candidate, or one for all.
    """

    def __init__(self, observed_xy: Any, observed_noise_std: Any, candidates: Any, domain: Any,
                 *, length_scale: float, signal_std: float, candidate_noise_std: Any) -> None:
        xy = check_array("observed_xy", observed_xy, (None, 2), what="metres")
        noise = check_array("observed_noise_std", observed_noise_std, (xy.shape[0],))
        if np.any(noise <= 0):
            raise InvalidArgumentError(
                f"`observed_noise_std` must be positive standard deviations; got {noise.min()!r}")
        cand = check_array("candidates", candidates, (None, 2), what="metres")
        dom = check_array("domain", domain, (None, 2), what="metres")
        new_noise = _per_candidate("candidate_noise_std", candidate_noise_std, (cand.shape[0],),
                                   allow_zero=False)  # fmt: skip
        kern = {"length_scale": length_scale, "signal_std": signal_std}
        p, c, d = xy.shape[0], cand.shape[0], dom.shape[0]
        check_allocation("PosteriorDesign(observed_xy, candidates, domain)",
                         (p * p + p * c + p * d + c * c + 2 * c * d,))  # kernels, a posterior
        self.prior = check_positive("signal_std", signal_std) ** 2
        self.new_var = new_noise**2
        self.observed_noise = noise
        self.k_pp = squared_exponential(xy, xy, **kern)
        self.k_pc = squared_exponential(xy, cand, **kern)
        self.k_pd = squared_exponential(xy, dom, **kern)
        self.k_cc = squared_exponential(cand, cand, **kern)
        self.k_cd = squared_exponential(cand, dom, **kern)

    def posterior(self, chosen: Sequence[int]) -> tuple[Array, Array, Array]:
        """The posterior given the observations made and the ``chosen`` candidates (indices,
        each observed once): the variance ``(d,)`` on the domain, the covariance ``(c, d)``
        between each candidate and the domain, and the variance ``(c,)`` at each candidate."""
        idx = np.asarray(chosen, dtype=np.int64).reshape(-1)
        n_candidates = self.k_cc.shape[0]
        if idx.size and (idx.min() < 0 or idx.max() >= n_candidates):
            raise InvalidArgumentError(
                f"`chosen` must index the {n_candidates} candidates; got {idx.tolist()}")
        noise = np.concatenate([self.observed_noise**2, self.new_var[idx]])
        k_ss = np.block([[self.k_pp, self.k_pc[:, idx]],
                         [self.k_pc[:, idx].T, self.k_cc[np.ix_(idx, idx)]]])
        if k_ss.size == 0:
            return (np.full(self.k_cd.shape[1], self.prior), self.k_cd.copy(),
                    np.full(self.k_cd.shape[0], self.prior))
        # RW2006 Eq. 2.24 on the covariance scaled to unit prior variance (jitter relative to σe²)
        (chol, lower), _ = cholesky_with_jitter((k_ss + np.diag(noise)) / self.prior,
                                                jitter=1e-12, max_jitter=1e-6,
                                                what="the covariance of the observations")
        scale = 1.0 / np.sqrt(self.prior)
        v_d = sla.solve_triangular(chol, scale * np.vstack([self.k_pd, self.k_cd[idx]]),
                                   lower=lower, check_finite=False)
        v_c = sla.solve_triangular(chol, scale * np.vstack([self.k_pc, self.k_cc[idx]]),
                                   lower=lower, check_finite=False)
        var_d = self.prior - np.sum(v_d**2, axis=0)
        cov = self.k_cd - v_c.T @ v_d
        var_c = self.prior - np.sum(v_c**2, axis=0)
        return var_d, cov, var_c

    def variance_after_adding(self, chosen: Sequence[int]) -> Array:
        """``(c, d)`` variance on the domain after the ``chosen`` candidates and one more: row
        ``j`` adds candidate ``j`` (:func:`variance_after_adding` on :meth:`posterior`)."""
        return variance_after_adding(*self.posterior(chosen), self.new_var)


def apply_smoother(data_xy: Any, noise_std: Any, query_xy: Any, values: Any, *,
                   length_scale: float, signal_std: float, jitter: float = 1e-10,
                   max_jitter: float = 1e-4) -> Array:
    """``K(query, data) (K + Σ)⁻¹ values``, ``Σ = diag(noise_std²)``: the ``(q,)`` or ``(q, k)``
    zero-prior-mean posterior mean at ``query_xy (q, 2)`` of ``values (n,)`` or ``(n, k)`` observed
    at ``data_xy (n, 2)``; ``jitter``, ``max_jitter`` as in :class:`GaussianRandomField`."""
    data = check_array("data_xy", data_xy, (None, 2), what="metres", min_rows=1)
    noise = check_array("noise_std", noise_std, (data.shape[0],))
    query = check_array("query_xy", query_xy, (None, 2), what="metres")
    vals = np.asarray(values, dtype=float)
    if vals.ndim not in (1, 2) or vals.shape[0] != data.shape[0]:
        raise InvalidArgumentError(
            f"`values` must be ({data.shape[0]},) or ({data.shape[0]}, k); got {vals.shape}")
    w = check_positive("length_scale", length_scale)
    s = check_positive("signal_std", signal_std)
    n, q = data.shape[0], query.shape[0]
    check_allocation("apply_smoother(data_xy, query_xy)", (n * n * 3 + q * n * 2,))
    # the unit-variance kernel and the noise in units of σe: the σe² of K* and of K cancel
    gram = _se(data, data, w) + np.diag((noise / s) ** 2)
    factor, _ = cholesky_with_jitter(gram, jitter=jitter, max_jitter=max_jitter,
                                     what="the data covariance K + Σ")  # fmt: skip
    weights = sla.cho_solve(factor, vals, check_finite=False)
    return np.asarray(_se(query, data, w) @ weights)
