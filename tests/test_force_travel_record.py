"""The press's force–travel record: what it accepts, and every refusal naming its field."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import (
    FORCE_MISMATCH_ABS_N,
    FORCE_MISMATCH_REL,
    MAX_TRAVEL_M,
    MIN_FORCE_RISE_N,
    TRAVEL_BACKWARDS_TOLERANCE_M,
    ForceTravel,
    PressObservation,
    PressPhase,
    TactileContact,
)
from deformap.errors import InvalidArgumentError

TRAVEL = np.linspace(0.0, 0.004, 9)  # a 4 mm dent
FORCE = np.linspace(0.05, 0.6, 9)


def _press(record: ForceTravel | None, force_n: float = 0.6) -> PressObservation:
    contact = TactileContact(tip_center=[0.3, 0.2, 0.056], force=[0, 0, -force_n],
                             tip_radius_m=0.01)
    robot = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    return PressObservation(cloud=PointCloud(np.zeros((3, 3))), contact=contact,
                            robot_points=robot, target_xy=[0.3, 0.2], force_n=force_n,
                            force_travel=record)


def test_a_good_record_is_kept_as_read_only_float_copies() -> None:
    travel, force = TRAVEL.copy(), [float(f) for f in FORCE]
    record = ForceTravel(travel_m=travel, force_n=force)
    assert len(record) == 9
    assert record.travel_m.dtype == np.float64 and not record.travel_m.flags.writeable
    assert not record.force_n.flags.writeable
    travel[0] = 1.0  # the caller's array stays the caller's
    assert record.travel_m[0] == 0.0
    assert travel.flags.writeable
    assert record == ForceTravel(travel_m=TRAVEL, force_n=FORCE)
    assert record != ForceTravel(travel_m=TRAVEL * 0.5, force_n=FORCE)


def test_a_rigid_press_within_encoder_noise_is_accepted() -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):  # 0.05 mm encoder noise around zero, 1000 samples
        travel = rng.normal(0.0, 5e-5, size=1000)
        ForceTravel(travel_m=travel, force_n=np.linspace(0.02, 0.6, 1000))


@pytest.mark.parametrize("field", ["travel_m", "force_n"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_values_are_refused(field: str, bad: float) -> None:
    values = {"travel_m": TRAVEL.copy(), "force_n": FORCE.copy()}
    values[field][4] = bad
    with pytest.raises(InvalidArgumentError, match=f"`{field}`.*NaN or infinite"):
        ForceTravel(**values)


@pytest.mark.parametrize("field", ["travel_m", "force_n"])
def test_fewer_than_three_samples_are_refused(field: str) -> None:
    values = {"travel_m": TRAVEL, "force_n": FORCE}
    values[field] = values[field][:2]
    with pytest.raises(InvalidArgumentError, match=f"`{field}` must have at least 3 rows"):
        ForceTravel(**values)


def test_shapes_that_differ_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="`force_n` must have one sample per"):
        ForceTravel(travel_m=TRAVEL, force_n=FORCE[:-1])
    with pytest.raises(InvalidArgumentError, match="`travel_m` must be a \\(n,\\) array"):
        ForceTravel(travel_m=TRAVEL.reshape(3, 3), force_n=FORCE)


def test_travel_going_backwards_beyond_encoder_noise_is_refused() -> None:
    travel = TRAVEL.copy()
    travel[5] = travel[4] - 0.9 * TRAVEL_BACKWARDS_TOLERANCE_M  # within noise: kept
    ForceTravel(travel_m=travel, force_n=FORCE)
    travel[5] = travel[4] - 1.1 * TRAVEL_BACKWARDS_TOLERANCE_M
    with pytest.raises(InvalidArgumentError, match=r"`travel_m` must not go backwards.*sample 5"):
        ForceTravel(travel_m=travel, force_n=FORCE)
    release = np.r_[0.0, np.linspace(0.004, 0.0005, 8)]  # pressed, then let go: not a press
    with pytest.raises(InvalidArgumentError, match="`travel_m` must not go backwards"):
        ForceTravel(travel_m=release, force_n=FORCE)


def test_force_not_rising_is_refused() -> None:
    for force in (FORCE[::-1], np.full(9, 0.6), 0.6 + np.linspace(0, 0.9 * MIN_FORCE_RISE_N, 9)):
        with pytest.raises(InvalidArgumentError, match="`force_n` must rise"):
            ForceTravel(travel_m=TRAVEL, force_n=force)
    with pytest.raises(InvalidArgumentError, match="`force_n` must be the force pressing"):
        ForceTravel(travel_m=TRAVEL, force_n=np.linspace(-0.6, -0.05, 9))  # sign flipped


def test_travel_in_millimetres_is_refused() -> None:
    ForceTravel(travel_m=TRAVEL * (MAX_TRAVEL_M / TRAVEL[-1]), force_n=FORCE)  # the limit itself
    with pytest.raises(InvalidArgumentError, match=r"`travel_m` must be metres.*millimetres"):
        ForceTravel(travel_m=TRAVEL * 1000.0, force_n=FORCE)


def test_press_observation_carries_the_record_or_none() -> None:
    assert _press(None).force_travel is None
    record = ForceTravel(travel_m=TRAVEL, force_n=FORCE)
    assert _press(record).force_travel is record
    with pytest.raises(InvalidArgumentError, match="`force_travel` must be a ForceTravel"):
        _press((TRAVEL, FORCE))  # type: ignore[arg-type]


def test_press_observation_refuses_a_record_far_from_the_commanded_force() -> None:
    allowed = FORCE_MISMATCH_REL * 0.6 + FORCE_MISMATCH_ABS_N
    for final, ok in ((0.6 + 0.9 * allowed, True), (0.6 - 0.9 * allowed, True),
                      (0.6 + 1.1 * allowed, False), (0.6 - 1.1 * allowed, False)):
        record = ForceTravel(travel_m=TRAVEL, force_n=np.linspace(0.02, final, 9))
        if ok:
            _press(record)
        else:
            with pytest.raises(InvalidArgumentError, match="`force_travel` must end at the "
                                                           "commanded force"):
                _press(record)
    grams = ForceTravel(travel_m=TRAVEL, force_n=FORCE * 1000 / 9.81)  # grams-force
    with pytest.raises(InvalidArgumentError, match="`force_travel`"):
        _press(grams)


def test_a_travel_that_does_not_start_at_contact_is_refused() -> None:
    # an absolute tip position passed for the travel since contact
    ForceTravel(travel_m=TRAVEL + 0.9 * TRAVEL_BACKWARDS_TOLERANCE_M, force_n=FORCE)  # noise
    with pytest.raises(InvalidArgumentError, match=r"`travel_m` must be the travel since first"):
        ForceTravel(travel_m=TRAVEL + 0.005, force_n=FORCE)


def test_a_force_that_was_not_zeroed_or_points_away_is_refused() -> None:
    ForceTravel(travel_m=TRAVEL, force_n=FORCE - 0.05 - 0.9 * MIN_FORCE_RISE_N)  # noise at 0
    with pytest.raises(InvalidArgumentError, match=r"`force_n` must be the force pressing"):
        ForceTravel(travel_m=TRAVEL, force_n=FORCE - 0.5)


# the hold and the unloading branch: time on the ramp's clock, each stretch after the one before
RAMP_T = np.linspace(0.0, 0.8, 9)
HOLD = dict(time_s=[0.9, 1.4, 1.9], travel_m=[0.0041, 0.0043, 0.0044], force_n=[0.6, 0.6, 0.6])
UNLOAD = dict(time_s=[2.0, 2.1, 2.2], travel_m=[0.004, 0.002, 0.0005], force_n=[0.5, 0.2, 0.0])


def _full(**change: object) -> ForceTravel:
    fields: dict[str, object] = dict(travel_m=TRAVEL, force_n=FORCE, time_s=RAMP_T,
                                     hold=PressPhase(**HOLD), unloading=PressPhase(**UNLOAD))
    fields.update(change)
    return ForceTravel(**fields)  # type: ignore[arg-type]


def test_a_record_with_hold_and_unloading_is_kept_and_compared_whole() -> None:
    record = _full()
    assert record.hold is not None and len(record.hold) == 3
    assert record.unloading is not None and not record.unloading.force_n.flags.writeable
    assert record == _full()
    assert record != _full(unloading=None)
    assert record != ForceTravel(travel_m=TRAVEL, force_n=FORCE)


@pytest.mark.parametrize(("change", "field"), [
    (dict(time_s=RAMP_T[::-1]), "`time_s` must increase"),
    (dict(time_s=RAMP_T[:5]), "`time_s`"),
    (dict(hold=PressPhase(**{**HOLD, "time_s": [0.5, 1.4, 1.9]})), "`hold.time_s` must start"),
    (dict(unloading=PressPhase(**{**UNLOAD, "time_s": [1.5, 1.6, 1.7]})),
     "`unloading.time_s` must start"),
    (dict(unloading=PressPhase(**{**UNLOAD, "force_n": [0.2, 0.5, 0.0]})),
     "`unloading.force_n` must fall"),
    (dict(time_s=None), "`time_s` must be given"),
])
def test_a_record_whose_time_or_unloading_is_impossible_is_refused(change: dict[str, object],
                                                                   field: str) -> None:
    with pytest.raises(InvalidArgumentError, match=field.replace("(", r"\(")):
        _full(**change)


@pytest.mark.parametrize(("change", "field"), [
    (dict(time_s=[0.9]), "`travel_m` must have the shape|`time_s`"),
    (dict(time_s=[], travel_m=[], force_n=[]), "`travel_m` must have at least 2 rows"),
    (dict(force_n=[0.6, float("nan"), 0.6]), "`force_n`.*NaN"),
    (dict(time_s=[0.9, float("inf"), 1.9]), "`time_s`.*NaN or infinite"),
    (dict(travel_m=[0.0041, 0.0043, 4.4]), "`travel_m` must be metres"),
    (dict(force_n=[0.6, -0.5, 0.6]), "`force_n` must be the force pressing"),
])
def test_a_stretch_with_no_samples_or_bad_values_is_refused(change: dict[str, object],
                                                            field: str) -> None:
    with pytest.raises(InvalidArgumentError, match=field):
        PressPhase(**{**HOLD, **change})  # type: ignore[arg-type]
