"""Where to poke next, from the map field's posterior variance on a grid.

Strategies
----------
``paper``
    Caccamo et al. 2016, Sec. III-D: a random cell among those whose variance exceeds ``T_h``,
    drawn with the explicit generator.
``max-variance``
    The cell of largest variance (ties: the first in row-major order).
``planned`` (default)
    The first of the fewest further pokes that bring the largest variance under ``T_h``, planned
    together and again after every poke (:mod:`deformap.explore._planning`).
``level-set``
    The reachable cell of largest straddle score (Bryan et al. 2005), ``1.96 σ(x) − min_l
    |μ(x) − h_l|``, at least a quarter ROI from every poke; ``h_l`` are the isopleths between the
    classes the region test finds in the pokes so far, and with one class the score is ``σ(x)``
    (a region not yet met is likeliest where the field is least known). Straddle rather than
    ILS-UCB (Garg et al. 2016) because it has no weight to choose: 1.96 is the 95 % band.

Every strategy runs until the map field's variance is below ``T_h`` (the paper's stop). Then each
of the ``boundary_pokes`` goes to the largest straddle score, as for ``level-set``, among the
reachable cells at least ``_targets.BOUNDARY_SPACING_ROI`` ROIs from every poke.

References
----------
Garg, A., Sen, S., Kapadia, R., et al. (2016). Tumor localization using automated palpation with
Gaussian process adaptive sampling. IEEE CASE.
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
Strategy = Literal["paper", "max-variance", "planned", "level-set"]
STRATEGIES: tuple[Strategy, ...] = get_args(Strategy)

#: ``() -> (2,)`` the next poke of a plan that reaches the threshold.
Planner = Callable[[], NDArray[np.float64]]
#: ``() -> (candidates (c, 2), scores (c,))`` the ``level-set`` candidates and their straddle
#: scores; the largest score is poked.
Scorer = Callable[[], tuple[NDArray[np.float64], NDArray[np.float64]]]


def choose_target(strategy: str, cells_xy: NDArray[np.float64], variance: NDArray[np.float64],
                  threshold: float, rng: np.random.Generator, *, planner: Planner | None = None,
                  scorer: Scorer | None = None) -> NDArray[np.float64] | None:
    """Pick the next target among the cells ``cells_xy (n, 2)`` [m] of map-field variance
    ``variance (n,)``, or ``None`` when none exceeds ``threshold`` (``T_h``); ``rng`` is used by
    ``paper``, ``planner`` required by ``planned``, ``scorer`` by ``level-set``."""
    if strategy not in STRATEGIES:
        raise InvalidArgumentError(f"`strategy` must be one of {list(STRATEGIES)}; got {strategy!r}")
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
    if scorer is None:  # level-set
        raise InvalidArgumentError(f"`scorer` is required by strategy {strategy!r}")
    candidates_xy, scores = scorer()
    return np.array(candidates_xy[int(np.argmax(scores))], dtype=float)


def boundary_score(mean: NDArray[np.float64], std: NDArray[np.float64],
                   levels: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(n,)`` straddle score ``1.96 σ − min_l |μ − h_l|`` (Bryan et al. 2005) of cells of
    posterior ``mean``, ``std (n,)`` and isopleths ``levels (m,)``; with none, ``std``."""
    if levels.size == 0:
        return np.asarray(std, dtype=float)
    gap = np.min(np.abs(mean[:, None] - levels[None, :]), axis=1)
    return np.asarray(1.96 * std - gap, dtype=float)
