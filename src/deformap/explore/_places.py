"""Where the pokes lie as evidence, after the region test of :mod:`deformap.explore._classes`:
junction classes merged into their neighbours (:func:`merge_seam_classes`) and a class split
where its pokes form two places (:func:`split_by_place`).

Split by place: two materials closer than ``min_step`` stay one class by value, but their pokes
form two *places*. A class's best split by value into two parts (at least three pokes each) is
scored by the edges of the pokes' Delaunay graph it cuts (the join count, Cliff & Ord 1981)
against :data:`PLACE_PERMUTATIONS` shuffles of the values (fixed seed); fewer cut edges than the
shuffles give (one-sided, 5 % Bonferroni over the classes tested in a round) keeps the split.
Only the class's pokes farther than twice the layer's thickness from every other class's take
part; the others join the part of their nearest tested poke. Repeated until no class splits or
``max_regions`` are found.

References
----------
Cliff, A. D., Ord, J. K. (1981). Spatial Processes: Models & Applications, ch. 1–2 (join count
statistics). Pion, London.
Fisher, W. D. (1958). On grouping for maximum homogeneity. JASA 53(284), 789–798.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import Delaunay, QhullError

from deformap._validation import check_array
from deformap.explore._classes import REGION_Z, RegionMap, ranked, separated

__all__ = ["PLACE_PERMUTATIONS", "merge_seam_classes", "place_split", "split_by_place"]

#: Shuffles of the split-by-place test: a p-value in steps of 1/200, a tenth of the test's 5 %.
PLACE_PERMUTATIONS = 199
_PLACE_SEED = 20161116
_PLACE_MIN_PART = 3  # pokes on each side of a split by place: the value test's smallest group


def _neighbours(xy: NDArray[np.float64]) -> list[set[int]]:
    """Each poke's natural neighbours (Delaunay; pokes at one place share them; places on one
    line neighbour those just before and after)."""
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

    A press where two pieces meet reads neither. A class is a junction when *every* one of its
    pokes is a natural neighbour, within the joint's reach, of pokes of at least two other
    classes: each such poke joins the neighbouring class of nearest mean, until no class is a
    junction. Without every poke's thickness (``None``) nothing is merged.
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
    return ranked(mean, values, [np.flatnonzero(labels == c) for c in range(labels.max() + 1)],
                   np.arange(labels.size))


def _value_splits(values: NDArray[np.float64]) -> NDArray[np.bool_]:
    """The upper part of each row's best split by value (Fisher's, at least ``_PLACE_MIN_PART``
    each side) as a mask over ``values (m, n)``."""
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
    """The upper part of the best split by value of one class's pokes ``values (n,)``, ``stds
    (n,)`` at ``xy (n, 2)`` when it follows their places at ``level`` (module docstring), else
    ``None`` (also under six pokes)."""
    n = values.size
    if n < 2 * _PLACE_MIN_PART:
        return None
    edges = np.array([(i, j) for i, near in enumerate(_neighbours(xy)) for j in near if i < j],
                     dtype=np.int64).reshape(-1, 2)
    if not edges.size:
        return None
    rng = np.random.default_rng(_PLACE_SEED)
    rows = np.vstack([values[None, :], [rng.permutation(values) for _ in range(PLACE_PERMUTATIONS)]])
    splits = _value_splits(rows)
    joins = np.count_nonzero(splits[:, edges[:, 0]] != splits[:, edges[:, 1]], axis=1)
    p_value = (1 + np.count_nonzero(joins[1:] <= joins[0])) / (PLACE_PERMUTATIONS + 1)
    upper = splits[0]
    parts = [np.flatnonzero(~upper), np.flatnonzero(upper)]
    if p_value > level or not separated(values, stds, parts, 0.0, REGION_Z):
        return None
    return upper


def _joint_reach(thickness_m: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """How far from each press a joint changes what it reads [m]: twice the layer's thickness (a
    bonded layer carries the load sideways over about its thickness)."""
    return 2.0 * check_array("thickness_m", thickness_m, (n,), what="metres")


def split_by_place(found: RegionMap, mean: NDArray[np.float64], poke_xy: NDArray[np.float64],
                   poke_value: NDArray[np.float64], poke_std: NDArray[np.float64],
                   thickness_m: NDArray[np.float64] | None, *, max_regions: int) -> RegionMap:
    """``found`` with each class split in two while its pokes away from the other classes form
    two places of different values (module docstring), up to ``max_regions`` classes; nothing is
    split without every poke's thickness (``None``)."""
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
            break
        else:  # no class split
            break
    if np.array_equal(labels, found.poke_labels):
        return found
    return ranked(mean, values, [np.flatnonzero(labels == c) for c in np.unique(labels)],
                   np.arange(labels.size))
