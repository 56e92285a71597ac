"""A raw robot bag of presses that hold and unload: the reader gives each press's hold and
unloading branch back, and what they reveal is what the live press revealed.

The world presses a viscoelastic foam and an elastic one with a 2 s hold and an unloading branch;
the raw writer replays each record's hold and unloading on the bag's clock (500 Hz force sensor,
50 Hz ``/tf``); ``load_raw_bag`` with no settings finds the presses and their phases.
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from deformap.explore import poke_behaviour
from deformap.replay import RigConfig, load_raw_bag, write_raw_mcap
from deformap.world import SimulatedWorld, WorldConfig, load_scenario

pytest.importorskip("rosbags")

FORCE, HOLD_S = 0.6, 2.0
SCENARIO = {"name": "two-foams", "workspace": {"lower": [0, 0], "upper": [0.4, 0.3]}, "blocks": [
    {"name": "memory", "rect": [0, 0, 0.2, 0.3], "hardness_n": 60,
     "viscoelastic": {"relaxed_ratio": 0.5, "times_s": [0.5], "weights": [1.0]}},
    {"name": "plain", "rect": [0.2, 0, 0.4, 0.3], "hardness_n": 60}]}
TARGETS = ((0.1, 0.15), (0.3, 0.15))


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    root = tmp_path_factory.mktemp("rawphases")
    (root / "two-foams.yaml").write_text(yaml.safe_dump(SCENARIO))
    world = SimulatedWorld(load_scenario(root / "two-foams.yaml"),
                           config=WorldConfig.coarse(hold_s=HOLD_S, unload=True),
                           rng=np.random.default_rng(0))  # fmt: skip
    observation = world.observe()
    presses = []
    for xy in TARGETS:
        presses.append(world.press(np.array(xy), FORCE))
        world.release()
    path = root / "robot.mcap"
    write_raw_mcap(path, observation, presses, RigConfig(colors=False), seed=0)
    return presses, load_raw_bag(path, default_force_n=FORCE)


def test_each_raw_press_has_the_hold_and_the_unloading_it_recorded(recorded) -> None:  # type: ignore[no-untyped-def]
    live, session = recorded
    assert len(session) == len(live)
    for i, press in enumerate(live):
        raw, truth = session.press_observation(i).force_travel, press.force_travel
        assert raw is not None and raw.hold is not None and raw.unloading is not None
        # the hold lasts the world's, on the bag's clock
        held = raw.hold.time_s[-1] - raw.time_s[-1]
        assert held == pytest.approx(truth.hold.time_s[-1] - truth.time_s[-1], rel=0.05)
        # the unloading falls from the force held to under a quarter of it, and where it ends
        # the tip has come back from the ramp's end as far as the live record says at that force
        # (within 0.3 mm; first contact, where travel counts from, is found on the noisy force)
        down = raw.unloading
        assert down.force_n[0] > 0.75 * FORCE and down.force_n[-1] < 0.25 * FORCE
        order = np.argsort(truth.unloading.force_n)
        expected = np.interp(down.force_n[-1], truth.unloading.force_n[order],
                             truth.unloading.travel_m[order]) - truth.travel_m[-1]  # fmt: skip
        assert down.travel_m[-1] - raw.travel_m[-1] == pytest.approx(expected, abs=3e-4)


def test_the_raw_hold_reads_the_creep_the_live_one_reads(recorded) -> None:  # type: ignore[no-untyped-def]
    live, session = recorded
    raw_visco = poke_behaviour(session.press_observation(0))
    live_visco = poke_behaviour(live[0])
    assert live_visco.behaviour == raw_visco.behaviour == "viscoelastic", raw_visco.evidence
    # the bag's hold starts at the ramp's end, the world's first hold sample 0.25 s later: the
    # bag sees more of the creep, never more than the foam's whole (1 − relaxed ratio)
    assert live_visco.relaxation - 0.02 <= raw_visco.relaxation <= 0.5
    # the elastic foam does not relax in the hold, read from the bag as live
    raw_plain = poke_behaviour(session.press_observation(1))
    assert raw_plain.behaviour != "viscoelastic" and raw_plain.relaxation is not None
    assert abs(raw_plain.relaxation) < 0.05, raw_plain.evidence
