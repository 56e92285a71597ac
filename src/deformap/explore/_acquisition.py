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
``level-set``
    Aimed at the region boundaries from the first poke on: the reachable cell of largest
    *straddle* score (Bryan et al. 2005), ``1.96 σ(x) − min_l |μ(x) − h_l|``, among those at least
    a quarter ROI from every poke (the score and the spacing of the boundary pokes below). The
    levels ``h_l`` are the map's current cut levels, the isopleths between the classes the region
    test finds in the pokes so far (:func:`deformap.explore.poke_classes`, the midpoints of
    neighbouring class means): those are the boundaries the map will draw, so a cell near one
    of them whose field is still uncertain is the cell whose label a poke is most likely to
    change. While the pokes form one class there is no level, and the score is ``σ(x)`` alone
    (the least-known place, where a region not yet met is most likely to be found). Straddle,
    rather than ILS-UCB (Garg et al. 2016), because it has no weight to choose: its 1.96 is the
    95 % band within which a cell's side of ``h`` is not yet known.
``integrated-variance``
    The candidate that most reduces the posterior variance integrated over the workspace
    (IMSE, Sacks et al. 1989): for a poke at ``x`` with noise ``σ_n²(x)``,
    ``Σ_d k_post(d, x)² / (σ²(x) + σ_n²(x))`` over the cells ``d`` where the variance must fall
    (an exact rank-one update of the posterior, which does not depend on the values). It is
    evaluated on the planner's 2 cm lattices (:class:`deformap.explore.MapGrid`'s
    ``plan_candidates`` and ``plan_domain``), so its cost is that of one (candidates × domain)
    matrix however fine the map grid, and it takes the noise a poke there is expected to have
    (:func:`deformap.explore._targets.expected_noise`). Myopic like ``min-max-variance``, but on
    the mean of the variance rather than its maximum: it pokes where most of the map learns,
    not where the worst cell is.

Every strategy runs until the map field's variance is below ``T_h`` (the paper's stop); the
boundary pokes, if any, follow.

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
Sacks, J., Welch, W. J., Mitchell, T. J., Wynn, H. P. (1989). Design and analysis of computer
experiments. Statistical Science 4(4), 409–423 (the integrated mean squared error criterion).
Garg, A., Sen, S., Kapadia, R., et al. (2016). Tumor localization using automated palpation with
Gaussian process adaptive sampling. IEEE CASE (the implicit level set UCB it is compared with).
Bryan, B., Schneider, J., Nichol, R. C., Miller, C. J., Genovese, C. R., Wasserman, L. (2005).
Active learning for identifying function threshold boundaries. NIPS 18.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError

__all__ = ["SCORED", "STRATEGIES", "Strategy", "boundary_score", "choose_target"]

#: The strategies' names: the one list, which ``ExplorationConfig.strategy`` is annotated with.
Strategy = Literal["paper", "max-variance", "min-max-variance", "planned", "level-set",
                   "integrated-variance"]
STRATEGIES: tuple[Strategy, ...] = get_args(Strategy)

#: ``(candidates (c, 2)) -> (c,)`` largest posterior variance left if that candidate were poked.
LookAhead = Callable[[NDArray[np.float64]], NDArray[np.float64]]
#: ``() -> (2,)`` the next poke of a plan that reaches the threshold.
Planner = Callable[[], NDArray[np.float64]]
#: ``() -> (candidates (c, 2), scores (c,))`` a scored strategy's candidates (``level-set``,
#: ``integrated-variance``); the largest score is poked.
Scorer = Callable[[], tuple[NDArray[np.float64], NDArray[np.float64]]]
#: The strategies that poke the best of their scorer's candidates.
SCORED: tuple[Strategy, ...] = ("level-set", "integrated-variance")


def choose_target(
    strategy: str,
    cells_xy: NDArray[np.float64],
    variance: NDArray[np.float64],
    threshold: float,
    rng: np.random.Generator,
    *,
    look_ahead: LookAhead | None = None,
    planner: Planner | None = None,
    scorer: Scorer | None = None,
    n_candidates: int = 256,
) -> NDArray[np.float64] | None:
    """Pick the next target, or ``None`` when no cell's variance exceeds ``threshold``.

    Parameters
    ----------
    strategy : {"paper", "max-variance", "min-max-variance", "planned", "level-set", \
"integrated-variance"}
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
    scorer : callable, optional
        Required by ``level-set`` and ``integrated-variance``: their candidates and scores; the
        first of the largest score is poked.
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
    if strategy in SCORED:
        if scorer is None:
            raise InvalidArgumentError(f"`scorer` is required by strategy {strategy!r}")
        candidates_xy, scores = scorer()
        return np.array(candidates_xy[int(np.argmax(scores))], dtype=float)
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
