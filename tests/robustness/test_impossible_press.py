"""A press whose measured contact force could not come from that press (pointing away from the
surface, or far from the commanded force) is refused where every environment's presses pass:
``PressObservation``; in a recorded session it breaks only that poke, and the report says so."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import PressObservation
from deformap.errors import InvalidArgumentError
from deformap.mechanics import TactileContact

ROBOT = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])


def _press(force: list[float], force_n: float = 0.6) -> PressObservation:
    contact = TactileContact(tip_center=[0.3, 0.2, 0.056], force=force, tip_radius_m=0.01)
    return PressObservation(cloud=PointCloud(np.zeros((3, 3))), contact=contact,
                            robot_points=ROBOT, target_xy=[0.3, 0.2], force_n=force_n)


@pytest.mark.parametrize(("force", "message"), [
    ([0.0, 0.0, 0.6], r"`contact.force` must push into the surface .*got \(0.0, 0.0, 0.6\)"),
    ([0.6, 0.0, 0.0], r"`contact.force` must push into the surface"),
    ([0.0, 0.0, -1e6], r"near the commanded force 0.6 N \(within 0.2 N\); its magnitude is 1e\+06"),
    ([0.0, 0.0, -0.0006], r"near the commanded force .*its magnitude is 0.0006 N"),  # mN as N
])
def test_an_impossible_contact_force_is_refused(force: list[float], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        _press(force)


def test_a_press_with_sensor_noise_and_a_tilt_is_accepted() -> None:
    tilted = 0.6 * np.array([np.sin(0.5), 0.0, -np.cos(0.5)])  # 29° off the vertical
    assert _press(list(tilted)).contact.force_n == pytest.approx(0.6)
    assert _press([0.01, -0.02, -0.74]).force_n == 0.6  # 23 % over: a controller's overshoot


def test_the_world_refuses_a_press_that_would_crush_the_foam_onto_the_table() -> None:
    from deformap.testing import coarse_world

    world = coarse_world("heterogeneous-60-150")
    with pytest.raises(InvalidArgumentError,
                       match=r"`force_n` of 100000 N would sink the tip .* m into 'foam-60', "
                             r"which is 0.05 m thick"):
        world.press([0.15, 0.2], 1e5)
    assert not world.is_pressing
    assert world.press([0.15, 0.2], 0.6).contact.tip_center[2] > 0.03  # a press it can take


@pytest.mark.parametrize(("field", "value", "message"), [
    ("hardness_n", 1e-9, r"`hardness_n` must be >= 0.1; got 1e-09 \(block 'x'\)"),
    ("hardness_n", 1e9, r"`hardness_n` must be <= 1.3e\+08"),
    ("youngs_modulus_pa", 1.0, r"`youngs_modulus_pa` must be >= 10"),
    ("youngs_modulus_pa", 1e12, r"`youngs_modulus_pa` must be <= 1e\+10"),
])
def test_a_scenario_material_no_world_can_press_is_refused(field: str, value: float,
                                                           message: str) -> None:
    from deformap.errors import DeformapError
    from deformap.world import Block

    square = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]])
    with pytest.raises(DeformapError, match=message):
        Block(name="x", polygon=square, **{field: value})
