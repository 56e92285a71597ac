from __future__ import annotations

import math

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval import region_scores


def _truth() -> np.ndarray:
    truth = np.zeros((4, 6), dtype=int)
    truth[:, 3:] = 1
    return truth


def test_perfect_map_with_swapped_labels() -> None:
    truth = _truth()
    beta = np.where(truth == 0, 0.8, 0.2)  # label 0 is soft (60 N), label 1 hard (150 N)
    scores = region_scores(1 - truth, truth, beta, {0: 60.0, 1: 150.0})
    assert (scores.found, scores.true) == (2, 2)
    assert scores.accuracy == 1.0 and scores.mean_iou == 1.0
    assert scores.kendall_tau == pytest.approx(1.0)


def test_wrong_ordering_and_partial_overlap() -> None:
    truth = _truth()
    beta = np.where(truth == 0, 0.2, 0.8)  # the soft region got the low β: wrong order
    predicted = np.zeros_like(truth)
    predicted[:, 4:] = 1  # boundary one column off
    scores = region_scores(predicted, truth, beta, {0: 60.0, 1: math.inf})
    assert scores.accuracy == pytest.approx(20 / 24)
    assert scores.mean_iou == pytest.approx((12 / 16 + 8 / 12) / 2)
    assert scores.kendall_tau == pytest.approx(-1.0)


def test_single_region_and_bad_input() -> None:
    truth = np.zeros((3, 3), dtype=int)
    scores = region_scores(truth, truth, np.zeros((3, 3)), {0: 60.0})
    assert scores.kendall_tau is None and scores.accuracy == 1.0
    with pytest.raises(InvalidArgumentError, match="`truth` must have the shape"):
        region_scores(truth, np.zeros((2, 2), int), np.zeros((3, 3)), {0: 60.0})
    with pytest.raises(InvalidArgumentError, match="lacks the true label"):
        region_scores(truth, truth + 1, np.zeros((3, 3)), {0: 60.0})
