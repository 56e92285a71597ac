"""Layout families of the random world generator, and footprints that are not convex (issue 16)."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.world import (
    LAYOUT_FAMILIES,
    Block,
    Scenario,
    SimulatedWorld,
    WorldConfig,
    random_scenario,
)
from deformap.world._polygon import is_simple, overlap_area, polygon_area, rectangle, triangulate

L_SHAPE = np.array([[0, 0], [0.4, 0], [0.4, 0.1], [0.1, 0.1], [0.1, 0.4], [0, 0.4]], float)


def is_convex(poly: np.ndarray) -> bool:
    """True when the counter-clockwise polygon turns left (or goes straight) at every vertex."""
    e = np.roll(poly, -1, axis=0) - poly
    return bool(np.all(e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1) >= -1e-12))


def test_every_family_is_seeded_and_tiles_the_workspace() -> None:
    xs, ys = np.linspace(0.001, 0.599, 200), np.linspace(0.001, 0.399, 140)
    for family in LAYOUT_FAMILIES:
        for seed in range(8):
            sc = random_scenario(np.random.default_rng(seed), family=family,
                                 hardness_range_n=(30.0, 250.0))
            again = random_scenario(np.random.default_rng(seed), family=family,
                                    hardness_range_n=(30.0, 250.0))
            assert sc.to_dict() == again.to_dict()
            assert sum(b.area_m2 for b in sc.blocks) == pytest.approx(0.24, abs=1e-9)
            assert sc.labels(xs, ys).min() >= 0, (family, seed)  # no bare table left
            assert all(30 <= b.hardness <= 250 for b in sc.blocks if not b.rigid)


def test_family_shapes() -> None:
    rng = np.random.default_rng(3)
    checker = random_scenario(rng, family="checker", p_rigid=0.0)
    h = [b.hardness for b in checker.blocks]  # blocks (0,0), (0,1), (1,0), (1,1): diagonals match
    assert len(h) == 4 and h[0] == h[3] and h[1] == h[2] and h[0] != h[1]
    ell = random_scenario(rng, family="l-shape")
    assert sorted(len(b.polygon) for b in ell.blocks) == [4, 6]
    assert not all(is_convex(b.polygon) for b in ell.blocks)
    insert = random_scenario(rng, family="insert")
    outer, inner = insert.blocks
    assert len(outer.holes) == 1 and not inner.holes
    assert outer.area_m2 + inner.area_m2 == pytest.approx(0.24)
    centre = inner.polygon.mean(axis=0)
    assert not outer.contains(centre)[0] and inner.contains(centre)[0]
    for seed in range(6):  # a U or a star: a footprint that is not convex, as one piece
        sc = random_scenario(np.random.default_rng(seed), family="non-convex")
        assert len(sc.blocks) == 2
        assert any(not is_convex(b.polygon) for b in sc.blocks)
    stripes = random_scenario(rng, family="stripes")
    assert 3 <= len(stripes.blocks) <= 5
    with pytest.raises(InvalidArgumentError, match="`family` must be one of"):
        random_scenario(rng, family="spiral")
    with pytest.raises(InvalidArgumentError, match="'cuts' family only"):
        random_scenario(rng, family="insert", n_regions=3)


def test_polygon_helpers_on_non_convex_footprints() -> None:
    assert is_simple(L_SHAPE) and not is_convex(L_SHAPE)
    assert not is_simple(np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float))  # a bow-tie
    rng = np.random.default_rng(0)
    for _ in range(20):  # star-shaped polygons: triangles tile them
        t = np.sort(rng.uniform(0, 2 * np.pi, 12))
        r = rng.uniform(0.3, 1.0, 12)
        star = np.column_stack([r * np.cos(t), r * np.sin(t)])
        tris = triangulate(star)
        assert len(tris) == 10
        assert sum(polygon_area(tr) for tr in tris) == pytest.approx(polygon_area(star))
        assert all(polygon_area(tr) > 0 for tr in tris)
    # the L against a square over its corner: the L holds 0.1 × 0.1 + 2 × 0.1 × 0.1 of it
    assert overlap_area(L_SHAPE, rectangle(0, 0, 0.2, 0.2)) == pytest.approx(0.03)
    hole = rectangle(0.2, 0.2, 0.3, 0.3)
    frame = rectangle(0, 0, 0.5, 0.5)
    assert overlap_area(frame, rectangle(0.2, 0.2, 0.4, 0.4), (hole,)) == pytest.approx(0.03)
    assert overlap_area(frame, hole, (hole,)) == pytest.approx(0.0, abs=1e-12)


def test_blocks_take_simple_polygons_with_holes_and_refuse_the_rest() -> None:
    block = Block(name="ell", polygon=L_SHAPE[::-1], hardness_n=60.0)  # clockwise is reversed
    assert polygon_area(block.polygon) > 0
    assert block.contains(np.array([[0.05, 0.3], [0.3, 0.3]])).tolist() == [True, False]
    with pytest.raises(InvalidArgumentError, match="simple polygon"):
        Block(name="bow", polygon=np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float),
              hardness_n=60.0)
    with pytest.raises(InvalidArgumentError, match="must lie inside"):
        Block(name="h", polygon=rectangle(0, 0, 0.2, 0.2), hardness_n=60.0,
              holes=(rectangle(0.1, 0.1, 0.3, 0.3),))
    rest = Block(name="rest", polygon=np.array(
        [[0.4, 0], [0.6, 0], [0.6, 0.4], [0.1, 0.4], [0.1, 0.1], [0.4, 0.1]]), hardness_n=150.0)
    Scenario(name="ok", blocks=(block, rest))  # they touch along the L's inner edges
    with pytest.raises(InvalidArgumentError, match="overlap"):
        Scenario(name="bad", blocks=(block, Block(name="sq", polygon=rectangle(0, 0, 0.2, 0.2),
                                                  hardness_n=90.0)))


def test_world_presses_a_non_convex_piece_and_the_insert_in_its_hole() -> None:
    sc = random_scenario(np.random.default_rng(1), family="insert", p_rigid=0.0,
                         hardness_range_n=(30.0, 250.0))
    world = SimulatedWorld(sc, config=WorldConfig.coarse(noise=False),
                           rng=np.random.default_rng(0))
    outer, inner = sc.blocks
    inside = inner.polygon.mean(axis=0)
    # a point of the outer piece well away from the insert: the corner nearest to it, inset
    corners = np.array([[0.06, 0.06], [0.54, 0.06], [0.54, 0.34], [0.06, 0.34]])
    outside = corners[np.argmax(np.linalg.norm(corners - inside, axis=1))]
    assert world.ground_truth_labels([inside[0]], [inside[1]])[0, 0] == 1
    assert world.ground_truth_labels([outside[0]], [outside[1]])[0, 0] == 0
    depth = {b.hardness: world.dent(xy, 0.6).depth_m for b, xy in ((inner, inside),
                                                                   (outer, outside))}
    soft, hard = sorted(depth)
    assert depth[soft] > depth[hard] > 0


def test_scenarios_with_holes_and_non_convex_blocks_round_trip_through_yaml(tmp_path) -> None:
    from deformap.world import load_scenario, save_scenario

    for family in ("insert", "non-convex", "l-shape"):
        sc = random_scenario(np.random.default_rng(4), family=family)
        save_scenario(sc, tmp_path / f"{family}.yaml")
        again = load_scenario(tmp_path / f"{family}.yaml")
        assert again.to_dict() == sc.to_dict()
        xs, ys = np.linspace(0.01, 0.59, 60), np.linspace(0.01, 0.39, 40)
        assert np.array_equal(again.labels(xs, ys), sc.labels(xs, ys))
