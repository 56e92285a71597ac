"""The indicator-kriging cut (``region_labels = "indicator-kriging"``)."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig, Mapper
from deformap.explore._indicator import _order_relations, class_probabilities, indicator_labels
from deformap.testing import synthetic_poke

KW = {"length_scale": 0.2, "signal_std": 0.3}


def test_class_probabilities_are_probabilities_that_honour_the_pokes_and_revert_far_away() -> None:
    xy = np.array([[0.1, 0.1], [0.3, 0.1], [0.5, 0.1], [0.3, 0.3]])
    labels = np.array([0, 1, 2, 2])
    noise = np.full(4, 0.003)
    query = np.vstack([xy, [[50.0, 50.0]], np.random.default_rng(0).uniform(0, 0.6, (200, 2))])
    prob = class_probabilities(xy, labels, noise, query, n_classes=3, **KW)
    assert prob.shape == (205, 3)
    assert np.all(prob >= 0) and np.all(prob <= 1)
    np.testing.assert_allclose(prob.sum(axis=1), 1.0)
    # nearly noiseless pokes: each one's own class, almost surely
    assert np.all(prob[np.arange(4), labels] > 0.95)
    # far from every poke: how often each class was met
    np.testing.assert_allclose(prob[4], [0.25, 0.25, 0.5], atol=1e-9)
    np.testing.assert_array_equal(
        indicator_labels(xy, labels, noise, xy, n_classes=3, **KW), labels)


def test_order_relations_are_restored_by_gslibs_average_correction() -> None:
    cdf = np.array([[0.3, 0.2], [-0.1, 1.2], [0.1, 0.6]])
    np.testing.assert_allclose(_order_relations(cdf), [[0.25, 0.25], [0.0, 1.0], [0.1, 0.6]])


def _mapper(labels: str, pokes: list[tuple[tuple[float, float], float]]) -> Mapper:
    config = ExplorationConfig(field="beta", region_labels=labels)  # type: ignore[arg-type]
    mapper = Mapper(Workspace(lower=(0.0, 0.0), upper=(0.8, 0.6)), config)
    for i, (xy, beta) in enumerate(pokes):
        mapper.add(synthetic_poke(np.array(xy), beta, 0.03, index=i))
    return mapper


def test_two_clean_classes_cut_as_the_isopleth_does() -> None:
    # two β values with one noise: the indicator is a linear function of β, and its share the
    # field's prior mean, so kriging the class is kriging the value
    pokes = [((0.1, 0.1), 0.8), ((0.2, 0.4), 0.8), ((0.5, 0.2), 0.5), ((0.7, 0.5), 0.5),
             ((0.6, 0.1), 0.5)]  # fmt: skip
    ik, iso = _mapper("indicator-kriging", pokes).regions(), _mapper("isopleth", pokes).regions()
    assert ik.n_regions == 2
    np.testing.assert_array_equal(ik.labels, iso.labels)
    np.testing.assert_array_equal(ik.levels, iso.levels)


def test_no_middle_class_band_where_the_two_outer_classes_meet() -> None:
    # soft (β 0.8) left and stiff (0.2) right on the bottom row, a middle foam (0.5) along the top:
    # the field's mean falls from 0.8 to 0.2 between the bottom pokes and its isopleths draw a
    # band of the middle class there, which no poke supports; the kriged classes do not
    pokes = [((0.1, 0.1), 0.8), ((0.2, 0.1), 0.8), ((0.6, 0.1), 0.2), ((0.7, 0.1), 0.2),
             ((0.1, 0.55), 0.5), ((0.4, 0.55), 0.5), ((0.7, 0.55), 0.5)]  # fmt: skip
    ik, iso = _mapper("indicator-kriging", pokes), _mapper("isopleth", pokes)
    found = ik.regions()
    assert found.n_regions == 3 and iso.regions().n_regions == 3
    cells = ik.grid.cells_xy
    between = (np.abs(cells[:, 1] - 0.1) < 0.003) & (cells[:, 0] > 0.2) & (cells[:, 0] < 0.6)
    middle = int(np.flatnonzero(found.class_betas == np.median(found.class_betas))[0])
    assert np.any(iso.regions().labels.ravel()[between] == middle)
    assert not np.any(found.labels.ravel()[between] == middle)
    # the pokes keep their classes
    rows = [int(np.argmin(np.sum((cells - xy) ** 2, axis=1))) for xy, _ in pokes]
    np.testing.assert_array_equal(found.labels.ravel()[rows], found.poke_labels)


def test_bad_labels_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="`poke_labels` must be"):
        class_probabilities(np.zeros((2, 2)), np.array([0, 3]), np.ones(2), np.zeros((1, 2)),
                            n_classes=2, **KW)  # fmt: skip
    with pytest.raises(InvalidArgumentError, match="`region_labels` must be one of"):
        ExplorationConfig(region_labels="kriging")  # type: ignore[arg-type]
