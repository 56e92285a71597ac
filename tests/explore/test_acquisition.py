from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.explore._acquisition import choose_target


def _cells() -> tuple[np.ndarray, np.ndarray]:
    xs = np.linspace(0, 1, 11)
    gx, gy = np.meshgrid(xs, xs)
    cells = np.column_stack([gx.ravel(), gy.ravel()])
    variance = np.exp(-np.sum((cells - [0.8, 0.3]) ** 2, axis=1) / 0.1)
    return cells, variance


def test_stops_when_nothing_exceeds_the_threshold() -> None:
    cells, variance = _cells()
    rng = np.random.default_rng(0)
    for strategy in ("paper", "max-variance"):
        assert choose_target(strategy, cells, variance, 2.0, rng) is None


def test_max_variance_picks_the_peak_and_paper_stays_above_threshold() -> None:
    cells, variance = _cells()
    np.testing.assert_allclose(
        choose_target("max-variance", cells, variance, 0.1, np.random.default_rng(0)), [0.8, 0.3]
    )
    rng = np.random.default_rng(1)
    picks = [choose_target("paper", cells, variance, 0.5, rng) for _ in range(30)]
    for xy in picks:
        i = np.flatnonzero(np.all(cells == xy, axis=1))[0]
        assert variance[i] > 0.5
    assert len({tuple(p) for p in picks}) > 1  # random, not always the peak
    again = [
        choose_target("paper", cells, variance, 0.5, np.random.default_rng(1)) for _ in range(1)
    ]
    np.testing.assert_array_equal(again[0], picks[0])


def test_min_max_variance_uses_the_look_ahead() -> None:
    cells, variance = _cells()
    target = np.array([0.2, 0.9])

    def look_ahead(candidates: np.ndarray) -> np.ndarray:
        return np.linalg.norm(candidates - target, axis=1)

    pick = choose_target(
        "min-max-variance",
        cells,
        np.ones(len(cells)),
        0.5,
        np.random.default_rng(0),
        look_ahead=look_ahead,
    )
    np.testing.assert_allclose(pick, target)
    with pytest.raises(InvalidArgumentError, match="`look_ahead` is required"):
        choose_target("min-max-variance", cells, variance, 0.1, np.random.default_rng(0))
    with pytest.raises(InvalidArgumentError, match="`strategy` must be one of"):
        choose_target("greedy", cells, variance, 0.1, np.random.default_rng(0))
