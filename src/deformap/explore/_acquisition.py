"""Where to poke next, from the β-field's variance on a grid.

Strategies
----------
``paper``
    Caccamo et al. 2016, Sec. III-D: a random cell among those whose variance exceeds the threshold
    ``T_h`` (drawn with the explicit generator, so a seed fixes the run).
``max-variance``
    The cell of largest variance (ties broken by the first in row-major order).
``min-max-variance``
    A one-step look-ahead: the candidate whose addition leaves the smallest *largest* posterior
    variance over the grid. A GP's posterior variance does not depend on the observed values, only
    on where they are (RW2006 Eq. 2.26), so the look-ahead is exact before the poke is made. It is
    myopic, though: the poke that lowers the worst cell most now is not the first of the fewest
    pokes that bring every cell under ``T_h``.
``planned`` (the default)
    The first of the fewest further pokes that bring the largest variance under ``T_h``, planned
    all together (:mod:`deformap.explore._planning`) and planned again after every poke. How
    many pokes each strategy needs on the simulated scenarios is in the README ("Results", the
    paper's Table I).

Boundary pokes (``boundary_pokes`` > 0, after any strategy)
    Once the variance is below ``T_h`` everywhere, the map is "known" in the paper's sense, but its
    region boundaries are not: the β-field's length scale (``BetaFieldConfig.length_scale_m``)
    smooths a block edge over as much, and more pokes placed for variance alone leave the isopleths
    where they were (README, "Region accuracy": a lower ``T_h`` against boundary pokes). Each
    boundary poke goes where a region boundary is least certain, by the *straddle* score of
    level-set estimation (Bryan et al. 2005), ``1.96 σ(x) − min_l |μ(x) − h_l|`` over the isopleths
    ``h_l`` between the classes found so far (``σ(x)`` alone while one class is found: a region not
    yet met is looked for where the field is least known), among the reachable cells at least a
    quarter ROI (``_targets.BOUNDARY_SPACING_ROI``) from every poke, where a new dent would
    overlap an old one.

References
----------
Bryan, B., Schneider, J., Nichol, R. C., Miller, C. J., Genovese, C. R., Wasserman, L. (2005).
Active learning for identifying function threshold boundaries. NIPS 18.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError

__all__ = ["STRATEGIES", "Strategy", "boundary_score", "choose_target"]

#: The strategies' names: the one list, which ``ExplorationConfig.strategy`` is annotated with.
Strategy = Literal["paper", "max-variance", "min-max-variance", "planned"]
STRATEGIES: tuple[Strategy, ...] = get_args(Strategy)

#: ``(candidates (c, 2)) -> (c,)`` largest posterior variance left if that candidate were poked.
LookAhead = Callable[[NDArray[np.float64]], NDArray[np.float64]]
#: ``() -> (2,)`` the next poke of a plan that reaches the threshold.
Planner = Callable[[], NDArray[np.float64]]


def choose_target(
    strategy: str,
    cells_xy: NDArray[np.float64],
    variance: NDArray[np.float64],
    threshold: float,
    rng: np.random.Generator,
    *,
    look_ahead: LookAhead | None = None,
    planner: Planner | None = None,
    n_candidates: int = 256,
) -> NDArray[np.float64] | None:
    """Pick the next target, or ``None`` when no cell's variance exceeds ``threshold``.

    Parameters
    ----------
    strategy : {"paper", "max-variance", "min-max-variance", "planned"}
    cells_xy : (n, 2) float, metres
        Centres of the grid cells that may be poked.
    variance : (n,) float
        β-field posterior variance at those cells.
    threshold : float
        ``T_h``: exploration stops when every cell's variance is at or below it.
    rng : numpy.random.Generator
        Used by ``paper`` (and to subsample candidates of ``min-max-variance``).
    look_ahead : callable, optional
        Required by ``min-max-variance``.
    planner : callable, optional
        Required by ``planned``.
    n_candidates : int
        How many above-threshold cells ``min-max-variance`` evaluates (a seeded subsample).
    """
    if strategy not in STRATEGIES:
        raise InvalidArgumentError(
            f"`strategy` must be one of {list(STRATEGIES)}; got {strategy!r}"
        )
    above = np.flatnonzero(variance > threshold)
    if above.size == 0:
        return None
    if strategy == "paper":
        return np.array(cells_xy[rng.choice(above)], dtype=float)
    if strategy == "max-variance":
        return np.array(cells_xy[int(np.argmax(variance))], dtype=float)
    if strategy == "planned":
        if planner is None:
            raise InvalidArgumentError("`planner` is required by strategy 'planned'")
        return np.array(planner(), dtype=float)
    if look_ahead is None:
        raise InvalidArgumentError("`look_ahead` is required by strategy 'min-max-variance'")
    candidates = above
    if candidates.size > n_candidates:
        candidates = np.sort(rng.choice(candidates, size=n_candidates, replace=False))
    left = look_ahead(cells_xy[candidates])
    # Among near-ties prefer the higher current variance: it is the less-known place.
    best = np.flatnonzero(left <= left.min() + 1e-9)
    pick = best[np.argmax(variance[candidates[best]])]
    return np.array(cells_xy[candidates[pick]], dtype=float)


def boundary_score(mean: NDArray[np.float64], std: NDArray[np.float64],
                   levels: NDArray[np.float64]) -> NDArray[np.float64]:
    """Straddle score ``1.96 σ − min_l |μ − h_l|`` of cells with β-field mean ``mean (n,)`` and
    standard deviation ``std (n,)`` against the isopleths ``levels (m,)``; ``std`` itself when
    there is no isopleth (one class). The next boundary poke goes to the largest score."""
    if levels.size == 0:
        return np.asarray(std, dtype=float)
    gap = np.min(np.abs(mean[:, None] - levels[None, :]), axis=1)
    return np.asarray(1.96 * std - gap, dtype=float)
