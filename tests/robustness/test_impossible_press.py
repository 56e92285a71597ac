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
