"""Regions and the behaviour each press reads: pokes of different known behaviours are never one
region; a poke of unknown behaviour is compatible with any."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig, map_regions
from deformap.explore._classes import class_behaviours, segment_regions, split_by_behaviour
from deformap.explore._field import PokeSet

# a 0.4 m × 0.2 m map; elastic foam on the left half, a plastic block of the same β on the right
_XS, _YS = np.linspace(0.0, 0.4, 17), np.linspace(0.0, 0.2, 9)
_GX, _GY = np.meshgrid(_XS, _YS)
_CELLS = np.column_stack([_GX.ravel(), _GY.ravel()])
_XY = np.array([[0.05, 0.05], [0.1, 0.15], [0.15, 0.1], [0.25, 0.1], [0.3, 0.05], [0.35, 0.15]])
_BETA = np.array([0.50, 0.52, 0.49, 0.51, 0.50, 0.48])
_SIDE = ["elastic", "elastic", "elastic", "plastic", "plastic", "plastic"]


def _pokes(values: np.ndarray = _BETA, xy: np.ndarray = _XY) -> PokeSet:
    return PokeSet(xy, values, np.full(values.size, 0.03))


@pytest.mark.parametrize("labels_by", ["nearest", "isopleth", "indicator-kriging"])
def test_pokes_of_two_known_behaviours_are_never_one_region(labels_by: str) -> None:
    config = ExplorationConfig(region_labels=labels_by)  # type: ignore[arg-type]
    mean = np.full(_GX.shape, 0.5)
    alone = map_regions(mean, _pokes(), _CELLS, config, "beta")
    assert alone.n_regions == 1  # by β alone: one material
    found = map_regions(mean, _pokes(), _CELLS, config, "beta", behaviours=_SIDE)
    assert found.n_regions == 2
    assert len(set(found.poke_labels[:3])) == 1 and len(set(found.poke_labels[3:])) == 1
    assert found.poke_labels[0] != found.poke_labels[3]
    # the cells follow the pokes: left of the middle elastic's, right of it plastic's
    assert np.all(found.labels[:, _XS <= 0.15] == found.poke_labels[0])
    assert np.all(found.labels[:, _XS >= 0.25] == found.poke_labels[3])
    assert found.levels.size == found.n_regions - 1


def test_an_unknown_behaviour_joins_the_part_of_its_nearest_known_poke() -> None:
    config = ExplorationConfig()
    mean = np.full(_GX.shape, 0.5)
    read = ["elastic", None, "unknown", "plastic", "unknown", "plastic"]
    found = map_regions(mean, _pokes(), _CELLS, config, "beta", behaviours=read)
    assert found.n_regions == 2
    # poke 1 (none read) lies 0.11 m from poke 0 (elastic), 0.16 m from poke 3 (plastic);
    # poke 2 (unknown) 0.11 m from poke 0 and 0.10 m from poke 3: it joins the plastic part
    np.testing.assert_array_equal(found.poke_labels == found.poke_labels[0],
                                  [True, True, False, False, False, False])
    # all unknown (or one known behaviour among unknowns): values alone decide
    for only in (["unknown"] * 6, ["plastic"] + ["unknown"] * 5, [None] * 6):
        assert map_regions(mean, _pokes(), _CELLS, config, "beta", behaviours=only).n_regions == 1


def test_classes_of_different_values_and_one_behaviour_stay_apart() -> None:
    values = np.array([0.2, 0.22, 0.21, 0.8, 0.79, 0.81])
    found = segment_regions(np.zeros((2, 2)), values, np.full(6, 0.02))
    assert found.n_regions == 2
    same = split_by_behaviour(found, np.zeros((2, 2)), _XY, values, ["plastic"] * 6)
    assert same is found
    # a plastic poke among the soft elastic ones makes a third class, the others unchanged
    read = ["elastic", "plastic", "elastic", "elastic", "elastic", "elastic"]
    split = split_by_behaviour(found, np.zeros((2, 2)), _XY, values, read)
    assert split.n_regions == 3
    assert sorted(np.bincount(split.poke_labels).tolist()) == [1, 2, 3]
    assert split.poke_labels[1] not in split.poke_labels[[0, 2]]


def test_each_class_reports_its_behaviour_and_evidence() -> None:
    labels = np.array([0, 0, 0, 1, 1, 2, 2])
    read = ["plastic", "unknown", "plastic", None, "unknown", "elastic", "viscoelastic"]
    assert class_behaviours(labels, read, 4) == [("plastic", 2), ("unknown", 0), ("mixed", 1),
                                                 ("unknown", 0)]


def test_bad_behaviours_are_refused_in_one_line() -> None:
    config = ExplorationConfig()
    mean = np.full(_GX.shape, 0.5)
    with pytest.raises(InvalidArgumentError, match="`behaviours` must have one entry per poke"):
        map_regions(mean, _pokes(), _CELLS, config, "beta", behaviours=_SIDE[:5])
    with pytest.raises(InvalidArgumentError, match="`behaviours` must hold text"):
        map_regions(mean, _pokes(), _CELLS, replace(config), "beta",
                    behaviours=[1, 2, 3, 4, 5, 6])  # type: ignore[list-item]
