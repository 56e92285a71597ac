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


def test_the_order_of_what_the_map_reports_not_only_of_its_field() -> None:
    from deformap.eval import ordering_scores

    truth = np.repeat([[0, 0, 1, 1]], 3, axis=0)  # soft 60 N left, rigid right
    hardness = {0: 60.0, 1: math.inf}
    beta = np.where(truth == 0, 0.8, 0.1)
    # a map whose two materials merged into one region: the field's means still order them ...
    merged = np.zeros_like(truth)
    assert region_scores(merged, truth, beta, hardness).kendall_tau == 1.0
    # ... but the map reports one value, so it is credited with no order
    scores = ordering_scores(merged, np.array([0.45]), truth, hardness, np.array([0.8, 0.1]),
                             np.array([0, 1]))
    assert scores.order_regions is None and scores.order_pokes == 1.0
    # two found regions, right and wrong way round; pokes read the wrong way round
    right = ordering_scores(1 - truth, np.array([0.1, 0.8]), truth, hardness,
                            np.array([0.1, 0.8]), np.array([0, 1]))
    wrong = ordering_scores(truth, np.array([0.1, 0.8]), truth, hardness,
                            np.array([0.1, 0.8]), np.array([0, 1]))
    assert right.order_regions == 1.0 and wrong.order_regions == 0.0
    assert right.order_pokes == 0.0
    # pokes that share a material do not lower the order (Kendall's τ-b would read 0.82 here)
    five = ordering_scores(truth, np.array([0.8, 0.1]), truth, hardness,
                           np.array([0.6, 0.62, 0.59, 0.0, 0.0]), np.array([0, 0, 0, 1, 1]))
    assert five.order_pokes == 1.0
    half = ordering_scores(truth, np.array([0.8, 0.1]), truth, hardness, np.array([0.3, 0.3]),
                           np.array([0, 1]))
    assert half.order_pokes == 0.5  # a tie across materials counts half
    with pytest.raises(InvalidArgumentError, match="`found` must hold indices"):
        ordering_scores(truth + 5, np.array([0.1, 0.8]), truth, hardness, np.zeros(2),
                        np.array([0, 1]))
    with pytest.raises(InvalidArgumentError, match="lacks the true label"):
        ordering_scores(truth, np.array([0.1, 0.8]), truth, hardness, np.zeros(2),
                        np.array([0, 7]))
