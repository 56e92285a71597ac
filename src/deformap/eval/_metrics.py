"""How good a β-field is, against a world's ground truth.

:func:`region_scores` compares a predicted label map with the true one after the best one-to-one
matching of labels (the Hungarian algorithm on the overlap counts):

- ``accuracy``: share of cells whose matched predicted label is the true one (an unmatched label's
  cells count as wrong);
- ``mean_iou``: intersection over union of each true region with its match, averaged over the true
  regions (an unmatched one scores 0);
- ``kendall_tau``: rank agreement between the field's mean β over each true region and its
  softness (1 / hardness; rigid: 0), ``None`` for fewer than two regions; it judges the field,
  not the regions the map reports.

:func:`ordering_scores` judges what the map reports, as concordances (Harrell's C; Kendall's τ-b
would count two pokes on one material as a tie and read below 1 for a perfect order):

- ``order_regions``: over the pairs of found regions on materials of different softness (the
  material under most of a region), the share whose values are ordered as the softness (a tie
  counts half): 1 ordered, 0.5 as by chance, 0 reversed; ``None`` without such a pair;
- ``order_pokes``: the same over the pairs of pokes, each reading against the material under it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.stats import kendalltau

from deformap._validation import check_array
from deformap.errors import InvalidArgumentError

__all__ = ["OrderingScores", "RegionScores", "ordering_scores", "region_scores"]


@dataclass(frozen=True)
class RegionScores:
    """Region metrics of one map (see the module docstring)."""

    found: int
    true: int
    accuracy: float
    mean_iou: float
    kendall_tau: float | None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def region_scores(predicted: NDArray[np.integer], truth: NDArray[np.integer],
                  beta_grid: NDArray[np.float64], true_hardness: dict[int, float], *,
                  valid: NDArray[np.bool_] | None = None) -> RegionScores:
    """Score a predicted region map against the truth: ``predicted`` and ``truth`` (ny, nx) int
    label maps, ``beta_grid`` (ny, nx) the β-field's mean, ``true_hardness`` each true label's
    hardness in newtons (``math.inf``: rigid), ``valid`` (ny, nx) bool the cells scored (all)."""
    pred = np.asarray(predicted)
    true = np.asarray(truth)
    beta = check_array("beta_grid", beta_grid, pred.shape)
    if true.shape != pred.shape:
        raise InvalidArgumentError(
            f"`truth` must have the shape of `predicted` {pred.shape}; got {true.shape}")
    mask = np.ones(pred.shape, bool) if valid is None else np.asarray(valid, bool)
    p, t, b = pred[mask], true[mask], beta[mask]
    if p.size == 0:
        raise InvalidArgumentError("`valid` must select at least one cell; got none")
    p_labels, p_idx = np.unique(p, return_inverse=True)
    t_labels, t_idx = np.unique(t, return_inverse=True)
    missing = sorted(set(t_labels.tolist()) - set(true_hardness))
    if missing:
        raise InvalidArgumentError(f"`true_hardness` lacks the true label(s) {missing}")
    overlap = np.zeros((t_labels.size, p_labels.size))
    np.add.at(overlap, (t_idx, p_idx), 1.0)
    rows, cols = linear_sum_assignment(-overlap)
    accuracy = float(overlap[rows, cols].sum() / p.size)
    t_size, p_size = overlap.sum(axis=1), overlap.sum(axis=0)
    ious = np.zeros(t_labels.size)
    ious[rows] = overlap[rows, cols] / (t_size[rows] + p_size[cols] - overlap[rows, cols])
    tau: float | None = None
    if t_labels.size >= 2:
        mean_beta = np.array([b[t_idx == i].mean() for i in range(t_labels.size)])
        softness = np.array([1.0 / true_hardness[int(label)] for label in t_labels])
        value = kendalltau(mean_beta, softness).statistic
        tau = None if np.isnan(value) else float(value)
    return RegionScores(found=int(p_labels.size), true=int(t_labels.size), accuracy=accuracy,
                        mean_iou=float(ious.mean()), kendall_tau=tau)


@dataclass(frozen=True)
class OrderingScores:
    """Whether what a map reports orders the materials (see the module docstring)."""

    order_regions: float | None
    order_pokes: float | None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _concordance(values: NDArray[np.float64], softness: NDArray[np.float64]) -> float | None:
    """Share of the pairs with different softness whose values are ordered as the softness is
    (ties in value count half); ``None`` without such a pair."""
    i, j = np.triu_indices(values.size, k=1)
    differ = softness[i] != softness[j]
    if not differ.any():
        return None
    i, j = i[differ], j[differ]
    agree = np.sign(values[i] - values[j]) * np.sign(softness[i] - softness[j])
    return float(np.mean(np.where(agree > 0, 1.0, np.where(agree == 0, 0.5, 0.0))))


def ordering_scores(found: NDArray[np.integer], class_values: NDArray[np.float64],
                    truth: NDArray[np.integer], true_hardness: dict[int, float],
                    poke_values: NDArray[np.float64], poke_truth: NDArray[np.integer],
                    ) -> OrderingScores:
    """Score the order of what a map reports against the materials' softness: ``found`` (ny, nx)
    int region labels indexing ``class_values`` (k,) (each region's reported value), ``truth``
    (ny, nx) int and ``true_hardness`` as for :func:`region_scores`, ``poke_values`` (p,) each
    poke's reading and ``poke_truth`` (p,) int the true label under it."""
    labels = np.asarray(found)
    true = np.asarray(truth)
    values = check_array("class_values", class_values, (None,))
    readings = check_array("poke_values", poke_values, (None,))
    under = np.asarray(poke_truth).reshape(-1)
    if true.shape != labels.shape:
        raise InvalidArgumentError(
            f"`truth` must have the shape of `found` {labels.shape}; got {true.shape}")
    if under.size != readings.size:
        raise InvalidArgumentError(
            f"`poke_truth` must have one label per poke ({readings.size}); got {under.size}")
    if labels.size and (labels.min() < 0 or labels.max() >= values.size):
        raise InvalidArgumentError(
            f"`found` must hold indices into `class_values` (0 to {values.size - 1}); got "
            f"{int(labels.min())} to {int(labels.max())}")
    missing = sorted((set(np.unique(true).tolist()) | set(under.tolist())) - set(true_hardness))
    if missing:
        raise InvalidArgumentError(f"`true_hardness` lacks the true label(s) {missing}")

    def softness(label: int) -> float:
        return 1.0 / true_hardness[int(label)]

    present = np.unique(labels)
    region_softness = []
    for label in present:
        under_region, counts = np.unique(true[labels == label], return_counts=True)
        region_softness.append(softness(under_region[np.argmax(counts)]))
    return OrderingScores(
        order_regions=_concordance(values[present], np.array(region_softness)),
        order_pokes=_concordance(readings, np.array([softness(t) for t in under])),
    )
