"""The probe's protocol in the world's config: sample times, a force hold and an unloading branch."""

from __future__ import annotations

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.world import SimulatedWorld, WorldConfig, load_scenario

XY, FORCE = (0.3, 0.2), 2.0


def _record(**protocol: object):  # type: ignore[no-untyped-def]
    world = SimulatedWorld(load_scenario("homogeneous-60"),
                           config=WorldConfig.coarse(**protocol), rng=np.random.default_rng(3))
    record = world.press(XY, FORCE).force_travel
    world.release()
    assert record is not None
    return record


def test_default_protocol_records_the_ramp_alone_and_the_phases_leave_it_unchanged() -> None:
    plain = _record()
    assert plain.time_s is None and plain.hold is None and plain.unloading is None
    np.testing.assert_array_equal(_record(hold_s=4.0, unload=True).travel_m, plain.travel_m)
    full = _record(hold_s=4.0, unload=True, ramp_rate_n_per_s=4.0)
    # load-controlled at 4 N/s: the ramp takes (F − F_contact) / rate, read at 100 Hz
    rate = WorldConfig().sample_rate_hz
    assert len(full) == round((FORCE - 0.02) / 4.0 * rate) + 1
    assert len(plain) == round((FORCE - 0.02) / 2.0 * rate) + 1
    assert full.time_s is not None and full.hold is not None and full.unloading is not None
    assert full.time_s[-1] == pytest.approx((FORCE - 0.02) / 4.0)
    assert full.hold.time_s[-1] == pytest.approx(full.time_s[-1] + 4.0)
    assert full.unloading.time_s[-1] == pytest.approx(full.hold.time_s[-1] + (FORCE - 0.02) / 4.0)


def test_elastic_block_holds_flat_and_unloads_along_the_ramp() -> None:
    exact = _record(hold_s=2.0, unload=True, noise=False)
    assert exact.hold is not None and exact.unloading is not None and exact.time_s is not None
    # the sensors read the hold and the unloading at the default 100 Hz
    rate = WorldConfig().sample_rate_hz
    assert len(exact.hold) == round(2.0 * rate) and len(exact.unloading) == round(
        (FORCE - 0.02) / 2.0 * rate)
    np.testing.assert_allclose(np.diff(exact.hold.time_s), 1.0 / rate)
    np.testing.assert_allclose(np.diff(exact.unloading.time_s), 1.0 / rate)
    np.testing.assert_array_equal(exact.hold.travel_m, exact.travel_m[-1])
    np.testing.assert_array_equal(exact.hold.force_n, FORCE)
    # the force falls at the ramp's rate down to contact; where it passes a ramp level the
    # travel lies between the ramp's at the levels on either side (an elastic block retraces
    # its loading) and is the ramp's first at contact
    np.testing.assert_allclose(exact.unloading.force_n,
                               FORCE - 2.0 * (exact.unloading.time_s - exact.hold.time_s[-1]))
    assert exact.unloading.force_n[-1] == pytest.approx(0.02)
    above = np.searchsorted(exact.force_n, exact.unloading.force_n - 1e-12)
    assert np.all(exact.unloading.travel_m <= exact.travel_m[above] + 1e-12)
    assert np.all(exact.unloading.travel_m >= exact.travel_m[np.maximum(above - 1, 0)] - 1e-12)
    assert exact.unloading.travel_m[-1] == pytest.approx(exact.travel_m[0], abs=1e-12)
    assert np.all(np.diff(exact.unloading.travel_m) <= 0.0)
    only_hold = _record(hold_s=2.0, noise=False)
    assert only_hold.hold is not None and only_hold.unloading is None


@pytest.mark.parametrize(("field", "value"), [("hold_s", -1.0), ("ramp_rate_n_per_s", 0.0),
                                              ("hold_s", float("nan")), ("sample_rate_hz", 0.0),
                                              ("sample_rate_hz", float("inf"))])
def test_bad_protocol_names_the_setting(field: str, value: float) -> None:
    with pytest.raises(SettingError, match=field):
        WorldConfig(**{field: value})


def test_the_sensors_read_a_viscoelastic_hold_between_the_solved_steps() -> None:
    """At the sensors' rate the hold creeps sample by sample; where a sample falls on a solved
    time it is the solved indentation (a world read at the solved schedule's rate)."""
    from deformap.environment import Workspace
    from deformap.world import Block, Scenario, Viscoelastic

    block = Block(name="memory", polygon=np.array([[0, 0], [0.3, 0], [0.3, 0.3], [0, 0.3]]),
                  hardness_n=60.0, viscoelastic=Viscoelastic(relaxed_ratio=0.5, times_s=(1.0,)))
    scenario = Scenario(name="m", blocks=(block,),
                        workspace=Workspace(lower=(0.0, 0.0), upper=(0.3, 0.3)))

    def record(rate: float):  # type: ignore[no-untyped-def]
        config = WorldConfig.coarse(noise=False, hold_s=2.0, unload=True, sample_rate_hz=rate)
        got = SimulatedWorld(scenario, config=config, rng=np.random.default_rng(0)).press(
            (0.15, 0.15), FORCE).force_travel
        assert got is not None and got.hold is not None and got.unloading is not None
        return got

    dense, solved = record(100.0), record(4.0)  # 4 Hz over 2 s: the solved 8 hold samples
    assert len(dense.hold) == 200 and len(solved.hold) == 8 and len(solved.unloading) == 8
    assert len(solved) == 9 and len(dense) == 100  # the 0.99 s ramp: its levels; at 100 Hz
    # the ramp read between its solved steps: it starts and ends on them, never falls, and
    # each sample lies between the solved samples on either side of its force
    assert dense.travel_m[-1] == pytest.approx(solved.travel_m[-1], abs=1e-12)
    assert np.all(np.diff(dense.travel_m) > 0.0)
    above = np.searchsorted(solved.force_n, dense.force_n - 1e-12)
    assert np.all(dense.travel_m <= solved.travel_m[above] + 1e-12)
    assert np.all(dense.travel_m >= solved.travel_m[np.maximum(above - 1, 0)] - 1e-12)
    at = np.searchsorted(dense.hold.time_s, solved.hold.time_s - 1e-9)
    np.testing.assert_allclose(dense.hold.time_s[at], solved.hold.time_s, atol=1e-12)
    np.testing.assert_allclose(dense.hold.travel_m[at], solved.hold.travel_m, atol=1e-12)
    assert np.all(np.diff(dense.hold.travel_m) > 0.0)  # it creeps between the solved samples
    assert dense.unloading.travel_m[-1] == pytest.approx(solved.unloading.travel_m[-1], abs=1e-12)
