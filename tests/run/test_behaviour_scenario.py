"""examples/behaviour-mix.yaml (an elastic foam, a memory foam and a clay block of one hardness)
explored with the default strategy, each press held 2 s and unloaded
(examples/behaviour-mix-run.yaml): at the stop, the regions' behaviours are the blocks' own."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from deformap.run import explore_scenario, load_run_config
from deformap.world import load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
TRUTH = {"elastic": "elastic", "memory-foam": "viscoelastic", "clay": "plastic"}

pytestmark = pytest.mark.slow  # the default world and strategy: about 40 s


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> dict:
    config = load_run_config(EXAMPLES / "behaviour-mix-run.yaml")
    assert (config.world.hold_s, config.world.unload) == (2.0, True)
    config = dataclasses.replace(config, scenario=str(EXAMPLES / "behaviour-mix.yaml"))
    out = explore_scenario(config, tmp_path_factory.mktemp("mix") / "run")
    return json.loads((out.folder / "report.json").read_text())


def _truth_at(xy: list[float]) -> str:
    scenario = load_scenario(EXAMPLES / "behaviour-mix.yaml")
    label = int(scenario.labels(np.array([xy[0]]), np.array([xy[1]]))[0, 0])
    return TRUTH[scenario.blocks[label].name]


def test_no_press_reads_a_behaviour_its_block_does_not_have(report: dict) -> None:
    read = [(p["contact_xy"], p["behaviour"]["behaviour"]) for p in report["pokes"]]
    known = [(xy, b) for xy, b in read if b != "unknown"]
    assert known  # the presses held and unloaded
    assert all(b == _truth_at(xy) for xy, b in known), known


def test_the_regions_behaviours_are_their_blocks(report: dict) -> None:
    regions = report["regions"]
    pokes = {p["index"]: p for p in report["pokes"]}
    kinds = regions["class_behaviours"]
    assert "mixed" not in kinds
    for k, kind in enumerate(kinds):
        mine = [pokes[i] for i, label in zip(regions["poke_indices"], regions["poke_labels"],
                                             strict=True) if label == k]
        truths = {_truth_at(p["contact_xy"]) for p in mine
                  if p["behaviour"]["behaviour"] != "unknown"}
        # a region's behaviour is that of the blocks its known presses lie on, and only one
        assert truths == ({kind} if kind != "unknown" else set())
    # each block is found with its behaviour (the elastic one too: its hold, read at the sensors'
    # rate, rules creep out)
    assert sorted(kinds) == ["elastic", "plastic", "viscoelastic"]
