"""One convex hull per part of the robot (issue 15, item 2): a narrow stick under a wide hand.

A single hull around both widens from the hand down to the tip and swallows the surface beside
the stick; one hull per part does not. Environments may give either; the sessions keep one hull
per poke (the parts' common one), and the raw-bag reader builds one per part from its model.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from deformap.cloud import PointCloud, points_in_hull
from deformap.environment import PressObservation, TactileContact
from deformap.errors import InvalidArgumentError
from deformap.replay import DEFAULT_HULL, HullPart, load_session, write_session
from deformap.replay._rawconfig import hull_points

TIP = np.array([0.3, 0.2, 0.06])


def at(dx: float, dy: float, dz: float) -> np.ndarray:
    """A point at ``(dx, dy, dz)`` from the tip's centre."""
    return TIP + np.array([dx, dy, dz])


def _box(center: np.ndarray, size: tuple[float, float, float]) -> np.ndarray:
    half = np.asarray(size) / 2
    return np.array([center + half * [x, y, z] for x in (-1, 1) for y in (-1, 1)
                     for z in (-1, 1)])  # fmt: skip


STICK = _box(at(0, 0, 0.05), (0.012, 0.012, 0.10))
HAND = _box(at(0, 0, 0.15), (0.08, 0.06, 0.10))
#: 2 cm beside the stick, 6 cm above the tip: inside the common hull of stick and hand, outside both.
BESIDE = TIP + np.array([0.02, 0.0, 0.06])


def test_one_hull_per_part_keeps_what_lies_between_the_parts() -> None:
    pts = np.vstack([BESIDE, at(0, 0, 0.05), at(0.03, 0.02, 0.15)])
    assert points_in_hull(pts, np.vstack([STICK, HAND])).tolist() == [True, True, True]
    assert points_in_hull(pts, (STICK, HAND)).tolist() == [False, True, True]
    assert points_in_hull(pts, [STICK, HAND]).tolist() == [False, True, True]
    # a list of points (nested lists, one per point) is still one hull
    assert points_in_hull(pts, np.vstack([STICK, HAND]).tolist()).tolist() == [True] * 3


def _press(robot: object) -> PressObservation:
    cloud = PointCloud(np.random.default_rng(0).uniform([0.2, 0.1, 0.04], [0.4, 0.3, 0.05],
                                                        (200, 3)))  # fmt: skip
    contact = TactileContact(tip_center=TIP, force=np.array([0.0, 0.0, -1.0]), tip_radius_m=0.01)
    return PressObservation(cloud=cloud, contact=contact, robot_points=robot,  # type: ignore[arg-type]
                            target_xy=TIP[:2], force_n=1.0)  # fmt: skip


def test_a_press_takes_one_hull_per_part_and_names_a_bad_part() -> None:
    obs = _press((STICK, HAND))
    assert isinstance(obs.robot_points, tuple) and len(obs.robot_hulls) == 2
    np.testing.assert_array_equal(obs.robot_hulls[1], HAND)
    assert not obs.robot_hulls[0].flags.writeable
    single = _press(np.vstack([STICK, HAND]))
    assert len(single.robot_hulls) == 1 and single.robot_hulls[0].shape == (16, 3)
    with pytest.raises(InvalidArgumentError, match=r"`robot_points\[1\]`"):
        _press((STICK, HAND[:3]))


def test_a_session_keeps_the_parts_common_hull_and_says_so(
    tmp_path: object, caplog: pytest.LogCaptureFixture
) -> None:
    from pathlib import Path

    from deformap.environment import Workspace

    obs = _press((STICK, HAND))
    folder = Path(str(tmp_path)) / "session"
    with caplog.at_level(logging.WARNING, logger="deformap.replay._write"):
        write_session(folder, workspace=Workspace(), observation=obs.cloud, presses=[obs])
    assert "one robot hull per part" in caplog.text
    back = load_session(folder).press_observation(0)
    np.testing.assert_allclose(back.robot_points, np.vstack([STICK, HAND]))


def test_the_default_probe_model_covers_stick_and_hand_but_not_the_dent() -> None:
    up_yaw = np.eye(3)
    hulls = tuple(hull_points(part, up_yaw, TIP) for part in DEFAULT_HULL)
    probe = np.vstack([at(0, 0, 0.009),       # the tip's upper half
                       at(0.004, 0, 0.08),    # on the stick
                       at(0.03, 0.02, 0.15)])  # in the hand  # fmt: skip
    surface = np.vstack([TIP - [0, 0, 0.011],     # under the tip: the dent
                         BESIDE,                   # beside the stick
                         at(0.015, 0, -0.002)])  # the dent's rim  # fmt: skip
    assert points_in_hull(probe, hulls).all()
    assert not points_in_hull(surface, hulls).any()


def test_a_tilted_tip_carries_its_parts_with_it() -> None:
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_euler("y", 90, degrees=True).as_matrix()  # the stick along world +x
    stick = hull_points(HullPart(shape="cylinder", center_m=(0, 0, 0.05),
                                 size_m=(0.012, 0.012, 0.1)), rot, TIP)  # fmt: skip
    assert points_in_hull(TIP + np.array([[0.08, 0, 0], [0, 0, 0.08]]), stick).tolist() == [True, False]
