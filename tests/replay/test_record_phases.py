"""What a press records besides its ramp: the cloud after release (refused with the tip in view)
and the record's time, hold and unloading carried through sessions and bags."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import (
    TIP_IN_VIEW_RADII,
    ForceTravel,
    PressObservation,
    TactileContact,
)
from deformap.errors import InvalidArgumentError

TIP = np.array([0.3, 0.2, 0.056])
RADIUS = 0.01


def _surface(dent_m: float, n: int = 400, seed: int = 0) -> PointCloud:
    """A flat top at 5 cm with a Gaussian dent of ``dent_m`` under the tip."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform([0.25, 0.15], [0.35, 0.25], (n, 2))
    z = 0.05 - dent_m * np.exp(-np.sum((xy - TIP[:2]) ** 2, axis=1) / 0.01**2)
    return PointCloud(np.column_stack([xy, z + rng.normal(0, 2e-4, n)]))


def _tip_cap(n: int = 50) -> np.ndarray:
    """Points on the upper half of the tip, as a camera above sees it."""
    rng = np.random.default_rng(1)
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.2
    return TIP + RADIUS * d / np.linalg.norm(d, axis=1, keepdims=True)


def _press(released: object = None, record: ForceTravel | None = None) -> PressObservation:
    contact = TactileContact(tip_center=TIP, force=[0, 0, -0.6], tip_radius_m=RADIUS)
    robot = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    return PressObservation(cloud=_surface(0.004), contact=contact, robot_points=robot,
                            target_xy=TIP[:2], force_n=0.6, force_travel=record,
                            released=released)  # type: ignore[arg-type]


def test_a_release_observation_without_the_tip_is_kept() -> None:
    released = _surface(0.001)
    assert _press(released).released is released
    assert _press().released is None


def test_a_release_observation_with_the_tip_in_view_is_refused() -> None:
    cloud = PointCloud(np.vstack([_surface(0.001).points, _tip_cap()]))
    with pytest.raises(InvalidArgumentError, match="`released` must be seen once the tip has left"):
        _press(cloud)
    # one point on the tip's top is enough; one just outside the stated radius is not the tip
    top = TIP + np.array([0.0, 0.0, RADIUS])
    with pytest.raises(InvalidArgumentError, match=r"`released`.*1 of its points"):
        _press(PointCloud(np.vstack([_surface(0.001).points, top])))
    outside = TIP + np.array([0.0, 0.0, 1.05 * TIP_IN_VIEW_RADII * RADIUS])
    _press(PointCloud(np.vstack([_surface(0.001).points, outside])))


def test_a_release_observation_that_is_not_a_cloud_is_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="`released` must be a PointCloud"):
        _press(_surface(0.001).points)
