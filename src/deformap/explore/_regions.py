"""Cut the map field (β, or ln E) into regions: classes of the pokes, cells by nearest poke,
isopleth or indicator kriging.

How the contour levels are chosen
---------------------------------
The paper draws "the best isopleth" of the β-field without saying how. We choose the levels from
the data the field is trained on, the pokes' own estimates (the field's posterior at a poke is
smoothed toward its neighbours, which fills the very gaps that separate classes), by divisive
splitting with a calibrated test:

1. Sort the βs; the best split of a group into a lower and an upper part is the one that explains
   the largest share of its spread (Fisher's optimal split of ordered data): between-part sum of
   squares B, within-part W.
2. Splitting a sorted sample at its best point *always* separates the two means, so the split's
   statistic ``T = B / (ν₀ s̄² + W)`` is compared with its own null distribution, simulated for
   the group under one material: each poke's β its mean plus a normal error of the poke's own
   uncertainty. ``s̄²`` is the group's mean squared uncertainty and ``ν₀`` (``prior_dof``) how
   many degrees of freedom the claimed uncertainties are worth beside the scatter the βs show
   (W): a moderated test (the claimed noise as a scaled-χ² prior on the scatter, as in Smyth
   2004). ``ν₀ = 0`` is the scale-free test that trusts only the βs; a large ``ν₀`` is Cochran's
   χ² test with known noise. The default 7 weighs the claimed noise like the eight presses on
   one foam that the β-field's former noise floor was measured from. The β-field's pokes carry
   the map's nugget in their uncertainty (:mod:`deformap.explore._nugget`), itself estimated
   within the classes this test finds (:func:`with_nugget`).
3. The same is done for the best split into three parts (two materials cannot always be told
   from one by a binary split when a third sits between them); the more significant of the two
   tests is used, at 5 % with a Bonferroni correction for testing both.
4. A split is kept only if neighbouring parts' means differ by at least ``min_step`` and by more
   than ``z`` standard errors (from the pokes' own uncertainties, at least ``floor``); each part
   is then split in turn. A group is tested while the test has two degrees of freedom for the
   scatter, ``ν₀ + n − 2 ≥ 2`` for ``n ≥ 3`` pokes: down to groups of 4 for the scale-free test,
   which learns the scatter from the βs alone, and of 3 when the claimed noise counts
   (``ν₀ ≥ 1``), so that a material met by a single poke beside two of another is still told
   apart (as when the few pokes a planned exploration needs meet three blocks; README,
   "Results").

Why not the scale-free test alone (``prior_dof=0``): with the few pokes a map needs, it must learn
the scatter from the same few βs it splits (``n − 2`` degrees of freedom), so its null distribution
is wide and two neighbouring foams go untold; the pokes' measured noise
(:mod:`deformap.explore._dent_noise`) is the information it lacks. The isopleth between two
neighbouring classes is the midpoint of their means; cells are labelled by the band of the β-field's
mean they fall in, so a region is a level set of the map, and ``n_regions`` is the number of classes
found.

Two materials whose values lie close (``ExplorationConfig.split_by_place``)
---------------------------------------------------------------------------
The test above sees the values only: two materials closer than ``min_step`` (or whose pokes'
values overlap) stay one class wherever their pokes lie. Where they lie is evidence too: pokes of
two materials side by side form two *places*, while the scatter of one material is spread over
its area at random. So a class is also tested for a split by place (:func:`split_by_place`):
its best split by value into a lower and an upper part (at least three pokes each, Fisher's
split as in 1.) is scored by how many edges of the pokes' Delaunay graph it cuts (the join
count: Cliff & Ord 1981), against the same split's join count after each of
:data:`PLACE_PERMUTATIONS` shuffles of the values over the places (fixed seed: the same pokes
give the same classes). A split that cuts fewer edges than shuffled values do (one-sided, 5 %
shared by the classes tested in one round, Bonferroni) is kept, with no smallest step: the
places, not the size of the difference, are the evidence (the parts' means must also lie ``z``
standard errors apart, but Fisher's best split of one material already separates them by about
that much: the join count is the test). Only the class's pokes farther than twice the layer's
thickness from every poke of another class take part (what a press reads near a joint is the
joint's, and pokes along a boundary would make one material look like two places: the junction
rule's reach, :func:`merge_seam_classes`); with six of them the test cannot reject (a 3 / 3 split
and its mirror cut as many edges), and it finds two materials cleanly left and right of random
places about half the time with nine. A tested poke keeps its part and
each other poke of the class joins the part of its nearest tested poke. Run after the junction
rule (its parts are not junctions) and repeated until no class splits or ``max_regions`` are
found. Measured on 42 default worlds (README, "Many worlds").

Labelling by nearest poke (``ExplorationConfig.region_labels = "nearest"``)
-----------------------------------------------------------------------------
The classes are found as above; each cell then takes the class of the poke nearest to it instead
of the band of the β-field it falls in (:meth:`RegionMap.nearest_poke`). The isopleths of a field
with a decimetre length scale are smooth curves that revert towards the field's mean away from
the pokes, and pokes placed to pin a boundary do not move them much; the nearest-poke labels of
the same pokes follow the pokes instead. It is the default: over 100 random worlds
(``deformap bench worlds``, README "Many worlds") it beat the isopleths with every strategy from
7 pokes on (level before) and was the best of the three cuts at 20 pokes; the paper's isopleths
stay available (``region_labels: isopleth``).

Labelling by indicator kriging (``region_labels = "indicator-kriging"``)
-------------------------------------------------------------------------
The classes are found as above; each cell takes its most probable class, each class's
probability kriged from the pokes' class indicators with the map field's own covariance
(:mod:`deformap.explore._indicator`). The README ("Strategies and cuts") compares the three cuts.

References
----------
Cliff, A. D., Ord, J. K. (1981). Spatial Processes: Models & Applications, ch. 1–2 (join count
statistics). Pion, London.
Fisher, W. D. (1958). On grouping for maximum homogeneity. JASA 53(284), 789–798.
Smyth, G. K. (2004). Linear models and empirical Bayes methods for assessing differential
expression in microarray experiments. Stat. Appl. Genet. Mol. Biol. 3(1), Article 3.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from itertools import pairwise

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import Delaunay, QhullError

from deformap._validation import check_array, check_int, check_positive
from deformap.explore._config import ExplorationConfig
from deformap.explore._field import REGION_MIN_STEP_BETA, PokeSet, beta_noise_floor, field_settings
from deformap.explore._indicator import indicator_labels
from deformap.explore._nugget import MAX_ROUNDS, estimate_nugget
from deformap.explore._records import PokeRecord

__all__ = ["PLACE_PERMUTATIONS", "RegionMap", "beta_pokes", "map_regions", "merge_seam_classes",
           "place_split", "poke_classes", "segment_regions", "split_by_place", "with_nugget"]

_NULL_SAMPLES = 4000
_NULL_SEED = 20161115
#: Shuffles of the values over the places in the split-by-place test (module docstring): a Monte
#: Carlo p-value in steps of 1/200, a tenth of the test's 5 %.
PLACE_PERMUTATIONS = 199
_PLACE_SEED = 20161116
# pokes on each side of a split by place: the value test's smallest group (segment_regions)
_PLACE_MIN_PART = 3
# the value test's z (segment_regions): standard errors between two parts' means
_REGION_Z = 2.0


@dataclass(frozen=True)
class RegionMap:
    """Regions of a β-field on a grid.

    Attributes
    ----------
    labels : (ny, nx) int
        Region of each cell, 0 for the lowest band of the field upwards (β-field: the stiffest
        class first; modulus field, ln E: the softest first).
    levels : (n_regions - 1,) float
        The isopleths between bands, increasing.
    class_betas : (n_regions,) float
        Mean value of the pokes in each class (β, or ln E [ln Pa] for the modulus field).
    poke_labels : (k,) int
        The class of each poke, in the order the pokes were given (a class is a run of the sorted
        βs, so a poke's class is not always the band its β falls in).
    """

    labels: NDArray[np.int64]
    levels: NDArray[np.float64]
    class_betas: NDArray[np.float64]
    poke_labels: NDArray[np.int64]

    @property
    def n_regions(self) -> int:
        return int(self.class_betas.size)

    def nearest_poke(self, poke_xy: NDArray[np.float64],
                     cells_xy: NDArray[np.float64]) -> RegionMap:
        """The same classes, each cell labelled by the class of the poke nearest to it (ties: the
        earliest poke) instead of by the band of the β-field it falls in.

        Parameters
        ----------
        poke_xy : (k, 2) float, metres
            Where the pokes were, in the order of ``poke_labels``.
        cells_xy : (ny · nx, 2) float, metres
            The cells of ``labels``, row-major.
        """
        pokes = check_array("poke_xy", poke_xy, (self.poke_labels.size, 2), what="metres")
        cells = check_array("cells_xy", cells_xy, (self.labels.size, 2), what="metres")
        # squared distances of every cell to every poke (a few dozen pokes): argmin keeps the
        # earliest poke of a tie, which a k-d tree does not promise
        d2 = np.sum((cells[:, None, :] - pokes[None, :, :]) ** 2, axis=-1)
        nearest = np.argmin(d2, axis=1)
        labels = self.poke_labels[nearest].reshape(self.labels.shape)
        return RegionMap(labels=labels, levels=self.levels, class_betas=self.class_betas,
                         poke_labels=self.poke_labels)


def _best_splits(values: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray, NDArray,
                                                       NDArray]:  # fmt: skip
    """Best 2- and 3-part splits of each sorted row of ``values (m, n)``.

    Returns the between-part sums of squares of the best splits, ``b2 (m,)`` and ``b3 (m,)``, the
    rows' total sums of squares ``spread (m,)``, and the cut indices, ``cut2 (m,)`` and ``cuts3
    (m, 2)``.
    """
    m, n = values.shape
    csum = np.concatenate([np.zeros((m, 1)), np.cumsum(values, axis=1)], axis=1)
    spread = np.sum((values - values.mean(axis=1, keepdims=True)) ** 2, axis=1)

    def part(i: NDArray, j: NDArray) -> NDArray:  # Σ² / size of the part [i, j)
        return (csum[:, j] - csum[:, i]) ** 2 / (j - i)

    base = csum[:, n] ** 2 / n
    cut2 = np.arange(1, n)
    between2 = part(np.zeros_like(cut2), cut2) + part(cut2, np.full_like(cut2, n)) - base[:, None]
    i3, j3 = np.triu_indices(n, k=1)
    keep = i3 >= 1
    i3, j3 = i3[keep], j3[keep]
    if i3.size:
        zeros, ends = np.zeros_like(i3), np.full_like(i3, n)
        between3 = part(zeros, i3) + part(i3, j3) + part(j3, ends) - base[:, None]
    else:
        between3 = np.zeros((m, 1))
        i3 = j3 = np.array([1])
    # round-off can leave a tiny between-sum on a row without spread
    b2 = np.where(spread > 0, between2.max(axis=1), 0.0)
    b3 = np.where(spread > 0, between3.max(axis=1), 0.0)
    best3 = np.argmax(between3, axis=1)
    return b2, b3, spread, cut2[np.argmax(between2, axis=1)], np.column_stack([i3[best3], j3[best3]])


def _statistics(values: NDArray[np.float64], prior: float) -> tuple[NDArray, NDArray, NDArray,
                                                                     NDArray]:  # fmt: skip
    """Split statistics ``T = between / (prior + within)`` of the best 2- and 3-part splits of
    each sorted row of ``values (m, n)``, with their cuts (see :func:`_best_splits`)."""
    b2, b3, spread, cut2, cuts3 = _best_splits(values)
    with np.errstate(invalid="ignore", divide="ignore"):
        t2 = np.nan_to_num(b2 / (prior + (spread - b2)))
        t3 = np.nan_to_num(b3 / (prior + (spread - b3)))
    return t2, t3, cut2, cuts3


def _null(stds: NDArray[np.float64], prior_dof: float) -> tuple[NDArray, NDArray]:
    """Sorted statistics t2, t3 of ``_NULL_SAMPLES`` draws of one material: each poke's β its
    mean plus its own noise (``stds``, in the group's sorted order, which under one material is
    unrelated to the noise)."""
    rng = np.random.default_rng(_NULL_SEED)
    draws = rng.standard_normal((_NULL_SAMPLES, stds.size)) * stds[None, :]
    t2, t3, _, _ = _statistics(np.sort(draws, axis=1), prior_dof * float(np.mean(stds**2)))
    return np.sort(t2), np.sort(t3)


def _p_value(null_sorted: NDArray, observed: float) -> float:
    above = null_sorted.size - np.searchsorted(null_sorted, observed, side="left")
    return float((above + 1) / (null_sorted.size + 1))


def _separated(b: NDArray, s: NDArray, parts: list[NDArray], min_step: float, z: float) -> bool:
    """Whether neighbouring parts' means differ by ``min_step`` and ``z`` standard errors."""
    for lower, upper in pairwise(parts):
        gap = b[upper].mean() - b[lower].mean()
        error = np.hypot(np.sqrt(np.mean(s[lower] ** 2) / lower.size),
                         np.sqrt(np.mean(s[upper] ** 2) / upper.size))  # fmt: skip
        if gap <= max(min_step, z * error):
            return False
    return True


def _split(b: NDArray, s: NDArray, group: NDArray, room: int, *, min_step: float, z: float,
           prior_dof: float) -> list[NDArray] | None:  # fmt: skip
    """The significant split of ``group`` into 2 or 3 parts, or None (5 %, Bonferroni over 2)."""
    prior = prior_dof * float(np.mean(s[group] ** 2))
    t2, t3, cut2, cuts3 = _statistics(b[group][None, :], prior)
    null2, null3 = _null(s[group], prior_dof)
    tests = [(_p_value(null2, float(t2[0])), [int(cut2[0])])]
    if room >= 3 and group.size >= 6:
        tests.append((_p_value(null3, float(t3[0])), [int(c) for c in cuts3[0]]))
    for p_value, cuts in sorted(tests, key=lambda t: t[0]):
        if p_value * len(tests) > 0.05:
            break
        parts = np.split(group, cuts)
        if _separated(b, s, parts, min_step, z):
            return parts
    return None


def segment_regions(
    beta_grid: NDArray[np.float64],
    poke_beta: NDArray[np.float64],
    poke_std: NDArray[np.float64],
    *,
    floor: float = 0.03,
    min_step: float = 0.05,
    z: float = 2.0,
    max_regions: int = 6,
    prior_dof: float = 7.0,
) -> RegionMap:
    """Label the cells of ``beta_grid`` by isopleths chosen from the pokes' β estimates.

    Parameters
    ----------
    beta_grid : (ny, nx) float
        Posterior mean of the β-field on the grid.
    poke_beta, poke_std : (k,) float
        The pokes' β estimates and their uncertainties.
    floor : float
        Smallest uncertainty a poke is credited with (the map field's noise floor:
        :func:`poke_classes` passes the field's own; this function's default, 0.03, is the
        β-field's on the former reference β scale, kept for direct callers).
    min_step : float
        Smallest difference of two class means that can separate them.
    z : float
        Standard errors of the difference of two class means needed to separate them.
    max_regions : int
        Most classes returned.
    prior_dof : float
        Degrees of freedom the pokes' uncertainties count for in the scatter the split test
        expects (0: the scatter is estimated from the βs alone, a scale-free test).
    """
    grid = check_array("beta_grid", beta_grid, (None, None))
    betas = check_array("poke_beta", poke_beta, (None,), min_rows=1)
    stds = check_array("poke_std", poke_std, (betas.size,), what="standard deviations")
    check_positive("floor", floor)
    check_positive("min_step", min_step, allow_zero=True)
    check_positive("z", z, allow_zero=True)
    check_int("max_regions", max_regions, minimum=1)
    check_positive("prior_dof", prior_dof, allow_zero=True)
    order = np.argsort(betas, kind="stable")
    b, s = betas[order], np.maximum(stds[order], floor)
    pending: list[NDArray[np.int64]] = [np.arange(b.size)]
    done: list[NDArray[np.int64]] = []
    while pending:
        group = pending.pop()
        room = max_regions - len(done) - len(pending)
        if group.size < 3 or prior_dof + group.size - 2 < 2 or room < 2:
            done.append(group)
            continue
        parts = _split(b, s, group, room, min_step=min_step, z=z, prior_dof=prior_dof)
        if parts is None:
            done.append(group)
        else:
            pending += parts
    return _ranked(grid, b, done, order)


def _ranked(grid: NDArray[np.float64], values: NDArray[np.float64],
            groups: list[NDArray[np.int64]], order: NDArray[np.int64]) -> RegionMap:
    """The regions of the classes ``groups`` (indices into ``values``), numbered by their mean
    value upwards, with the isopleths midway between neighbouring means; ``order`` maps an index
    into ``values`` to the poke's place in the order the pokes were given."""
    means = np.array([values[g].mean() for g in groups])
    rank = np.argsort(means, kind="stable")
    class_betas = means[rank]
    poke_labels = np.empty(values.size, dtype=np.int64)
    for k, g in enumerate(rank):
        poke_labels[order[groups[g]]] = k
    levels = (class_betas[:-1] + class_betas[1:]) / 2
    labels = np.searchsorted(levels, grid, side="right").astype(np.int64)
    return RegionMap(labels=labels, levels=levels, class_betas=class_betas,
                     poke_labels=poke_labels)


def _neighbours(xy: NDArray[np.float64]) -> list[set[int]]:
    """Each poke's natural neighbours: the pokes whose Voronoi cells share an edge with its own
    (Delaunay triangulation; pokes at one place share their neighbours). Places on one line
    (no triangle) have their Voronoi cells side by side along it: each place's neighbours are
    the places just before and after it along the line."""
    places, which = np.unique(np.round(xy, 9), axis=0, return_inverse=True)
    which = np.asarray(which).reshape(-1)
    near: list[set[int]] = [set() for _ in range(places.shape[0])]
    try:
        if places.shape[0] < 3:
            raise QhullError("fewer than three places")
        for simplex in Delaunay(places).simplices:
            for a in simplex:
                near[a].update(int(b) for b in simplex if b != a)
    except QhullError:  # on one line: neighbours along it
        centred = places - places.mean(axis=0)
        axis = np.linalg.svd(centred, full_matrices=False)[2][0]
        order = np.argsort(centred @ axis, kind="stable")
        for a, b in pairwise(order.tolist()):
            near[a].add(b)
            near[b].add(a)
    members = [np.flatnonzero(which == k) for k in range(places.shape[0])]
    return [{int(j) for k in near[which[i]] | {int(which[i])} for j in members[k] if j != i}
            for i in range(xy.shape[0])]


def merge_seam_classes(found: RegionMap, mean: NDArray[np.float64],
                       poke_xy: NDArray[np.float64], poke_value: NDArray[np.float64],
                       thickness_m: NDArray[np.float64] | None) -> RegionMap:
    """``found`` with its junction classes merged into their neighbours.

    A press where two pieces meet reads neither piece: across a bonded seam it dents both and
    reads between them; beside a free face (pieces laid side by side) the foam gives way sideways
    and it reads softer than both. The classes, found from the values alone, take such a reading
    for a material of its own. A class is taken for a junction when *every* one of its pokes is a
    natural neighbour (:func:`_neighbours`) of pokes of at least two other classes: each such poke
    then joins, of its neighbours' classes, the one whose mean is nearest to its value; the
    classes' means and isopleths are recomputed and the test repeated until no class is a
    junction. A class with one poke inside it (its neighbours of one other class only) is kept,
    so an insert met by a single poke stays a region. What it gives up: a material seen only by
    pokes lying where two others meet (a stripe one poke wide between two others) is merged until
    a poke lands inside it; ``deformap bench rescore --merge-seams`` measures the trade (README,
    "Many worlds"). Without every poke's thickness (``None``: a poke without a force–travel
    record) no class is merged.
    """
    if thickness_m is None:
        return found
    labels = found.poke_labels.copy()
    values = check_array("poke_value", poke_value, (labels.size,))
    xy = check_array("poke_xy", poke_xy, (labels.size, 2), what="metres")
    reach = _joint_reach(thickness_m, labels.size)
    near = [{j for j in neighbours if np.hypot(*(xy[j] - xy[i])) <= reach[i]}
            for i, neighbours in enumerate(_neighbours(xy))]
    while True:
        classes = np.unique(labels)
        means = np.array([values[labels == c].mean() for c in classes])
        others = [{int(labels[j]) for j in near[i]} - {int(labels[i])}
                  for i in range(labels.size)]
        junction = next((int(c) for c in classes[np.argsort(means, kind="stable")]
                         if all(len(others[i]) >= 2 for i in np.flatnonzero(labels == c))), None)
        if junction is None:
            break
        mean_of = dict(zip(classes.tolist(), means.tolist(), strict=True))
        moved = labels.copy()
        for i in np.flatnonzero(labels == junction):
            moved[i] = min(sorted(others[i]), key=lambda c: abs(values[i] - mean_of[c]))
        labels = np.unique(moved, return_inverse=True)[1].reshape(-1)
    return _ranked(mean, values, [np.flatnonzero(labels == c) for c in range(labels.max() + 1)],
                   np.arange(labels.size))


def _value_splits(values: NDArray[np.float64]) -> NDArray[np.bool_]:
    """For each row of ``values (m, n)``, the upper part of its best split by value (Fisher's:
    the largest between-part sum of squares, at least ``_PLACE_MIN_PART`` values each side), as a
    mask over the row's own places (ties broken by place, stably)."""
    m, n = values.shape
    order = np.argsort(values, axis=1, kind="stable")
    csum = np.cumsum(np.take_along_axis(values, order, axis=1), axis=1)
    size = np.arange(_PLACE_MIN_PART, n - _PLACE_MIN_PART + 1)  # of the lower part
    lower = csum[:, size - 1] / size
    upper = (csum[:, -1:] - csum[:, size - 1]) / (n - size)
    best = size[np.argmax(size * (n - size) * (upper - lower) ** 2, axis=1)]
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.broadcast_to(np.arange(n), (m, n)), axis=1)
    return np.asarray(rank >= best[:, None])


def place_split(values: NDArray[np.float64], stds: NDArray[np.float64],
                xy: NDArray[np.float64], *, level: float = 0.05) -> NDArray[np.bool_] | None:
    """The upper part of the best split by value of one class's pokes when that split follows
    their places at ``level`` (module docstring, "Two materials whose values lie close"), else
    ``None``.

    ``values (n,)`` and ``stds (n,)`` (each at least the field's floor) at ``xy (n, 2)``; at least
    ``2 · 3`` pokes, else ``None`` (with six the test cannot reject: a 3 / 3 split and its mirror
    image cut as many edges, so about one shuffle in ten ties it; two materials cleanly left and
    right of random places are found in about half of the draws with nine pokes at 5 %)."""
    n = values.size
    if n < 2 * _PLACE_MIN_PART:
        return None
    edges = np.array([(i, j) for i, near in enumerate(_neighbours(xy)) for j in near if i < j],
                     dtype=np.int64).reshape(-1, 2)
    if not edges.size:
        return None
    rng = np.random.default_rng(_PLACE_SEED)
    rows = np.vstack([values[None, :], [rng.permutation(values) for _ in
                                        range(PLACE_PERMUTATIONS)]])
    splits = _value_splits(rows)
    joins = np.count_nonzero(splits[:, edges[:, 0]] != splits[:, edges[:, 1]], axis=1)
    p_value = (1 + np.count_nonzero(joins[1:] <= joins[0])) / (PLACE_PERMUTATIONS + 1)
    upper = splits[0]
    parts = [np.flatnonzero(~upper), np.flatnonzero(upper)]
    if p_value > level or not _separated(values, stds, parts, 0.0, _REGION_Z):
        return None
    return upper


def _joint_reach(thickness_m: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """How far from a press a joint changes what it reads: twice the layer's thickness there
    (a bonded layer carries the load sideways over about its own thickness; the joint, expected
    midway between two presses, within one thickness of each), per poke [m]."""
    return 2.0 * check_array("thickness_m", thickness_m, (n,), what="metres")


def split_by_place(found: RegionMap, mean: NDArray[np.float64], poke_xy: NDArray[np.float64],
                   poke_value: NDArray[np.float64], poke_std: NDArray[np.float64],
                   thickness_m: NDArray[np.float64] | None, *, max_regions: int) -> RegionMap:
    """``found`` with each class split in two while its pokes away from the other classes form
    two places of different values (:func:`place_split`; module docstring), up to
    ``max_regions`` classes. Only a class's pokes farther than the joint's reach
    (:func:`_joint_reach`) from every poke of another class are tested; the classes tested in one
    round share the 5 % (Bonferroni); a tested poke keeps its part and every other poke of the
    class joins the part of its nearest tested poke (a split that would leave a part empty is
    none). Without every poke's thickness (``None``) nothing is split, as
    :func:`merge_seam_classes` merges nothing. With eleven classes or more tested at once the
    shared level falls below the shuffles' resolution (1/200) and none can split: the default
    ``max_regions`` (6) stays clear of it."""
    if thickness_m is None:
        return found
    labels = found.poke_labels.copy()
    values = check_array("poke_value", poke_value, (labels.size,))
    stds = check_array("poke_std", poke_std, (labels.size,), what="standard deviations")
    xy = check_array("poke_xy", poke_xy, (labels.size, 2), what="metres")
    reach = _joint_reach(thickness_m, labels.size)
    distance = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    while np.unique(labels).size < max_regions:
        candidates = []
        for c in np.unique(labels):
            members = np.flatnonzero(labels == c)
            away = np.all(distance[np.ix_(members, np.flatnonzero(labels != c))]
                          > reach[members, None], axis=1)
            if np.count_nonzero(away) >= 2 * _PLACE_MIN_PART:
                candidates.append((members, members[away]))
        split = False
        for members, tested in candidates:
            upper = place_split(values[tested], stds[tested], xy[tested],
                                level=0.05 / len(candidates))
            if upper is None:
                continue
            side = upper[np.argmin(distance[np.ix_(members, tested)], axis=1)]
            side[np.searchsorted(members, tested)] = upper  # a tested poke keeps its own part
            if side.all() or not side.any():
                continue
            labels[members[side]] = labels.max() + 1
            split = True
            break
        if not split:
            break
    if np.array_equal(labels, found.poke_labels):
        return found
    return _ranked(mean, values, [np.flatnonzero(labels == c) for c in np.unique(labels)],
                   np.arange(labels.size))


def poke_classes(mean: NDArray[np.float64], pokes: PokeSet,
                 config: ExplorationConfig) -> RegionMap:
    """The pokes' classes and the isopleth labels of the map field's mean ``mean (ny, nx)``, by
    :func:`segment_regions` with the exploration's settings (``max_regions``,
    ``region_prior_dof``) and the map field's noise floor and smallest step
    (:func:`deformap.explore.field_settings`: β, or ln E under ``field = "modulus"``)."""
    cfg = field_settings(config)
    return segment_regions(mean, pokes.beta, pokes.noise, floor=cfg.noise_floor,
                           min_step=cfg.min_step, max_regions=config.max_regions,
                           prior_dof=config.region_prior_dof)  # fmt: skip


def map_regions(mean: NDArray[np.float64], pokes: PokeSet, cells_xy: NDArray[np.float64],
                config: ExplorationConfig) -> RegionMap:
    """The regions of a β-field with mean ``mean (ny, nx)`` fitted to ``pokes``, as the
    exploration settings ask: classes by :func:`segment_regions` (``max_regions``,
    ``region_prior_dof``, the β-field's noise floor), junctions merged (``merge_seams``) and
    classes split by place (``split_by_place``), cells labelled by isopleth, by nearest
    poke or by indicator kriging (``region_labels``; ``cells_xy (ny · nx, 2)`` are the grid's
    cells)."""
    found = poke_classes(mean, pokes, config)
    if config.merge_seams and found.n_regions >= 3:
        found = merge_seam_classes(found, mean, pokes.xy, pokes.beta, pokes.thickness)
    if config.split_by_place:  # after the junctions: the parts it makes are not junctions
        found = split_by_place(found, mean, pokes.xy, pokes.beta,
                               np.maximum(pokes.noise, field_settings(config).noise_floor),
                               pokes.thickness, max_regions=config.max_regions)  # fmt: skip
    if config.region_labels == "nearest":
        return found.nearest_poke(pokes.xy, cells_xy)
    if config.region_labels == "indicator-kriging":
        cfg = field_settings(config)
        labels = indicator_labels(pokes.xy, found.poke_labels, pokes.noise, cells_xy,
                                  n_classes=found.n_regions, length_scale=cfg.length_scale_m,
                                  signal_std=cfg.signal_std)  # fmt: skip
        return RegionMap(labels=labels.reshape(found.labels.shape), levels=found.levels,
                         class_betas=found.class_betas, poke_labels=found.poke_labels)
    return found


def with_nugget(pokes: PokeSet, config: ExplorationConfig) -> PokeSet:
    """``pokes`` (β, each noise its claimed σ at least the floor) with the map's nugget τ̂ added to
    every poke's noise in variance, ``√(σᵢ² + τ̂²)`` (:mod:`deformap.explore._nugget`).

    The classes are the region test's on the β values (:func:`segment_regions` with the
    exploration's ``max_regions``, ``region_prior_dof`` and the β-field's smallest step and floor):
    found first with the claimed σ, τ̂ estimated within those the test examined (as many pokes as
    it tests a group of: a smaller class, a pair above all, is no evidence of one material), found
    again with the noise that τ̂ gives, until they no longer change (at most
    :data:`deformap.explore._nugget.MAX_ROUNDS` rounds). ``pokes`` unchanged under
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
        found = segment_regions(flat, pokes.beta, np.hypot(pokes.noise, tau), floor=floor,
                                min_step=REGION_MIN_STEP_BETA, max_regions=config.max_regions,
                                prior_dof=config.region_prior_dof).poke_labels  # fmt: skip
        if labels is not None and np.array_equal(found, labels):
            break
        labels, before = found, tau
        tau = estimate_nugget(pokes.beta, pokes.noise, labels, min_class_size=examined)
        if tau == before:  # the same noise finds the same classes again
            break
    return replace(pokes, noise=np.hypot(pokes.noise, tau), nugget=tau)


def beta_pokes(records: Sequence[PokeRecord], config: ExplorationConfig) -> PokeSet:
    """The pokes of the β-field as the mapper fits it: each poke's claimed σ raised to the floor
    (:func:`deformap.explore.beta_noise_floor`), plus the map's nugget (:func:`with_nugget`)."""
    return with_nugget(PokeSet.of(records, beta_noise_floor(config)), config)
