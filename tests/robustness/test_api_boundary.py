"""The Python API's boundary: what no caller may pass is refused with one line naming the
argument (never an AttributeError, an IndexError, a hang or silent NaN from deep inside)."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import MAX_GRID_CELLS, Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig, explore
from deformap.gp import GaussianRandomField


class FlatWorld:
    """The smallest Environment: counts presses (none may happen when arguments are refused)."""

    def __init__(self) -> None:
        self.workspace = Workspace()
        self.presses = 0

    def observe(self) -> PointCloud:
        return PointCloud(np.zeros((1, 3)))

    def press(self, target_xy: object, force_n: float) -> None:
        self.presses += 1

    def release(self) -> None:
        pass


def test_explore_names_each_bad_argument() -> None:
    cfg, rng = ExplorationConfig(), np.random.default_rng(0)
    world = FlatWorld()
    cases = [
        (("x", cfg), {"rng": rng}, r"`env` must be an Environment .*got 'x' \(str\)"),
        ((world, None), {"rng": rng}, r"`config` must be an ExplorationConfig; got None"),
        ((world, cfg), {"rng": None}, r"`rng` must be a numpy.random.Generator; got None"),
        ((world, cfg), {"rng": 3}, r"`rng` must be a numpy.random.Generator; got 3"),
        ((world, cfg), {"rng": rng, "journal": "j"}, r"`journal` must be a Journal or None"),
        ((world, cfg), {"rng": rng, "done": "ab"}, r"`done` must be a sequence of PokeRecord"),
        ((world, cfg), {"rng": rng, "done": [1]}, r"`done` must be a sequence of PokeRecord"),
        ((world, cfg), {"rng": rng, "on_poke": 5}, r"`on_poke` must be callable or None"),
    ]
    for args, kwargs, message in cases:
        with pytest.raises(InvalidArgumentError, match=message):
            explore(*args, **kwargs)  # type: ignore[arg-type]
    assert world.presses == 0  # refused before any work


def test_a_grid_too_fine_is_refused_before_allocating() -> None:
    with pytest.raises(InvalidArgumentError, match=r"`spacing_m` must give at most 25,000,000"):
        Workspace().grid(1e-9)
    xs, ys = Workspace().grid((0.6 * 0.4 / MAX_GRID_CELLS) ** 0.5 * 1.01)  # just inside
    assert xs.size * ys.size <= MAX_GRID_CELLS


def test_point_cloud_select_transform_and_dtype() -> None:
    cloud = PointCloud(np.arange(30, dtype=float).reshape(10, 3))
    with pytest.raises(InvalidArgumentError,
                       match=r"`mask` indices must lie in \[-10, 9\]; got 3 to 20"):
        cloud.select(np.array([3, 20]))
    with pytest.raises(InvalidArgumentError, match=r"`mask` indices must lie"):
        cloud.select(np.array([-11]))
    assert len(cloud.select(np.array([-10, 9]))) == 2
    with pytest.raises(InvalidArgumentError, match=r"`a2b` must be a rigid transform.*det 0"):
        cloud.transformed(np.zeros((4, 4)), "cam")
    shear = np.eye(4)
    shear[0, 1] = 0.5
    with pytest.raises(InvalidArgumentError, match=r"`a2b` must be a rigid transform"):
        cloud.transformed(shear, "cam")
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    with pytest.raises(InvalidArgumentError, match=r"`a2b` must be a rigid transform.*det -1"):
        cloud.transformed(mirror, "cam")
    turn = np.eye(4)
    turn[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    turn[:3, 3] = [1.0, 2.0, 3.0]
    moved = cloud.transformed(turn, "cam")
    np.testing.assert_allclose(moved.points[1], [-4.0 + 1.0, 3.0 + 2.0, 5.0 + 3.0])
    with pytest.raises(InvalidArgumentError, match=r"`points` must be .*got dtype bool"):
        PointCloud(np.ones((5, 3), dtype=bool))


@pytest.mark.parametrize("name", ["length_scale", "signal_std", "noise_std"])
@pytest.mark.parametrize("value", [1e300, 1e-300, 1e13, 1e-13])
def test_gp_hyperparameters_outside_double_precision_range_are_refused(name: str,
                                                                      value: float) -> None:
    params = {"length_scale": 0.1, "signal_std": 1.0, "noise_std": 0.1, name: value}
    with pytest.raises(InvalidArgumentError, match=rf"`{name}` must lie in \[1e-12, 1e\+12\]"):
        GaussianRandomField(**params)


def test_gp_at_the_range_ends_predicts_finite_values() -> None:
    rng = np.random.default_rng(0)
    xy, z = rng.random((20, 2)), rng.random(20)
    for params in ({"length_scale": 1e12, "signal_std": 1e12, "noise_std": 1e-12},
                   {"length_scale": 1e-12, "signal_std": 1e-12, "noise_std": 1e-12}):
        mean, std = GaussianRandomField(**params, method="exact").fit(xy, z).predict(
            xy, return_std=True)
        assert np.all(np.isfinite(mean)) and np.all(np.isfinite(std))
    with pytest.raises(InvalidArgumentError, match=r"`noise_std` must lie in .*everywhere"):
        GaussianRandomField(length_scale=0.1, signal_std=1.0, noise_std=0.1).fit(
            xy, z, noise_std=np.full(20, 1e-20))
