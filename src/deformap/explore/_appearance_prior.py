"""The appearance prior: a map field whose covariance couples places that look alike, with a weight
the pokes learn.

The kernel of a field with prior standard deviation σ and length scale ℓ (the blind field's) is

    k((x, a), (x', a')) = σ² [(1 − w) k_ℓ(x, x') + w k_L(x, x') k_app(a, a')],

``k_ℓ`` the blind field's squared exponential, ``k_app(a, a') = exp(−‖a − a'‖² / ℓ_a²)`` on the
segments' standardised features (a masked cell takes its nearest seen cell's), and ``k_L`` a
squared exponential over the workspace's diagonal. At ``w = 0`` it is the blind kernel; at every
``w`` the prior variance is σ², so ``T_h`` keeps its meaning. It is a sum, not a product
``k_ℓ · (1 − w + w k_app)``, because a product only removes covariance.

``w`` and ``ℓ_a`` range over a small grid (:data:`WEIGHTS` × :data:`LOOK_SCALES`; one half on
``w = 0``, the blind map, the other half uniform over the weights above 0, then ``ℓ_a``: a
spike-and-slab prior), each point's posterior from the pokes' exact marginal likelihood (RW2006
Eq. 2.30). The field on the grid is the Bayesian model average: the mixture's mean and variance
``E[var] + Var[mean]``; where the pokes contradict the looks the posterior moves to ``w = 0``.

References
----------
Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes for Machine Learning, Alg. 2.1,
Eq. 2.30 and Sec. 5.2 (model selection by the marginal likelihood).
Hoeting, J. A., Madigan, D., Raftery, A. E., Volinsky, C. T. (1999). Bayesian model averaging:
a tutorial. Statistical Science 14(4), 382–417.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy import ndimage as ndi

from deformap.explore._appearance import AppearanceImage
from deformap.gp import cholesky_with_jitter, squared_exponential

__all__ = ["BLIND_PRIOR", "LOOK_SCALES", "WEIGHTS", "AppearanceModels", "AppearancePrior",
           "WeightPosterior"]

Array = NDArray[np.float64]

#: The weights ``w`` of the look: 0 the blind map; up to 0.95, never 1, so the blind part always
#: lets two places of one look differ.
WEIGHTS = (0.0, 0.5, 0.8, 0.95)
#: The prior probability of ``w = 0``: the two hypotheses, the looks follow the materials or
#: they do not, equally likely before any poke, so the map leans on the looks only as far as
#: the pokes' Bayes factor for them says.
BLIND_PRIOR = 0.5
#: The look length scales ``ℓ_a``, in units of the segments' standardised features: from looks a
#: noise apart to looks of the image's whole spread.
LOOK_SCALES = (0.5, 1.0, 2.0)


class AppearancePrior:
    """The look of every place on the grid ``xs``, ``ys`` [m] the ``image`` is on, and the kernel."""

    def __init__(self, image: AppearanceImage, xs: Array, ys: Array) -> None:
        self.image = image
        self.xs, self.ys = xs, ys
        self.span_m = float(np.hypot(np.ptp(xs), np.ptp(ys))) or 1.0
        gx, gy = np.meshgrid(xs, ys)
        self.cells_xy = np.column_stack([gx.ravel(), gy.ravel()])
        # a masked cell takes its nearest seen cell's look: a place hidden by the robot is
        # likeliest what surrounds it
        seg = image.segments
        nearest = ndi.distance_transform_edt(seg < 0, return_distances=False,
                                             return_indices=True)  # fmt: skip
        self._look = np.asarray(seg[nearest[0], nearest[1]].ravel(), dtype=np.int64)

    @property
    def looks(self) -> NDArray[np.int64]:
        """``(ny, nx)`` each cell's segment, a masked cell its nearest seen cell's."""
        return self._look.reshape(self.image.segments.shape)

    def cells_of(self, xy: Array) -> NDArray[np.int64]:
        """``(n,)`` flat index of the cell each of ``xy (n, 2)`` [m] lies in (nearest centre)."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        ix = np.clip(np.searchsorted(self.xs, xy[:, 0]), 1, self.xs.size - 1)
        ix -= np.abs(xy[:, 0] - self.xs[ix - 1]) <= np.abs(xy[:, 0] - self.xs[ix])
        iy = np.clip(np.searchsorted(self.ys, xy[:, 1]), 1, self.ys.size - 1)
        iy -= np.abs(xy[:, 1] - self.ys[iy - 1]) <= np.abs(xy[:, 1] - self.ys[iy])
        if self.xs.size == 1:
            ix[:] = 0
        if self.ys.size == 1:
            iy[:] = 0
        return np.asarray(iy * self.xs.size + ix, dtype=np.int64)

    def look_kernel(self, cells_a: NDArray[np.int64], cells_b: NDArray[np.int64],
                    look_scale: float) -> Array:
        """``k_app`` between the looks of two sets of flat cells."""
        feats = self.image.features
        fa, fb = feats[self._look[cells_a]], feats[self._look[cells_b]]
        d2 = np.sum((fa[:, None, :] - fb[None, :, :]) ** 2, axis=-1)
        return np.asarray(np.exp(-d2 / look_scale**2))

    def covariance(self, xy_a: Array, xy_b: Array, *, signal_std: float, length_scale: float,
                   weight: float, look_scale: float) -> Array:
        """``(a, b)`` the kernel (module docstring) between ``xy_a (a, 2)`` and ``xy_b (b, 2)``
        [m], in the field's units squared."""
        blind = squared_exponential(xy_a, xy_b, length_scale=length_scale, signal_std=1.0)
        if weight == 0.0:
            return np.asarray(signal_std**2 * blind)
        near = squared_exponential(xy_a, xy_b, length_scale=self.span_m, signal_std=1.0)
        look = self.look_kernel(self.cells_of(xy_a), self.cells_of(xy_b), look_scale)
        return np.asarray(signal_std**2 * ((1.0 - weight) * blind + weight * near * look))


@dataclass(frozen=True)
class WeightPosterior:
    """The posterior over the prior's grid of ``(w, ℓ_a)``: each grid point's ``weights``,
    ``look_scales`` and ``probability`` (summing to 1), ``(m,)`` each."""

    weights: Array
    look_scales: Array
    probability: Array

    @property
    def mean_weight(self) -> float:
        """The posterior mean of ``w``."""
        return float(self.probability @ self.weights)

    @property
    def look_scale(self) -> float:
        """``ℓ_a`` of the most probable grid point with ``w > 0`` (the look's own scale)."""
        looked = self.weights > 0
        return float(self.look_scales[looked][np.argmax(self.probability[looked])])

    def weight_distribution(self) -> tuple[Array, Array]:
        """``(values, probability)``: the posterior of ``w`` alone, ``ℓ_a`` summed out."""
        values = np.unique(self.weights)
        return values, np.array([self.probability[self.weights == v].sum() for v in values])


def _grid_points() -> tuple[Array, Array, Array]:
    """The grid's ``w``, ``ℓ_a`` and prior probability: :data:`BLIND_PRIOR` on ``w = 0``, the
    rest uniform over the weights above 0, then over ``ℓ_a``."""
    w, la, p = [0.0], [LOOK_SCALES[0]], [BLIND_PRIOR]
    looked = [weight for weight in WEIGHTS if weight > 0]
    for weight in looked:
        for scale in LOOK_SCALES:
            w.append(weight)
            la.append(scale)
            p.append((1.0 - BLIND_PRIOR) / (len(looked) * len(LOOK_SCALES)))
    return np.array(w), np.array(la), np.array(p)


class AppearanceModels:
    """The field over the pokes ``xy (p ≥ 1, 2)`` [m] with ``values``, ``noise (p,)`` under every
    ``(w, ℓ_a)`` of the grid, and their average; ``signal_std``, ``length_scale`` [m] the blind
    field's σ and ℓ."""

    def __init__(self, prior: AppearancePrior, xy: Array, values: Array, noise: Array, *,
                 signal_std: float, length_scale: float) -> None:
        self.prior, self.xy = prior, np.asarray(xy, dtype=float)
        self.signal_std, self.length_scale = signal_std, length_scale
        weights_n = 1.0 / noise**2
        self.constant = float(np.sum(weights_n * values) / np.sum(weights_n))
        resid = values - self.constant
        w, la, prior_p = _grid_points()
        self._factors, self._alphas, lml = [], [], []
        for weight, scale in zip(w, la, strict=True):
            gram = self._cov(self.xy, weight, scale) / signal_std**2
            gram[np.diag_indices_from(gram)] += (noise / signal_std) ** 2
            factor, _ = cholesky_with_jitter(gram, jitter=1e-10, max_jitter=1e-4,
                                             what="the pokes' covariance under the look prior")
            alpha = sla.cho_solve(factor, resid, check_finite=False) / signal_std**2
            log_det = 2.0 * np.sum(np.log(np.diag(factor[0]))) + resid.size * np.log(signal_std**2)
            lml.append(-0.5 * float(resid @ alpha) - 0.5 * log_det)  # RW2006 Eq. 2.30 (less a constant)
            self._factors.append(factor)
            self._alphas.append(alpha)
        log_post = np.log(prior_p) + np.array(lml)
        prob = np.exp(log_post - log_post.max())
        self.posterior = WeightPosterior(w, la, prob / prob.sum())

    def _cov(self, query: Array, weight: float, scale: float) -> Array:
        return self.prior.covariance(query, self.xy, signal_std=self.signal_std,
                                     length_scale=self.length_scale, weight=weight,
                                     look_scale=scale)  # fmt: skip

    def _variance(self, k: int, cross: Array) -> Array:
        """``(q,)`` the posterior variance under grid point ``k`` given ``cross (q, p)``."""
        s2 = self.signal_std**2
        v = sla.solve_triangular(self._factors[k][0], cross.T / np.sqrt(s2), lower=True,
                                 check_finite=False)  # fmt: skip
        return np.asarray(np.maximum(s2 - np.sum(v**2, axis=0), 0.0))

    def predict(self, query: Array) -> tuple[Array, Array]:
        """``(mean, variance)`` at ``query (q, 2)`` [m]: the model average (module docstring)."""
        first = np.zeros(query.shape[0])
        second = np.zeros(query.shape[0])
        exp_var = np.zeros(query.shape[0])
        post = self.posterior
        for k, prob in enumerate(post.probability):
            if prob < 1e-12:
                continue
            cross = self._cov(query, post.weights[k], post.look_scales[k])  # (q, p)
            mean = self.constant + cross @ self._alphas[k]
            first += prob * mean
            second += prob * mean**2
            exp_var += prob * self._variance(k, cross)
        return first, exp_var + np.maximum(second - first**2, 0.0)

    def blind_variance(self, query: Array) -> Array:
        """``(q,)`` the variance at ``query`` under ``w = 0``, the blind map's."""
        return self._variance(0, self._cov(query, 0.0, LOOK_SCALES[0]))

    def covariance_at_mean(self, xy_a: Array, xy_b: Array) -> Array:
        """The prior covariance at the posterior-mean ``w`` and the most probable ``ℓ_a``
        (what the planner's posterior algebra uses)."""
        return self.prior.covariance(xy_a, xy_b, signal_std=self.signal_std,
                                     length_scale=self.length_scale,
                                     weight=self.posterior.mean_weight,
                                     look_scale=self.posterior.look_scale)  # fmt: skip

    def correlation(self, query: Array) -> Array:
        """``(q, p)`` the model-averaged prior correlation of ``query`` with each poke."""
        post = self.posterior
        out = np.zeros((query.shape[0], self.xy.shape[0]))
        for k, prob in enumerate(post.probability):
            if prob >= 1e-12:
                out += prob * self._cov(query, post.weights[k], post.look_scales[k])
        return out / self.signal_std**2
