from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.explore._regions import segment_regions


def test_three_separated_classes_give_three_bands() -> None:
    grid = np.tile(np.linspace(0.0, 0.9, 10), (4, 1))
    result = segment_regions(grid, np.array([0.05, 0.1, 0.5, 0.85]), np.full(4, 0.02))
    assert result.n_regions == 3
    np.testing.assert_allclose(result.levels, [0.3, 0.675])
    np.testing.assert_allclose(result.class_betas, [0.075, 0.5, 0.85])
    assert result.labels[0, 0] == 0 and result.labels[0, -1] == 2
    assert np.all(np.diff(result.labels[0]) >= 0)  # monotone along a monotone field


def test_uncertain_pokes_are_not_split() -> None:
    grid = np.zeros((3, 3))
    result = segment_regions(grid, np.array([0.3, 0.45]), np.array([0.1, 0.1]))
    assert result.n_regions == 1 and result.levels.size == 0
    assert np.all(result.labels == 0)
    # the same gap with tight uncertainties is two classes
    assert segment_regions(grid, np.array([0.3, 0.45]), np.array([0.01, 0.01])).n_regions == 2


def test_small_gaps_below_min_step_never_split() -> None:
    result = segment_regions(np.zeros((2, 2)), np.array([0.30, 0.33]), np.zeros(2), min_step=0.05)
    assert result.n_regions == 1


def test_bad_input() -> None:
    with pytest.raises(InvalidArgumentError, match="`poke_beta` must have at least 1 rows"):
        segment_regions(np.zeros((2, 2)), np.zeros(0), np.zeros(0))
    with pytest.raises(InvalidArgumentError, match="`poke_std`"):
        segment_regions(np.zeros((2, 2)), np.zeros(2), np.zeros(3))
