"""The β-field's nugget: the scatter of β̂ between places on one material that the pokes' own
uncertainties do not explain, estimated for each map from its pokes.

Why
---
A poke's claimed σ is the camera's noise carried through the estimate
(:mod:`deformap.explore._dent_noise`): a repeatability at that place. Pressed at another place of
the same material β̂ also moves with what the camera's noise does not model (the foam's own
variation, the dent's reconstruction at another spot, the contact's placement), so the spread of β̂
between places on one material exceeds the claimed σ. That excess is estimated from each map's
pokes.

Model
-----
Within one class of the region test (:func:`deformap.explore.segment_regions`: the pokes it finds
to be one material), ``β̂ᵢ = μ_c + ηᵢ + εᵢ``: ``μ_c`` the class's β (a fixed effect, one per class),
``ηᵢ ~ N(0, τ²)`` the place-to-place scatter (the nugget, the same for every poke of the map) and
``εᵢ ~ N(0, σᵢ²)`` the poke's claimed uncertainty. τ is the maximum a posteriori of the restricted
(REML) likelihood of that one-way random-effects model (Patterson & Thompson 1971; Harville 1977),
the likelihood of the within-class contrasts, which the class means do not enter:

    ℓ_R(τ) = −½ Σ_c [ Σ_{i∈c} ln vᵢ + ln Σ_{i∈c} 1/vᵢ + Σ_{i∈c} (β̂ᵢ − μ̂_c)² / vᵢ ],  vᵢ = σᵢ² + τ²

(μ̂_c the class's inverse-variance weighted mean; a class of one poke contributes nothing), with a
half-Cauchy prior on τ (Gelman 2006, the weakly-informative prior for a variance component met by
few groups) whose scale is the pokes' median claimed σ: before any data, the scatter the camera
does not explain is expected of the order of the scatter it does, and the Cauchy's tail lets the
data say it is many times more. The scale is the estimator's own (a camera with more noise claims
more), no number of the simulated world. The prior's mode is τ = 0, so pokes that scatter no more
than they claim give τ̂ = 0 (the field then takes their own σ, at least the floor).

Why within the classes, not from the β-field's marginal likelihood
------------------------------------------------------------------
The β-field's prior (σₑ 0.3 over σ_w 0.2 m) explains a difference of a few tenths between pokes a
decimetre or more apart as signal, so a nugget from its marginal likelihood is only identified by
pokes closer together than σ_w; the few pokes of a map (five or six, a decimetre or two apart) leave
it unidentified, while a step between two foams at close pokes is soaked up as noise. The classes
say which pokes are one material whatever their distance, and removing each class's mean removes the
steps between materials. Only the classes the region test examined and kept whole count: a class
of fewer pokes than the test examines (3 with the default ``region_prior_dof``) is no evidence of
one material (two pokes are never split, so a pair straddling two foams would read their step as
scatter, and that scatter could merge the two foams' classes).
The classes depend on the noise and the noise on τ:
:func:`with_nugget` starts from the claimed σ, estimates τ from the classes
found, finds the classes again with σᵢ² + τ² and repeats until the classes no longer change (at
most :data:`MAX_ROUNDS` rounds). The region test's smallest step (``min_step``, 0.05 in β) keeps
one material whose scatter the first round underrates from being cut in two.

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

__all__ = ["MAX_ROUNDS", "beta_pokes", "estimate_nugget", "restricted_log_posterior",
           "with_nugget"]

#: Most rounds of classes and nugget (:func:`with_nugget`).
MAX_ROUNDS = 5

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
    """τ̂, the MAP nugget of pokes ``beta (k,)`` with claimed ``std (k,)`` in classes ``labels (k,)``.

    Only the classes of at least ``min_class_size`` pokes (and 2) count. 0 when none is left
    (nothing is known of the scatter within a material) or the pokes scatter no more than they
    claim. The prior's scale is the median ``std`` of all the pokes (module docstring).
    """
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
    tau = float(found.x) if found.success and -found.fun >= values[best] else float(taus[best])
    return tau


def with_nugget(pokes: PokeSet, config: ExplorationConfig) -> PokeSet:
    """``pokes`` (β, each noise its claimed σ at least the floor) with the map's nugget τ̂ added to
    every poke's noise in variance, ``√(σᵢ² + τ̂²)`` (module docstring).

    The classes are the region test's on the β values (:func:`deformap.explore.segment_regions` with the
    exploration's ``max_regions``, ``region_prior_dof`` and the β-field's smallest step and floor):
    found first with the claimed σ, τ̂ estimated within those the test examined (as many pokes as
    it tests a group of: a smaller class, a pair above all, is no evidence of one material), found
    again with the noise that τ̂ gives, until they no longer change (at most
    :data:`MAX_ROUNDS` rounds). ``pokes`` unchanged under
    ``beta_field.nugget: off``.
    """
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
    """The pokes of the β-field as the mapper fits it: each poke's claimed σ raised to the floor
    (:func:`deformap.explore.beta_noise_floor`), plus the map's nugget (:func:`with_nugget`)."""
    return with_nugget(PokeSet.of(records, beta_noise_floor(config)), config)
