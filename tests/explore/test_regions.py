from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.explore._classes import RegionMap, ranked, segment_regions
from deformap.explore._places import merge_seam_classes, place_split, split_by_place


def test_three_separated_classes_give_three_bands() -> None:
    grid = np.tile(np.linspace(0.0, 0.9, 10), (4, 1))
    betas = np.array([0.02, 0.0, 0.01, 0.5, 0.52, 0.48, 0.85, 0.86, 0.84])
    result = segment_regions(grid, betas, np.full(betas.size, 0.02))
    assert result.n_regions == 3
    np.testing.assert_allclose(result.class_betas, [0.01, 0.5, 0.85], atol=1e-9)
    np.testing.assert_allclose(result.levels, [0.255, 0.675], atol=1e-9)
    assert result.labels[0, 0] == 0 and result.labels[0, -1] == 2
    assert np.all(np.diff(result.labels[0]) >= 0)  # monotone along a monotone field


def test_one_material_with_the_claimed_scatter_is_one_region_at_the_test_level() -> None:
    splits = 0
    for seed in range(100):
        rng = np.random.default_rng(seed)
        n = int(rng.integers(5, 13))
        stds = rng.uniform(0.03, 0.06, size=n)
        betas = 0.6 + rng.normal(0.0, stds)
        splits += segment_regions(np.zeros((2, 2)), betas, stds).n_regions > 1
    assert splits <= 10  # a 5 % test (Bonferroni over the 2- and 3-part splits)


def test_without_prior_dof_the_test_is_scale_free() -> None:
    # The uncertainties claimed are half the real scatter: trusting them splits one material;
    # prior_dof=0 estimates the scatter from the βs alone and keeps it whole.
    trusted = untrusted = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        betas = 0.7 + rng.normal(0.0, 0.06, size=10)
        trusted += segment_regions(np.zeros((2, 2)), betas, np.full(10, 0.03)).n_regions > 1
        untrusted += segment_regions(
            np.zeros((2, 2)), betas, np.full(10, 0.03), prior_dof=0.0
        ).n_regions > 1
    assert untrusted == 0 and trusted > untrusted


def test_two_close_materials_are_told_apart_with_a_few_pokes() -> None:
    # 0.12 apart, each poke known to 0.03: seven pokes suffice; the scale-free test cannot tell.
    betas = np.array([0.55, 0.59, 0.62, 0.72, 0.73, 0.74, 0.75])
    stds = np.full(betas.size, 0.03)
    result = segment_regions(np.zeros((2, 2)), betas, stds)
    assert result.n_regions == 2
    np.testing.assert_allclose(result.class_betas, [0.5867, 0.735], atol=1e-3)
    assert segment_regions(np.zeros((2, 2)), betas, stds, prior_dof=0.0).n_regions == 1


def test_a_poke_on_a_boundary_does_not_bridge_two_classes() -> None:
    betas = np.array([0.86, 0.84, 0.87, 0.85, 0.78, 0.65, 0.66, 0.59, 0.67, 0.65])
    result = segment_regions(np.zeros((2, 2)), betas, np.full(betas.size, 0.08))
    assert result.n_regions == 2


def test_uncertain_pokes_are_not_split() -> None:
    grid = np.zeros((3, 3))
    result = segment_regions(grid, np.array([0.3, 0.45]), np.array([0.1, 0.1]))
    assert result.n_regions == 1 and result.levels.size == 0
    assert np.all(result.labels == 0)
    # groups that differ by less than min_step are never split
    close = np.array([0.30, 0.30, 0.31, 0.33, 0.33, 0.34])
    assert segment_regions(grid, close, np.full(6, 0.001), min_step=0.05).n_regions == 1


def test_bad_input() -> None:
    with pytest.raises(InvalidArgumentError, match="`poke_beta` must have at least 1 rows"):
        segment_regions(np.zeros((2, 2)), np.zeros(0), np.zeros(0))
    with pytest.raises(InvalidArgumentError, match="`poke_std`"):
        segment_regions(np.zeros((2, 2)), np.zeros(2), np.zeros(3))
    with pytest.raises(InvalidArgumentError, match="`prior_dof`"):
        segment_regions(np.zeros((2, 2)), np.zeros(2), np.zeros(2), prior_dof=-1.0)
    with pytest.raises(InvalidArgumentError, match="`max_regions`"):
        segment_regions(np.zeros((2, 2)), np.zeros(2), np.zeros(2), max_regions=0)


def test_each_poke_gets_the_class_its_beta_was_grouped_in() -> None:
    betas = np.array([0.86, 0.01, 0.5, 0.0, 0.84, 0.52, 0.02, 0.48, 0.85])
    result = segment_regions(np.zeros((2, 2)), betas, np.full(betas.size, 0.02))
    np.testing.assert_array_equal(result.poke_labels, [2, 0, 1, 0, 2, 1, 0, 1, 2])
    for k in range(result.n_regions):
        assert betas[result.poke_labels == k].mean() == pytest.approx(result.class_betas[k])


def test_nearest_poke_labels_give_each_cell_its_nearest_pokes_class() -> None:
    xs, ys = np.linspace(0.0, 0.6, 13), np.linspace(0.0, 0.4, 9)
    gx, gy = np.meshgrid(xs, ys)
    cells = np.column_stack([gx.ravel(), gy.ravel()])
    pokes = np.array([[0.1, 0.2], [0.2, 0.1], [0.45, 0.2], [0.5, 0.3]])
    betas = np.array([0.85, 0.84, 0.30, 0.31])
    # a field whose isopleth lies far from the pokes' midline (reverting to its mean at the left)
    field = np.where(gx < 0.05, 0.4, np.where(gx < 0.35, 0.85, 0.3))
    found = segment_regions(field, betas, np.full(4, 0.02))
    assert found.n_regions == 2 and found.labels[4, 0] == 0  # the left edge cut off by the band
    near = found.nearest_poke(pokes, cells)
    np.testing.assert_array_equal(found.poke_labels, [1, 1, 0, 0])
    # the soft pokes' side of the perpendicular bisector between (0.2, 0.1) and (0.45, 0.2),
    # the two pokes of different classes that face each other across the middle
    soft = gx < 0.30
    np.testing.assert_array_equal(near.labels[:, :5], 1)  # x ≤ 0.2 m: nearer a soft poke
    np.testing.assert_array_equal(near.labels[:, 8:], 0)  # x ≥ 0.4 m: nearer a stiff poke
    assert np.mean(near.labels == soft) > 0.9
    assert near.labels[4, 0] == 1  # the left edge goes to the soft pokes beside it
    np.testing.assert_array_equal(near.levels, found.levels)
    with pytest.raises(InvalidArgumentError, match="`poke_xy`"):
        found.nearest_poke(pokes[:3], cells)
    with pytest.raises(InvalidArgumentError, match="`cells_xy`"):
        found.nearest_poke(pokes, cells[:-1])


_THICK = np.full(25, 0.05)  # 5 cm foam: a joint within 10 cm of a press reaches it


def _grid_pokes(value_at) -> tuple[np.ndarray, np.ndarray]:
    xs = np.linspace(0.0, 0.2, 5)
    xy = np.array([(x, y) for y in xs for x in xs])
    return xy, np.array([value_at(x, y) for x, y in xy])


def test_a_class_of_seam_pokes_joins_the_classes_it_lies_between() -> None:
    """Soft on the left, hard on the right, the middle column pressed on the seam reads between;
    taken for a material by the values alone, it is merged once its pokes border both sides."""
    xy, value = _grid_pokes(lambda x, y: 0.0 if x < 0.09 else 2.0 if x > 0.11 else
                            (0.9 if y < 0.1 else 1.1))
    std = np.full(value.size, 0.05)
    found = segment_regions(np.zeros((2, 2)), value, std)
    assert found.n_regions == 4  # the seam's 0.9s and 1.1s are two classes of their own
    merged = merge_seam_classes(found, np.zeros((2, 2)), xy, value, _THICK)
    assert merged.n_regions == 2
    middle = np.isclose(xy[:, 0], 0.1)
    # each seam poke ends on the side nearer its value: 0.9 soft, 1.1 hard
    assert merged.poke_labels[middle & (value < 1.0)].tolist() == [0, 0]
    assert merged.poke_labels[middle & (value > 1.0)].tolist() == [1, 1, 1]
    np.testing.assert_allclose(merged.class_betas, [
        value[merged.poke_labels == 0].mean(), value[merged.poke_labels == 1].mean()])


def test_a_material_with_pokes_inside_it_is_not_a_seam() -> None:
    """A middle value whose block has pokes bordering only its own class stays a region."""
    xy, value = _grid_pokes(lambda x, y: 0.0 if x < 0.09 else 1.0 if y > 0.09 else 2.0)
    found = segment_regions(np.zeros((2, 2)), value, np.full(value.size, 0.05))
    merged = merge_seam_classes(found, np.zeros((2, 2)), xy, value, _THICK)
    assert merged.n_regions == found.n_regions == 3
    np.testing.assert_array_equal(merged.poke_labels, found.poke_labels)


def test_a_press_by_a_free_face_reading_softer_than_both_joins_a_neighbour() -> None:
    """Two pieces laid side by side: one press beside the joint reads softer than either; it
    borders both, so it is no third material."""
    xy, value = _grid_pokes(lambda x, y: 1.0 if x < 0.09 else 2.0)
    joint = np.flatnonzero(np.isclose(xy[:, 0], 0.05) & np.isclose(xy[:, 1], 0.1))
    value[joint] = 0.2
    found = segment_regions(np.zeros((2, 2)), value, np.full(value.size, 0.05))
    assert found.n_regions == 3 and found.poke_labels[joint] == [0]
    merged = merge_seam_classes(found, np.zeros((2, 2)), xy, value, _THICK)
    assert merged.n_regions == 2 and merged.poke_labels[joint] == [0]
    np.testing.assert_array_equal(merged.poke_labels[value != 0.2], found.poke_labels[value != 0.2] - 1)


def test_an_insert_met_by_one_poke_stays_a_region() -> None:
    """One poke inside a piece borders pokes of one other class only: kept."""
    xy, value = _grid_pokes(lambda x, y: 0.0 if x < 0.09 else 2.0)
    centre = np.flatnonzero(np.isclose(xy[:, 0], 0.15) & np.isclose(xy[:, 1], 0.1))
    value[centre] = 1.0
    found = segment_regions(np.zeros((2, 2)), value, np.full(value.size, 0.05))
    assert found.n_regions == 3
    merged = merge_seam_classes(found, np.zeros((2, 2)), xy, value, _THICK)
    np.testing.assert_array_equal(merged.poke_labels, found.poke_labels)


def test_pokes_on_one_line_are_neighbours_along_it() -> None:
    """A line of pokes has no triangle: the joint's poke borders the pokes either side of it
    along the line, exactly on it or a hair off it alike."""
    value = np.array([0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0])
    found = segment_regions(np.zeros((2, 2)), value, np.full(7, 0.05))
    assert found.n_regions == 3
    for off in (0.0, 1e-7):
        xy = np.column_stack([np.linspace(0, 0.18, 7), np.zeros(7)])
        xy[3, 1] += off
        merged = merge_seam_classes(found, np.zeros((2, 2)), xy, value, np.full(7, 0.05))
        assert merged.n_regions == 2, off
        assert merged.poke_labels.tolist() == [0, 0, 0, 0, 1, 1, 1]


def test_a_joint_farther_than_the_layer_reaches_is_no_junction() -> None:
    """The seam column of the first test, read with 1 cm foam: its neighbours 5 cm away lie
    beyond twice the thickness, so nothing merges; without the thickness nothing merges either."""
    xy, value = _grid_pokes(lambda x, y: 0.0 if x < 0.09 else 2.0 if x > 0.11 else
                            (0.9 if y < 0.1 else 1.1))
    found = segment_regions(np.zeros((2, 2)), value, np.full(value.size, 0.05))
    for thickness in (np.full(25, 0.01), None):
        merged = merge_seam_classes(found, np.zeros((2, 2)), xy, value, thickness)
        np.testing.assert_array_equal(merged.poke_labels, found.poke_labels)
    with pytest.raises(InvalidArgumentError, match="thickness_m"):
        merge_seam_classes(found, np.zeros((2, 2)), xy, value, np.full(3, 0.05))


def _halves(rng: np.random.Generator, contrast: float, scatter: float = 0.05
            ) -> tuple[np.ndarray, np.ndarray]:
    """Twenty pokes on a 60 × 40 cm table: ln E one value on the left half and ``contrast``
    more on the right, each read with ``scatter``."""
    xy = np.column_stack([rng.uniform(0.02, 0.58, 20), rng.uniform(0.02, 0.38, 20)])
    value = np.log(10e3) + contrast * (xy[:, 0] > 0.3) + scatter * rng.standard_normal(20)
    return xy, value


def _one_class(value: np.ndarray) -> RegionMap:
    return ranked(np.zeros((2, 2)), value, [np.arange(value.size)], np.arange(value.size))


def test_two_close_materials_side_by_side_split_by_their_places() -> None:
    rng = np.random.default_rng(3)
    xy, value = _halves(rng, contrast=0.2)  # ln 1.22: under the modulus field's smallest step
    found = segment_regions(np.zeros((2, 2)), value, np.full(20, 0.05), floor=0.05,
                            min_step=0.285)
    assert found.n_regions == 1  # the values alone cannot tell them
    split = split_by_place(found, np.zeros((2, 2)), xy, value, np.full(20, 0.05),
                           np.full(20, 0.03), max_regions=6)
    assert split.n_regions == 2
    right = xy[:, 0] > 0.3  # the split is by value: a poke read across the other's may follow it
    assert np.count_nonzero(split.poke_labels == right) >= 18
    # the same split again from the same pokes (a fixed seed for the shuffles)
    again = split_by_place(found, np.zeros((2, 2)), xy, value, np.full(20, 0.05),
                           np.full(20, 0.03), max_regions=6)
    np.testing.assert_array_equal(again.poke_labels, split.poke_labels)


def test_one_material_is_not_split_by_place_beyond_the_test_level() -> None:
    rng = np.random.default_rng(4)
    splits = 0
    for _ in range(40):
        xy, value = _halves(rng, contrast=0.0, scatter=0.1)
        if place_split(value, np.full(20, 0.1), xy) is not None:
            splits += 1
    assert splits <= 5  # 5 % of 40 is 2; a binomial tail above 5 has probability under 2 %


def test_a_split_by_place_needs_the_values_apart_and_six_pokes_away_from_other_classes() -> None:
    rng = np.random.default_rng(5)
    xy, value = _halves(rng, contrast=0.2)
    # claimed σ so large that the parts' means are not 2 standard errors apart
    assert place_split(value, np.full(20, 1.0), xy) is None
    assert place_split(value[:5], np.full(5, 0.05), xy[:5]) is None  # fewer than six pokes
    # every poke within reach of another class's (thickness 0.5 m): none tested, none split
    others = np.vstack([xy, [[0.3, 0.2]]])
    found = ranked(np.zeros((2, 2)), np.append(value, 12.0),
                    [np.arange(20), np.array([20])], np.arange(21))
    kept = split_by_place(found, np.zeros((2, 2)), others, np.append(value, 12.0),
                          np.full(21, 0.05), np.full(21, 0.5), max_regions=6)
    assert kept is found
    # without every poke's thickness nothing is split
    assert split_by_place(_one_class(value), np.zeros((2, 2)), xy, value, np.full(20, 0.05),
                          None, max_regions=6).n_regions == 1
    # nor beyond max_regions
    assert split_by_place(_one_class(value), np.zeros((2, 2)), xy, value, np.full(20, 0.05),
                          np.full(20, 0.03), max_regions=1).n_regions == 1


def test_pokes_repeated_at_one_place_end_the_split_by_place() -> None:
    """Each place on the left pressed once high and then six times low, those on the right once
    high, all at one spot each (the review's case that looped forever: a tested poke took the
    part of a co-located one): a tested poke keeps its own part, so the split ends, in two."""
    xs, ys = np.linspace(0.05, 0.55, 8), np.linspace(0.05, 0.35, 5)
    grid = np.array([(x, y) for y in ys for x in xs])
    xy, value = [], []
    for place in grid:
        presses = 7 if place[0] < 0.25 else 1
        xy += [place] * presses
        value += [np.log(13e3)] + [np.log(9e3)] * (presses - 1)
    xy_arr, values = np.array(xy), np.array(value)
    n = values.size
    assert place_split(values, np.full(n, 0.05), xy_arr) is not None  # the split is tested
    split = split_by_place(_one_class(values), np.zeros((2, 2)), xy_arr, values,
                           np.full(n, 0.05), np.full(n, 0.01), max_regions=6)
    assert split.n_regions == 2
    low = values < np.log(10e3)
    assert np.all(split.poke_labels[low] == 0) and np.all(split.poke_labels[~low] == 1)


def test_with_the_split_by_place_on_the_junction_rule_still_merges_a_joint_column() -> None:
    """A joint column between two foams is merged with the split on as with it off (the split,
    which runs after the junction rule, finds nothing to split here)."""
    from deformap.explore import ExplorationConfig, PokeSet, map_regions

    xs, ys = np.linspace(0.05, 0.55, 7), np.linspace(0.05, 0.35, 5)
    xy = np.array([(x, y) for y in ys for x in xs])
    value = np.log(np.where(xy[:, 0] < 0.28, 10e3, np.where(xy[:, 0] > 0.32, 40e3, 20e3)))
    pokes = PokeSet(xy, value, np.full(len(xy), 0.1), thickness=np.full(len(xy), 0.06))
    cells = np.array([(x, y) for y in np.linspace(0, 0.4, 9) for x in np.linspace(0, 0.6, 13)])
    mean = np.zeros((9, 13))
    on = map_regions(mean, pokes, cells, ExplorationConfig(field="modulus"), "modulus")
    off = map_regions(mean, pokes, cells,
                      ExplorationConfig(field="modulus", split_by_place=False), "modulus")
    assert on.n_regions == off.n_regions == 2  # the joint merged; the two foams not split again
    np.testing.assert_array_equal(on.poke_labels, off.poke_labels)
