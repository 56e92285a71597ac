"""Scenarios: the built-in Table I layouts, the YAML format and its strict checks, random worlds."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import ConfigError, InvalidArgumentError
from deformap.world import (
    Block,
    Scenario,
    hardness_to_youngs_modulus,
    list_scenarios,
    load_scenario,
    random_scenario,
    save_scenario,
    youngs_modulus_to_hardness,
)
from deformap.world._polygon import convex_overlap_area, polygon_area, rectangle

TABLE_I = ["homogeneous-60", "homogeneous-110", "heterogeneous-60-150", "heterogeneous-110-150",
           "heterogeneous-150-rigid", "heterogeneous-60-110-rigid"]


def test_hardness_conversion_reference_values() -> None:
    # issue 3: 60, 110, 150 N -> 4.6, 8.5, 11.6 kPa
    got = [hardness_to_youngs_modulus(h) / 1e3 for h in (60, 110, 150)]
    np.testing.assert_allclose(got, [4.644, 8.514, 11.610], atol=0.001)
    assert youngs_modulus_to_hardness(hardness_to_youngs_modulus(77.0)) == pytest.approx(77.0)
    with pytest.raises(InvalidArgumentError, match="`hardness_n` must be > 0"):
        hardness_to_youngs_modulus(0.0)


def test_table_i_scenarios_exist_cover_the_area_and_have_their_hardness() -> None:
    assert list_scenarios() == TABLE_I
    xs, ys = np.linspace(0.005, 0.595, 60), np.linspace(0.005, 0.395, 40)
    for name in TABLE_I:
        sc = load_scenario(name)
        labels = sc.labels(xs, ys)
        assert labels.shape == (40, 60)
        assert labels.min() >= 0, f"{name}: part of the area is bare table"
        hardness = sorted({b.hardness for b in sc.blocks})
        expected = sorted(float(t) if t != "rigid" else np.inf for t in name.split("-")[1:])
        assert hardness == expected, name
        assert sum(polygon_area(b.polygon) for b in sc.blocks) == pytest.approx(0.24)


def test_three_region_layout_has_a_slanted_boundary() -> None:
    sc = load_scenario("heterogeneous-60-110-rigid")
    labels = sc.labels(np.linspace(0.0, 0.6, 121), np.array([0.02, 0.38]))
    first_110 = [int(np.argmax(row == 1)) for row in labels]
    assert first_110[0] != first_110[1]  # the 60|110 cut is not parallel to y


def test_yaml_round_trip(tmp_path) -> None:
    sc = load_scenario("heterogeneous-60-110-rigid")
    path = tmp_path / "s.yaml"
    save_scenario(sc, path)
    back = load_scenario(str(path))
    assert back.region_names == sc.region_names
    for a, b in zip(back.blocks, sc.blocks, strict=True):
        np.testing.assert_allclose(a.polygon, b.polygon)
        assert a.hardness == b.hardness and a.rigid == b.rigid


GOOD = """
name: custom
workspace: {lower: [0.0, 0.0], upper: [0.7, 0.4]}
blocks:
  - name: soft
    rect: [0.0, 0.0, 0.3, 0.4]
    hardness_n: 60
  - name: board
    polygon: [[0.3, 0.0], [0.6, 0.0], [0.6, 0.4], [0.3, 0.4]]
    rigid: true
    thickness_m: 0.03
  - name: stiff
    rect: [0.6, 0.0, 0.7, 0.1]
    youngs_modulus_pa: 20000
"""


def test_custom_yaml_reads_rect_polygon_modulus_and_rigid(tmp_path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(GOOD)
    sc = load_scenario(path)
    assert [b.rigid for b in sc.blocks] == [False, True, False]
    assert sc.blocks[1].thickness_m == 0.03
    assert sc.blocks[2].hardness_n == pytest.approx(20000 * 0.0323 * 0.4)
    assert sc.labels(np.array([0.65]), np.array([0.05, 0.3])).ravel().tolist() == [2, -1]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("hardness_n: 60", "hardness_n: 60\n    squishiness: 3"), "unknown key"),
        (("rect: [0.6, 0.0, 0.7, 0.1]", "rect: [0.5, 0.0, 0.7, 0.1]"), "overlap"),
        (("thickness_m: 0.03", "thickness_m: -0.03"), "thickness_m` must be >= 0.001"),
        (("hardness_n: 60", "hardness_n: 0"), "hardness_n` must be >= 0.1"),
        (("youngs_modulus_pa: 20000", "youngs_modulus_pa: 20000\n    rigid: true"), "exactly one"),
        (("rect: [0.0, 0.0, 0.3, 0.4]", "rect: [0.3, 0.0, 0.0, 0.4]"), "x1 > x0"),
        (("name: custom", "name: custom\nwind: 3"), "unknown key"),
        # a bow-tie: two edges cross (a notched, non-convex footprint is fine)
        (("[0.6, 0.4], [0.3, 0.4]]", "[0.3, 0.4], [0.6, 0.4]]"), "simple polygon"),
    ],
)
def test_bad_yaml_is_refused_with_a_clear_message(tmp_path, edit, message) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(GOOD.replace(*edit, 1))
    with pytest.raises(ConfigError, match=message):
        load_scenario(path)


def test_unknown_name_and_broken_yaml(tmp_path) -> None:
    with pytest.raises(ConfigError, match="unknown scenario 'nope'"):
        load_scenario("nope")
    path = tmp_path / "x.yaml"
    path.write_text("name: [unclosed")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_scenario(path)
    path.write_text("name: x\n")
    with pytest.raises(ConfigError, match="missing required key `blocks`"):
        load_scenario(path)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfename: x\n", r"not UTF-8 text \(byte 0\)"),
        (b"name: 2020-02-30\n", "not valid YAML.*day is out of range"),  # PyYAML's timestamps
        (b"name: " + b"[" * 5000 + b"]" * 5000 + b"\n", "YAML nested deeper than 64 levels"),
    ],
)
def test_yaml_that_the_parser_cannot_take_is_a_config_error(
    tmp_path, content: bytes, message: str
) -> None:
    path = tmp_path / "bad.yaml"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=rf"bad\.yaml.*{message}"):
        load_scenario(path)


def test_a_scenario_path_the_system_refuses_is_a_config_error(tmp_path) -> None:
    with pytest.raises(ConfigError, match="cannot read the scenario file: File name too long"):
        load_scenario(str(tmp_path / ("a" * 300 + ".yaml")))


def test_block_and_scenario_refuse_bad_values_directly() -> None:
    with pytest.raises(InvalidArgumentError, match="exactly one"):
        Block(name="a", polygon=rectangle(0, 0, 1, 1))
    a = Block(name="a", polygon=rectangle(0, 0, 0.2, 0.2), hardness_n=60)
    b = Block(name="b", polygon=rectangle(0.1, 0.1, 0.3, 0.3), rigid=True)
    with pytest.raises(InvalidArgumentError, match=r"overlap by 100\.00 cm²"):
        Scenario(name="s", blocks=(a, b))
    touching = Block(name="c", polygon=rectangle(0.2, 0.0, 0.4, 0.2), rigid=True)
    assert len(Scenario(name="s", blocks=(a, touching)).blocks) == 2


def test_convex_overlap_area_reference() -> None:
    assert convex_overlap_area(rectangle(0, 0, 2, 2), rectangle(1, 1, 3, 3)) == pytest.approx(1.0)
    assert convex_overlap_area(rectangle(0, 0, 1, 1), rectangle(1, 0, 2, 1)) == 0.0


def test_random_scenarios_are_seeded_valid_and_tile_the_area() -> None:
    xs, ys = np.linspace(0.002, 0.598, 150), np.linspace(0.002, 0.398, 100)
    counts = set()
    for seed in range(12):
        sc = random_scenario(np.random.default_rng(seed))
        again = random_scenario(np.random.default_rng(seed))
        assert sc.to_dict() == again.to_dict()
        counts.add(len(sc.blocks))
        assert 2 <= len(sc.blocks) <= 4
        assert sum(polygon_area(b.polygon) for b in sc.blocks) == pytest.approx(0.24)
        assert sc.labels(xs, ys).min() >= 0
        foams = [b.hardness for b in sc.blocks if not b.rigid]
        assert all(60 <= h <= 150 for h in foams)
        assert len(np.unique(sc.labels(xs, ys))) == len(sc.blocks)
    assert counts == {2, 3, 4}
    with pytest.raises(InvalidArgumentError, match="`n_regions` must be 2, 3 or 4"):
        random_scenario(np.random.default_rng(0), n_regions=7)
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        random_scenario(0)  # type: ignore[arg-type]


def test_per_block_gives_each_point_its_blocks_value_and_the_table_elsewhere() -> None:
    scenario = load_scenario("heterogeneous-60-150")
    xs, ys = np.linspace(-0.05, 0.65, 15), np.linspace(0.0, 0.4, 5)
    labels = scenario.labels(xs, ys)
    values = [10.0 * (k + 1) for k in range(len(scenario.blocks))]
    got = scenario.per_block(xs, ys, values, table=-1.0)
    np.testing.assert_array_equal(got, np.where(labels < 0, -1.0, 10.0 * (labels + 1)))
    assert (labels < 0).any() and (labels >= 0).any()
    with pytest.raises(InvalidArgumentError, match="one value per block"):
        scenario.per_block(xs, ys, values[:1])
