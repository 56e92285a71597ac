"""Appearance families of random worlds: each family's defining property, and no change to the
layout, the materials or the caller's generator."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.world import APPEARANCE_FAMILIES, LAYOUT_FAMILIES, Scenario, random_scenario
from deformap.world._appearance import Appearance

CASES = [(layout, seed) for layout in LAYOUT_FAMILIES for seed in range(4)]


def _material(block_name: str) -> str:
    return block_name.split("-", 2)[2]  # "region-3-101.5N" -> "101.5N"; "rigid"


def _looks_by_material(scenario: Scenario) -> dict[str, set[Appearance | None]]:
    out: dict[str, set[Appearance | None]] = {}
    for block in scenario.blocks:
        out.setdefault(_material(block.name), set()).add(block.appearance)
    return out


@pytest.mark.parametrize("family", APPEARANCE_FAMILIES)
def test_a_family_changes_no_layout_material_or_later_draw(family: str) -> None:
    for layout, seed in CASES:
        rng_plain, rng = np.random.default_rng(seed), np.random.default_rng(seed)
        plain = random_scenario(rng_plain, family=layout)
        painted = random_scenario(rng, family=layout, appearance=family)
        assert [b.name for b in painted.blocks] == [b.name for b in plain.blocks]
        for a, b in zip(plain.blocks, painted.blocks, strict=True):
            np.testing.assert_array_equal(a.polygon, b.polygon)
        assert rng.uniform() == rng_plain.uniform()


def test_plain_is_one_look_everywhere() -> None:
    for layout, seed in CASES:
        scenario = random_scenario(np.random.default_rng(seed), family=layout)
        assert {b.appearance for b in scenario.blocks} == {None}


def test_informative_gives_each_material_its_own_look() -> None:
    for layout, seed in CASES:
        looks = _looks_by_material(random_scenario(np.random.default_rng(seed), family=layout,
                                                   appearance="informative"))
        assert all(len(v) == 1 for v in looks.values())
        colours = [next(iter(v)).color for v in looks.values()]  # type: ignore[union-attr]
        assert len(set(colours)) == len(colours)


def test_textured_materials_differ_by_texture_not_colour() -> None:
    for layout, seed in CASES:
        looks = _looks_by_material(random_scenario(np.random.default_rng(seed), family=layout,
                                                   appearance="textured"))
        one = [next(iter(v)) for v in looks.values()]
        assert all(len(v) == 1 for v in looks.values())
        kinds = {(a.texture, a.photo if a.texture == "photo" else a.scale_m)  # type: ignore[union-attr]
                 for a in one}
        assert len(kinds) == len(one)
        colours = np.array([a.color for a in one])  # type: ignore[union-attr]
        assert np.ptp(colours, axis=0).max() <= 0.06 + 1e-12


def test_shared_gives_two_materials_one_look() -> None:
    for layout, seed in CASES:
        looks = _looks_by_material(random_scenario(np.random.default_rng(seed), family=layout,
                                                   appearance="shared"))
        assert all(len(v) == 1 for v in looks.values())
        distinct = {next(iter(v)) for v in looks.values()}
        assert len(distinct) == len(looks) - 1


def test_split_paints_one_material_in_two_looks() -> None:
    for layout, seed in CASES:
        scenario = random_scenario(np.random.default_rng(seed), family=layout, appearance="split")
        split = [b for b in scenario.blocks if b.appearance and b.appearance.split]
        assert len(split) == 1
        block = split[0]
        look = block.appearance
        assert look is not None and look.split is not None
        assert block.contains(np.array([look.split.through]))[0]  # the line crosses the block
        others = {b.appearance for b in scenario.blocks if b is not block}
        painted = look.split.look
        assert painted.color != look.color
        assert all(o is None or painted.color != o.color for o in others)


def test_misleading_looks_ignore_the_materials() -> None:
    for layout, seed in CASES:
        scenario = random_scenario(np.random.default_rng(seed), family=layout,
                                   appearance="misleading")
        looks = {b.appearance for b in scenario.blocks}
        assert len(looks) == 1
        (look,) = looks
        assert look is not None and look.split is not None
        assert look.split.look.color != look.color


def test_an_unknown_family_is_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="`appearance` must be one of"):
        random_scenario(np.random.default_rng(0), appearance="pretty")
