"""Region labels by indicator kriging (``ExplorationConfig.region_labels = "indicator-kriging"``).

The classes are the region test's (:func:`deformap.explore.segment_regions`); what this module
decides is which class each cell belongs to. For each class threshold ``k`` (between class ``k``
and ``k + 1``, classes ordered by their mean value) the indicator ``I_k = 1`` when a poke's class
is ``≤ k`` is kriged over the map (Journel 1983): the kriged value is an estimate of
``P(class(x) ≤ k)``, and a cell takes the class of largest probability
``P(class ≤ k) − P(class ≤ k − 1)``.

Choices, and why
----------------
- The indicators are kriged with the map field's own covariance (its length scale and prior
  standard deviation) and each poke's own noise: the weights are then the field's own
  smoother's, so the cut differs from the isopleths only in *what* is smoothed, a poke's class
  rather than its value. A poke on a seam that reads between two classes counts as the class the
  region test gave it, and a class whose values sit far from the isopleth does not push the
  boundary past the pokes of the class next to it. (Fitting an indicator variogram needs more
  pokes than a map has: tens of pairs per lag.)
- Simple kriging about each indicator's share of the pokes: far from every poke a cell reverts to
  how often each class was met, not to an arbitrary prior.
- Kriging weights can be negative, so the estimates are clipped to [0, 1] and made non-decreasing
  in ``k`` by the average of the upward and downward corrections (order-relation correction,
  Deutsch & Journel 1998, GSLIB Sec. V.1.6); ties go to the lower class.

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
    """``cdf (q, m)`` clipped to [0, 1] and non-decreasing along its columns: the average of the
    running maximum from the left and the running minimum from the right (GSLIB's correction)."""
    clipped = np.clip(cdf, 0.0, 1.0)
    up = np.maximum.accumulate(clipped, axis=1)
    down = np.minimum.accumulate(clipped[:, ::-1], axis=1)[:, ::-1]
    return np.asarray((up + down) / 2)


def class_probabilities(poke_xy: NDArray[np.float64], poke_labels: NDArray[np.int64],
                        poke_noise: NDArray[np.float64], query_xy: NDArray[np.float64], *,
                        n_classes: int, length_scale: float, signal_std: float
                        ) -> NDArray[np.float64]:  # fmt: skip
    """``(q, n_classes)`` the kriged probability of each class at ``query_xy (q, 2)`` metres.

    Parameters
    ----------
    poke_xy : (k, 2) float, metres
    poke_labels : (k,) int
        Each poke's class, ``0 .. n_classes - 1``.
    poke_noise : (k,) float
        Each poke's noise in the field's units (the field's floor included).
    n_classes : int
    length_scale, signal_std : float
        The map field's prior (σ_w, σ_e), whose ratio to ``poke_noise`` sets the weights.
    """
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
