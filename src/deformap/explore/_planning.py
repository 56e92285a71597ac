"""Non-myopic poke planning: the fewest further pokes that bring the map field under ``T_h``.

A GP's posterior variance does not depend on the values (RW2006 Eq. 2.26), so the pokes after
which the largest variance over the domain falls below ``T_h`` can be planned before any is made:
a covering design over a grid of candidates for ``m = 1, 2, …`` pokes in turn. A design scores
the variance above ``T_h`` summed over the domain, ties broken by the largest variance. The plan
for ``m`` is that for ``m − 1`` plus the best candidate, improved by exchange passes (Fedorov
1972) that move each planned poke to the candidate that best complements the others; the first
``m`` whose plan reaches ``T_h`` is the plan. The loop plans again after every poke.

References
----------
Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes for Machine Learning, Eq. 2.26
(the posterior algebra is :class:`deformap.gp.PosteriorDesign`).
Fedorov, V. V. (1972). Theory of Optimal Experiments. Academic Press (the exchange algorithm).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_int, check_positive
from deformap.errors import InvalidArgumentError
from deformap.gp import PosteriorDesign

__all__ = ["PokePlan", "plan_pokes"]

Array = NDArray[np.float64]
#: ``(a (n, 2), b (m, 2)) -> (n, m)`` a prior covariance between places [m], in the field's units
#: squared, its diagonal ``signal_std²``.
Covariance = Callable[[Array, Array], Array]


@dataclass(frozen=True)
class PokePlan:
    """The further pokes planned, first the one to make next.

    Attributes
    ----------
    targets : (m, 2) float, metres
        The planned pokes, ordered by the field's variance there now (largest first).
    max_variance : float
        The largest variance over the domain once they are all made with their assumed noise.
    reaches : bool
        Whether ``max_variance`` is at or below the threshold (else ``targets`` is the best
        ``max_new`` found).
    """

    targets: Array
    max_variance: float
    reaches: bool


def _use_covariance(gp: PosteriorDesign, covariance: Covariance, poked_xy: Array,
                    candidates: Array, domain: Array) -> None:
    """Replace the design's kernel matrices by ``covariance``'s (its algebra holds for any prior
    whose diagonal is ``signal_std²``)."""
    gp.k_pp = covariance(poked_xy, poked_xy)
    gp.k_pc = covariance(poked_xy, candidates)
    gp.k_pd = covariance(poked_xy, domain)
    gp.k_cc = covariance(candidates, candidates)
    gp.k_cd = covariance(candidates, domain)


def _best_addition(gp: PosteriorDesign, chosen: list[int], threshold: float
                   ) -> tuple[int, tuple[float, float]]:  # fmt: skip
    """The candidate not in ``chosen`` whose addition (an exact rank-one update of the posterior)
    leaves the least variance above ``threshold`` summed over the domain (then the smallest
    largest variance), and that score."""
    after = gp.variance_after_adding(chosen)
    excess = np.maximum(after - threshold, 0.0).sum(axis=1)
    worst = np.asarray(after.max(axis=1))
    excess[chosen] = np.inf  # a second poke on the same place is never the better plan
    pick = int(np.lexsort((worst, excess))[0])
    return pick, (float(excess[pick]), float(worst[pick]))


def plan_pokes(poked_xy: Array, poked_noise: Array, candidates: Array, domain: Array, *,
               signal_std: float, length_scale: float, new_noise: float | Array, threshold: float,
               max_new: int, max_passes: int = 4,
               covariance: Covariance | None = None) -> PokePlan:
    """The fewest further pokes among ``candidates`` that bring the field's largest variance
    over ``domain`` to ``threshold`` or below (method: module docstring).

    ``poked_xy (p, 2)`` [m] and ``poked_noise (p,)`` are the pokes so far (``p`` may be 0),
    ``candidates (c, 2)`` and ``domain (d, 2)`` [m] where a poke may go and where the variance
    must fall, ``new_noise`` (scalar or ``(c,)``) the σ assumed for a planned poke, ``max_new``
    the most further pokes, ``max_passes`` the exchange passes per plan size, ``covariance`` the
    prior (default the squared exponential of ``signal_std`` and ``length_scale`` [m]).
    """
    poked_xy = check_array("poked_xy", poked_xy, (None, 2), what="metres")
    poked_noise = check_array("poked_noise", poked_noise, (poked_xy.shape[0],))
    candidates = check_array("candidates", candidates, (None, 2), what="metres", min_rows=1)
    domain = check_array("domain", domain, (None, 2), what="metres", min_rows=1)
    for name, value in (("signal_std", signal_std), ("length_scale", length_scale),
                        ("threshold", threshold)):
        check_positive(name, value)
    if np.ndim(new_noise) == 0:
        new_noise = check_positive("new_noise", new_noise)
    else:
        new_noise = check_array("new_noise", new_noise, (candidates.shape[0],))
        if np.any(new_noise <= 0):
            raise InvalidArgumentError(
                f"`new_noise` must be positive standard deviations; got {new_noise.min()!r}")
    if np.any(poked_noise <= 0):
        raise InvalidArgumentError(
            f"`poked_noise` must be positive standard deviations; got {poked_noise.min()!r}")
    max_new = check_int("max_new", max_new, minimum=1)
    max_passes = check_int("max_passes", max_passes, minimum=0)
    gp = PosteriorDesign(poked_xy, poked_noise, candidates, domain, length_scale=length_scale,
                         signal_std=signal_std, candidate_noise_std=new_noise)
    if covariance is not None:
        _use_covariance(gp, covariance, poked_xy, candidates, domain)
    chosen: list[int] = []
    best = (np.inf, np.inf)
    for _ in range(min(max_new, candidates.shape[0])):
        pick, best = _best_addition(gp, chosen, threshold)
        chosen = [*chosen, pick]
        for _ in range(max_passes):
            moved = False
            for i in range(len(chosen)):
                others = chosen[:i] + chosen[i + 1:]
                pick, score = _best_addition(gp, others, threshold)
                if score < best and pick != chosen[i]:
                    chosen, best, moved = [*others[:i], pick, *others[i:]], score, True
            if not moved:
                break
        if best[1] <= threshold:
            break
    # poke first where the field is least known now
    _, _, var_now = gp.posterior([])
    order = sorted(range(len(chosen)), key=lambda i: (-var_now[chosen[i]], i))
    targets = candidates[np.array([chosen[i] for i in order])]
    return PokePlan(targets=np.array(targets, dtype=float), max_variance=best[1],
                    reaches=best[1] <= threshold)
