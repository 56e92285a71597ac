from __future__ import annotations

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.errors import InvalidArgumentError


def test_points_are_float64_and_read_only() -> None:
    cloud = PointCloud(np.arange(12, dtype=np.int32).reshape(4, 3))
    assert cloud.points.dtype == np.float64
    assert len(cloud) == 4
    with pytest.raises(ValueError):
        cloud.points[0, 0] = 1.0


@pytest.mark.parametrize(
    ("points", "message"),
    [
        (np.zeros((4, 2)), r"`points` must be a \(n, 3\) array .* got shape \(4, 2\)"),
        (np.array([[0.0, np.nan, 0.0]]), "1 NaN or infinite"),
        ("abc", "got 'abc'"),
        (np.array([["a", "b", "c"]]), "got dtype <U1"),
    ],
)
def test_bad_points_name_the_argument(points: object, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        PointCloud(points)  # type: ignore[arg-type]


def test_integer_colours_are_scaled_and_checked() -> None:
    cloud = PointCloud(np.zeros((2, 3)), colors=np.array([[255, 0, 0], [0, 0, 255]]))
    assert cloud.colors is not None and cloud.colors.max() == 1.0
    with pytest.raises(InvalidArgumentError, match=r"`colors` must be a \(2, 3\)"):
        PointCloud(np.zeros((2, 3)), colors=np.zeros((3, 3)))
    with pytest.raises(InvalidArgumentError, match=r"\[0, 255\]"):
        PointCloud(np.zeros((1, 3)), colors=np.array([[300, 0, 0]]))


def test_select_transform_and_concatenate() -> None:
    rng = np.random.default_rng(0)
    cloud = PointCloud(rng.normal(size=(10, 3)), colors=rng.uniform(size=(10, 3)))
    sub = cloud.select(cloud.z > 0)
    assert len(sub) == int(np.sum(cloud.z > 0))
    shift = np.eye(4)
    shift[:3, 3] = [1.0, 2.0, 3.0]
    moved = cloud.transformed(shift, frame="table")
    np.testing.assert_allclose(moved.points - cloud.points, np.tile([1.0, 2.0, 3.0], (10, 1)))
    both = PointCloud.concatenate([cloud, cloud])
    assert len(both) == 20 and both.colors is not None
    with pytest.raises(InvalidArgumentError, match="share one frame"):
        PointCloud.concatenate([cloud, moved])
    with pytest.raises(InvalidArgumentError, match=r"`mask` must be a \(10,\) boolean"):
        cloud.select(np.ones(3, dtype=bool))
