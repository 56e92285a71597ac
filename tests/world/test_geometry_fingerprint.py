"""Appearance leaves geometry alone: the points, the press and its force–travel record of a small
seeded world are byte for byte those of the world before it rendered colour (commit 03972c1; the
record's since the sensors read the ramp at their rate, branch h-ramp)."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from deformap.world import CameraConfig, SimulatedWorld, WorldConfig, load_scenario, random_scenario

# sha256 (first 16 hex digits) of the float64 bytes, computed with the code at commit 03972c1
# (the record's, with the code that reads the ramp at the sensors' rate)
_OBSERVE = "c2b9e85d51093383"
_PRESS_CLOUD = "9dd202ee92a403db"
_CONTACT = "fc4d81500bdcc497"
_FORCE_TRAVEL = "d5f85eb3b8b213b6"  # the ramp read at the sensors' rate (100 Hz)
_OBSERVE_PRESSED = "8650a342df53a090"
_RANDOM_POLYGONS = "51d861bba4a897e1"


def _hash(*arrays: object) -> str:
    digest = hashlib.sha256()
    for a in arrays:
        digest.update(np.ascontiguousarray(np.asarray(a, dtype=np.float64)).tobytes())
    return digest.hexdigest()[:16]


@pytest.mark.parametrize("use_embree", [False, True])
def test_points_press_and_record_are_unchanged(use_embree: bool) -> None:
    config = WorldConfig.coarse(camera=CameraConfig(width=64, height=48, use_embree=use_embree))
    world = SimulatedWorld(load_scenario("heterogeneous-60-150"), config=config,
                           rng=np.random.default_rng(0))
    cloud = world.observe()
    press = world.press((0.15, 0.2), 0.6)
    assert press.force_travel is not None
    assert cloud.points.shape == (1668, 3)
    assert _hash(cloud.points) == _OBSERVE
    assert _hash(press.cloud.points) == _PRESS_CLOUD
    assert _hash(press.contact.force, press.contact.tip_center) == _CONTACT
    assert _hash(press.force_travel.travel_m, press.force_travel.force_n) == _FORCE_TRAVEL
    assert _hash(world.observe().points) == _OBSERVE_PRESSED


def test_random_layout_and_stream_are_unchanged() -> None:
    rng = np.random.default_rng(5)
    scenario = random_scenario(rng, family="cuts")
    assert _hash(*[b.polygon for b in scenario.blocks]) == _RANDOM_POLYGONS
    assert [b.name for b in scenario.blocks] == [
        "region-0-121.6N", "region-1-62.1N", "region-2-143.4N", "region-3-101.5N"]
    assert rng.uniform() == pytest.approx(0.4467110728501832, abs=0)
