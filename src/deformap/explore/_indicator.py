"""Region labels by indicator kriging (``ExplorationConfig.region_labels = "indicator-kriging"``).

The classes are the region test's; for each threshold ``k`` between classes (ordered by mean) the
indicator ``I_k = [class ≤ k]`` of the pokes is kriged over the map (Journel 1983), estimating
``P(class(x) ≤ k)``; a cell takes the class of largest probability. It is simple kriging about
each indicator's share of the pokes, with the map field's own covariance and each poke's noise (a
map has too few pokes to fit an indicator variogram). The estimates are clipped to [0, 1] and
made non-decreasing in ``k`` (order-relation correction, Deutsch & Journel 1998, GSLIB Sec.
V.1.6); ties go to the lower class.

References
----------
Journel, A. G. (1983). Nonparametric estimation of spatial distributions. Mathematical Geology
15(3), 445–468.
Deutsch, C. V., Journel, A. G. (1998). GSLIB: Geostatistical Software Library and User's Guide,
2nd ed. Oxford University Press.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError
from deformap.gp import apply_smoother

__all__ = ["class_probabilities", "indicator_labels"]


def _order_relations(cdf: NDArray[np.float64]) -> NDArray[np.float64]:
    """``cdf (q, m)`` clipped to [0, 1], the mean of its running max and reversed running min."""
    clipped = np.clip(cdf, 0.0, 1.0)
    up = np.maximum.accumulate(clipped, axis=1)
    down = np.minimum.accumulate(clipped[:, ::-1], axis=1)[:, ::-1]
    return np.asarray((up + down) / 2)


def class_probabilities(poke_xy: NDArray[np.float64], poke_labels: NDArray[np.int64],
                        poke_noise: NDArray[np.float64], query_xy: NDArray[np.float64], *,
                        n_classes: int, length_scale: float, signal_std: float
                        ) -> NDArray[np.float64]:  # fmt: skip
    """``(q, n_classes)`` the kriged probability of each class at ``query_xy (q, 2)`` metres, from
    pokes at ``poke_xy (k, 2)`` of classes ``poke_labels (k,)`` with noise ``poke_noise (k,)`` in
    the field's units, under the field's prior ``length_scale`` and ``signal_std``."""
    xy = check_array("poke_xy", poke_xy, (None, 2), what="metres", min_rows=1)
    labels = np.asarray(poke_labels)
    if labels.shape != (xy.shape[0],) or not np.issubdtype(labels.dtype, np.integer) or (
            labels.min() < 0 or labels.max() >= n_classes):
        raise InvalidArgumentError(
            f"`poke_labels` must be ({xy.shape[0]},) integers in [0, {n_classes}); got "
            f"{labels.tolist()}")  # fmt: skip
    noise = check_array("poke_noise", poke_noise, (xy.shape[0],), what="standard deviations")
    query = check_array("query_xy", query_xy, (None, 2), what="metres")
    check_positive("length_scale", length_scale)
    check_positive("signal_std", signal_std)
    if n_classes == 1:
        return np.ones((query.shape[0], 1))
    # I_k = [class ≤ k] for the n_classes − 1 thresholds
    indicators = (labels[:, None] <= np.arange(n_classes - 1)[None, :]).astype(float)
    share = indicators.mean(axis=0)
    kriged = share + apply_smoother(xy, noise, query, indicators - share,
                                    length_scale=length_scale, signal_std=signal_std)
    cdf = _order_relations(np.atleast_2d(kriged))
    cdf = np.column_stack([cdf, np.ones(query.shape[0])])
    return np.asarray(np.diff(cdf, axis=1, prepend=0.0))


def indicator_labels(poke_xy: NDArray[np.float64], poke_labels: NDArray[np.int64],
                     poke_noise: NDArray[np.float64], cells_xy: NDArray[np.float64], *,
                     n_classes: int, length_scale: float, signal_std: float
                     ) -> NDArray[np.int64]:  # fmt: skip
    """``(c,)`` the most probable class of each of ``cells_xy (c, 2)`` (ties: the lower class);
    the arguments are :func:`class_probabilities`'."""
    prob = class_probabilities(poke_xy, poke_labels, poke_noise, cells_xy, n_classes=n_classes,
                               length_scale=length_scale, signal_std=signal_std)  # fmt: skip
    return np.asarray(np.argmax(prob, axis=1), dtype=np.int64)
