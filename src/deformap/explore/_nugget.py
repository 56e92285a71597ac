"""The β-field's nugget τ: the scatter of β̂ between places on one material that the pokes' own
uncertainties (the camera's noise, :mod:`deformap.explore._dent_noise`) do not explain, estimated
for each map from its pokes.

Within one class of the region test, ``β̂ᵢ = μ_c + ηᵢ + εᵢ`` with ``ηᵢ ~ N(0, τ²)`` and
``εᵢ ~ N(0, σᵢ²)``. τ̂ is the maximum a posteriori of the restricted (REML) likelihood of that
one-way random-effects model (Patterson & Thompson 1971; Harville 1977),

    ℓ_R(τ) = −½ Σ_c [ Σ_{i∈c} ln vᵢ + ln Σ_{i∈c} 1/vᵢ + Σ_{i∈c} (β̂ᵢ − μ̂_c)² / vᵢ ],  vᵢ = σᵢ² + τ²

(μ̂_c the class's inverse-variance weighted mean), under a half-Cauchy prior on τ (Gelman 2006)
scaled by the pokes' median σᵢ, whose mode τ = 0 gives τ̂ = 0 to pokes that scatter no more than
they claim. Only classes of as many pokes as the region test examines count. Classes and τ depend
on each other: :func:`with_nugget` alternates until the classes no longer change, at most
:data:`MAX_ROUNDS` rounds.

References
----------
Patterson, H. D., Thompson, R. (1971). Recovery of inter-block information when block sizes are
unequal. Biometrika 58(3), 545–554. Harville, D. A. (1977). Maximum likelihood approaches to
variance component estimation. JASA 72(358), 320–338. Gelman, A. (2006). Prior distributions for
variance parameters in hierarchical models. Bayesian Analysis 1(3), 515–534.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from deformap._validation import check_array
from deformap.errors import InvalidArgumentError
from deformap.explore._classes import segment_regions
from deformap.explore._config import ExplorationConfig
from deformap.explore._field import REGION_MIN_STEP_BETA, PokeSet, beta_noise_floor
from deformap.explore._records import PokeRecord

__all__ = ["MAX_ROUNDS", "beta_pokes", "estimate_nugget", "restricted_log_posterior", "with_nugget"]

MAX_ROUNDS = 5  #: Most rounds of classes and nugget (:func:`with_nugget`).

_GRID = 241  # τ values of the coarse search, geometric between the scale / 1000 and the upper end


def restricted_log_posterior(tau: float, beta: NDArray[np.float64], std: NDArray[np.float64],
                             labels: NDArray[np.int64], prior_scale: float,
                             min_class_size: int = 2) -> float:
    """``ℓ_R(τ) − ln(1 + (τ / prior_scale)²)`` (module docstring), up to a constant, over the
    classes of at least ``min_class_size`` pokes."""
    total = -np.log1p((tau / prior_scale) ** 2)
    for c in np.unique(labels):
        members = labels == c
        if np.count_nonzero(members) < max(2, min_class_size):
            continue
        v = std[members] ** 2 + tau**2
        w = 1.0 / v
        mean = np.sum(w * beta[members]) / np.sum(w)
        total -= 0.5 * (np.sum(np.log(v)) + np.log(np.sum(w))
                        + np.sum(w * (beta[members] - mean) ** 2))  # fmt: skip
    return float(total)


def estimate_nugget(beta: NDArray[np.float64], std: NDArray[np.float64],
                    labels: NDArray[np.int64], *, min_class_size: int = 2) -> float:
    """τ̂, the MAP nugget of pokes ``beta (k,)`` with claimed ``std (k,)`` in classes ``labels (k,)``
    of at least ``min_class_size`` (and 2) pokes; 0 when no such class is left."""
    b = check_array("beta", beta, (None,), min_rows=1)
    s = check_array("std", std, (b.size,), what="standard deviations")
    lab = np.asarray(labels).reshape(-1)
    if lab.size != b.size:
        raise InvalidArgumentError(
            f"`labels` must have one class per poke ({b.size}); got {lab.size}")
    if np.any(s <= 0):
        raise InvalidArgumentError(f"`std` must be positive everywhere; got {s.min():g}")
    classes, counts = np.unique(lab, return_counts=True)
    counted = classes[counts >= max(2, min_class_size)]
    if not counted.size:
        return 0.0
    scale = float(np.median(s))
    # the within-class residuals bound what τ can be: ten times their largest spread
    spread = max(float(np.ptp(b[lab == c])) for c in counted)
    upper = 10.0 * max(spread, scale)
    taus = np.concatenate([[0.0], np.geomspace(scale * 1e-3, upper, _GRID)])

    def posterior(t: float) -> float:
        return restricted_log_posterior(t, b, s, lab, scale, min_class_size)

    values = np.array([posterior(t) for t in taus])
    best = int(np.argmax(values))
    if best == 0:
        return 0.0
    lo, hi = taus[best - 1], taus[min(best + 1, taus.size - 1)]
    found = minimize_scalar(lambda t: -posterior(t), bounds=(lo, hi), method="bounded",
                            options={"xatol": scale * 1e-4})
    return float(found.x) if found.success and -found.fun >= values[best] else float(taus[best])


def with_nugget(pokes: PokeSet, config: ExplorationConfig) -> PokeSet:
    """``pokes`` with the map's nugget τ̂ added to every poke's noise, ``√(σᵢ² + τ̂²)`` (module
    docstring); unchanged under ``beta_field.nugget: off``."""
    if config.beta_field.nugget == "off" or len(pokes) < 2:
        return pokes
    floor = beta_noise_floor(config)
    flat = np.zeros((1, 1))
    # the smallest class the region test examines (segment_regions: n ≥ 3 and ν₀ + n − 2 ≥ 2)
    examined = max(3, int(np.ceil(4 - config.region_prior_dof)))
    tau, labels = 0.0, None
    for _ in range(MAX_ROUNDS):
        found = segment_regions(flat, pokes.values, np.hypot(pokes.noise, tau), floor=floor,
                                min_step=REGION_MIN_STEP_BETA, max_regions=config.max_regions,
                                prior_dof=config.region_prior_dof).poke_labels  # fmt: skip
        if labels is not None and np.array_equal(found, labels):
            break
        labels, before = found, tau
        tau = estimate_nugget(pokes.values, pokes.noise, labels, min_class_size=examined)
        if tau == before:  # the same noise finds the same classes again
            break
    return replace(pokes, noise=np.hypot(pokes.noise, tau), nugget=tau)


def beta_pokes(records: Sequence[PokeRecord], config: ExplorationConfig) -> PokeSet:
    """The β-field's pokes: each claimed σ raised to the floor, plus the map's nugget."""
    return with_nugget(PokeSet.of(records, beta_noise_floor(config)), config)
