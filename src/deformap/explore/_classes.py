"""The region test: classes of the pokes' values on the map field (β, or ln E), and the
isopleths between them.

The levels are chosen from the pokes' own estimates (the posterior's smoothing fills the gaps
between classes) by divisive splitting with a calibrated test:

1. The best split of a sorted group into a lower and an upper part explains the largest share of
   its spread (Fisher 1958): between-part sum of squares B, within-part W.
2. Its statistic ``T = B / (ν₀ s̄² + W)`` is compared with its null distribution, simulated for
   the group under one material (each poke its mean plus a normal error of its own uncertainty);
   ``s̄²`` is the mean squared uncertainty and ``ν₀`` (``prior_dof``) the degrees of freedom the
   claimed uncertainties count for beside W: a moderated test (Smyth 2004); ``ν₀ = 0`` is the
   scale-free test, a large ``ν₀`` Cochran's χ² test with known noise.
3. The same for the best split into three parts (a third material between two); the more
   significant of the two is used, at 5 % with Bonferroni over both.
4. A split is kept only if neighbouring parts' means differ by at least ``min_step`` and by more
   than ``z`` standard errors (uncertainties at least ``floor``); each part is split in turn while
   ``n ≥ 3`` and ``ν₀ + n − 2 ≥ 2``.

The isopleth between two neighbouring classes is the midpoint of their means; cells are labelled
by the band of the field's mean they fall in.

Behaviour (:func:`split_by_behaviour`, after the value test): two pokes whose presses read
different known behaviours (elastic, viscoelastic, plastic) are never one class, whatever their
values. A class whose pokes read several known behaviours is split into one class per behaviour;
a poke of unknown behaviour (or none read) is compatible with any and joins the part of the
nearest poke of its class with a known behaviour (ties: the earliest). Such a split may leave more
than ``max_regions`` classes: the value test's limit does not merge what the presses tell apart.

References
----------
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

from deformap._validation import check_array, check_int, check_positive
from deformap.errors import InvalidArgumentError
from deformap.explore._config import ExplorationConfig, FieldName
from deformap.explore._field import PokeSet, field_settings

__all__ = ["KNOWN_BEHAVIOURS", "REGION_Z", "RegionMap", "class_behaviours", "poke_classes",
           "ranked", "segment_regions", "separated", "split_by_behaviour"]

_NULL_SAMPLES = 4000
_NULL_SEED = 20161115
#: The value test's z (:func:`segment_regions`): standard errors between two parts' means.
REGION_Z = 2.0
#: The behaviours a press can show that tell two pokes apart; any other reading ("unknown", or
#: none) is compatible with every class.
KNOWN_BEHAVIOURS: tuple[str, ...] = ("elastic", "viscoelastic", "plastic")


@dataclass(frozen=True)
class RegionMap:
    """Regions of a field on a grid: ``labels (ny, nx)`` each cell's region, from the lowest band
    up; ``levels (n_regions - 1,)`` the isopleths, increasing; ``class_betas (n_regions,)`` each
    class's mean (β, or ln E); ``poke_labels (k,)`` each poke's class, in the order given."""

    labels: NDArray[np.int64]
    levels: NDArray[np.float64]
    class_betas: NDArray[np.float64]
    poke_labels: NDArray[np.int64]

    @property
    def n_regions(self) -> int:
        return int(self.class_betas.size)

    def nearest_poke(self, poke_xy: NDArray[np.float64], cells_xy: NDArray[np.float64]) -> RegionMap:
        """The same classes, each cell of ``cells_xy (ny · nx, 2)`` labelled by the class of the
        nearest of the pokes at ``poke_xy (k, 2)`` (ties: the earliest), metres."""
        pokes = check_array("poke_xy", poke_xy, (self.poke_labels.size, 2), what="metres")
        cells = check_array("cells_xy", cells_xy, (self.labels.size, 2), what="metres")
        # argmin keeps the earliest poke of a tie, which a k-d tree does not promise
        nearest = np.argmin(np.sum((cells[:, None, :] - pokes[None, :, :]) ** 2, axis=-1), axis=1)
        return replace(self, labels=self.poke_labels[nearest].reshape(self.labels.shape))


def _best_splits(values: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray, NDArray,
                                                       NDArray]:  # fmt: skip
    """Best 2- and 3-part splits of each sorted row of ``values (m, n)``: between-part sums of
    squares ``b2``, ``b3``, total ``spread`` and cuts ``cut2 (m,)``, ``cuts3 (m, 2)``."""
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
    """``T = between / (prior + within)`` of the best 2- and 3-part splits, with their cuts."""
    b2, b3, spread, cut2, cuts3 = _best_splits(values)
    with np.errstate(invalid="ignore", divide="ignore"):
        t2 = np.nan_to_num(b2 / (prior + (spread - b2)))
        t3 = np.nan_to_num(b3 / (prior + (spread - b3)))
    return t2, t3, cut2, cuts3


def _null(stds: NDArray[np.float64], prior_dof: float) -> tuple[NDArray, NDArray]:
    """Sorted statistics t2, t3 of ``_NULL_SAMPLES`` draws of one material with noise ``stds``."""
    rng = np.random.default_rng(_NULL_SEED)
    draws = rng.standard_normal((_NULL_SAMPLES, stds.size)) * stds[None, :]
    t2, t3, _, _ = _statistics(np.sort(draws, axis=1), prior_dof * float(np.mean(stds**2)))
    return np.sort(t2), np.sort(t3)


def _p_value(null_sorted: NDArray, observed: float) -> float:
    above = null_sorted.size - np.searchsorted(null_sorted, observed, side="left")
    return float((above + 1) / (null_sorted.size + 1))


def separated(b: NDArray, s: NDArray, parts: list[NDArray], min_step: float, z: float) -> bool:
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
        if separated(b, s, parts, min_step, z):
            return parts
    return None


def segment_regions(beta_grid: NDArray[np.float64], poke_beta: NDArray[np.float64],
                    poke_std: NDArray[np.float64], *, floor: float = 0.03, min_step: float = 0.05,
                    z: float = 2.0, max_regions: int = 6, prior_dof: float = 7.0) -> RegionMap:
    """Label the cells of ``beta_grid (ny, nx)`` (the field's mean) by isopleths chosen from the
    pokes' estimates ``poke_beta (k,)`` and uncertainties ``poke_std (k,)`` (module docstring:
    ``floor``, ``min_step``, ``z``, ``prior_dof``; at most ``max_regions`` classes)."""
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
    return ranked(grid, b, done, order)


def ranked(grid: NDArray[np.float64], values: NDArray[np.float64],
            groups: list[NDArray[np.int64]], order: NDArray[np.int64]) -> RegionMap:
    """The regions of the classes ``groups`` (indices into ``values``), numbered by mean upwards,
    isopleths midway; ``order`` maps an index into ``values`` to the poke's given place."""
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


def poke_classes(mean: NDArray[np.float64], pokes: PokeSet, config: ExplorationConfig,
                 field: FieldName) -> RegionMap:
    """:func:`segment_regions` of the map field ``field``'s mean ``mean (ny, nx)`` with the
    exploration's settings and that field's noise floor and smallest step."""
    cfg = field_settings(config, field)
    return segment_regions(mean, pokes.values, pokes.noise, floor=cfg.noise_floor,
                           min_step=cfg.min_step, max_regions=config.max_regions,
                           prior_dof=config.region_prior_dof)  # fmt: skip


def _check_behaviours(behaviours: Sequence[str | None], n: int) -> list[str | None]:
    items = list(behaviours)
    if len(items) != n:
        raise InvalidArgumentError(
            f"`behaviours` must have one entry per poke ({n}); got {len(items)}")
    for b in items:
        if b is not None and not isinstance(b, str):
            raise InvalidArgumentError(f"`behaviours` must hold text or None; got {b!r}")
    return items


def split_by_behaviour(found: RegionMap, mean: NDArray[np.float64], poke_xy: NDArray[np.float64],
                       poke_value: NDArray[np.float64],
                       behaviours: Sequence[str | None]) -> RegionMap:
    """``found`` with each class whose pokes read several known behaviours split into one class
    per behaviour, the pokes of unknown behaviour joining their nearest known poke's part (module
    docstring); ``found`` itself when no class needs it. ``behaviours (k,)`` each poke's class
    (:data:`KNOWN_BEHAVIOURS`; anything else is unknown), in the pokes' order; the new classes are
    ranked by mean (:func:`ranked`), so their labels on the grid are bands of ``mean`` until the
    caller labels the cells."""
    labels = found.poke_labels
    values = check_array("poke_value", poke_value, (labels.size,))
    xy = check_array("poke_xy", poke_xy, (labels.size, 2), what="metres")
    kinds = [b if b in KNOWN_BEHAVIOURS else None
             for b in _check_behaviours(behaviours, labels.size)]
    groups: list[NDArray[np.int64]] = []
    for c in range(found.n_regions):
        members = np.flatnonzero(labels == c)
        known = [int(i) for i in members if kinds[i] is not None]
        if len({kinds[i] for i in known}) < 2:
            if members.size:
                groups.append(members)
            continue
        anchors = np.array(known, dtype=np.int64)
        part = {}
        for i in members.tolist():
            if kinds[i] is not None:
                part[i] = kinds[i]
            else:  # argmin keeps the earliest of a tie
                near = anchors[np.argmin(np.sum((xy[anchors] - xy[i]) ** 2, axis=1))]
                part[i] = kinds[int(near)]
        for kind in KNOWN_BEHAVIOURS:
            mine = np.array([i for i in members.tolist() if part[i] == kind], dtype=np.int64)
            if mine.size:
                groups.append(mine)
    if len(groups) == found.n_regions:
        return found
    return ranked(mean, values, groups, np.arange(labels.size))


def class_behaviours(poke_labels: NDArray[np.int64], behaviours: Sequence[str | None],
                     n_classes: int) -> list[tuple[str, int]]:
    """Each class's behaviour and how many of its pokes show it: the known behaviour its pokes
    agree on; ``"unknown"`` (0) when none of them reads one; ``"mixed"`` (the count of the most
    frequent) when they read several (regions cut without :func:`split_by_behaviour`)."""
    labels = np.asarray(poke_labels, dtype=np.int64).reshape(-1)
    kinds = _check_behaviours(behaviours, labels.size)
    out = []
    for c in range(n_classes):
        known = [kinds[i] for i in np.flatnonzero(labels == c) if kinds[i] in KNOWN_BEHAVIOURS]
        counts = {k: known.count(k) for k in KNOWN_BEHAVIOURS if k in known}
        if not counts:
            out.append(("unknown", 0))
        elif len(counts) == 1:
            (kind, count), = counts.items()
            out.append((kind, count))
        else:
            out.append(("mixed", max(counts.values())))
    return out
