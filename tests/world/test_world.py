"""The simulated world as an Environment: camera, probe, press rules, ground truth, determinism."""

from __future__ import annotations

import itertools
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
import trimesh
from scipy.spatial import Delaunay

from deformap.cloud import PointCloud
from deformap.environment import Environment, PressObservation
from deformap.errors import EnvironmentStateError, InvalidArgumentError
from deformap.explore import ExplorationConfig
from deformap.world import (
    CameraConfig,
    SimulatedWorld,
    WorldConfig,
    hardness_to_youngs_modulus,
    load_scenario,
)
from deformap.world._raycast import cast_rays

COARSE = WorldConfig.coarse()


@pytest.fixture(scope="module")
def world() -> SimulatedWorld:
    return SimulatedWorld(load_scenario("heterogeneous-60-110-rigid"), config=COARSE,
                          rng=np.random.default_rng(7))


def _fresh(world: SimulatedWorld) -> SimulatedWorld:
    if world.is_pressing:
        world.release()
    return world


def test_world_is_an_environment_and_observes_the_area(world) -> None:
    assert isinstance(world, Environment)
    cloud = _fresh(world).observe()
    assert isinstance(cloud, PointCloud) and cloud.frame == "world"
    on_area = world.workspace.contains(cloud.xy)
    assert on_area.sum() > 5000  # 320x240 coarse camera; 640x480 gives ~4x more
    # surfaces are at the block tops (5 cm) on the area, give or take the sensor noise
    assert np.median(np.abs(cloud.z[on_area] - 0.05)) < 0.004


def test_noise_free_points_lie_on_the_surfaces() -> None:
    cam = replace(COARSE.camera, noise=False)
    w = SimulatedWorld(load_scenario("homogeneous-60"), config=replace(COARSE, camera=cam),
                       rng=np.random.default_rng(0))
    cloud = w.observe()
    inner = np.all((cloud.xy > 0.01) & (cloud.xy < np.array([0.59, 0.39])), axis=1)
    np.testing.assert_allclose(cloud.z[inner], 0.05, atol=1e-9)
    table = np.all((cloud.xy < -0.05) | (cloud.xy > 0.65), axis=1) & (cloud.xy[:, 1] < 0.8)
    np.testing.assert_allclose(cloud.z[table], 0.0, atol=1e-9)


def test_axial_noise_follows_the_quadratic_model() -> None:
    w = SimulatedWorld(load_scenario("homogeneous-110"),
                       config=replace(COARSE, camera=replace(COARSE.camera,
                                                             flying_probability=0.0)),
                       rng=np.random.default_rng(1))
    cloud = w.observe()
    inner = np.all((cloud.xy > 0.02) & (cloud.xy < np.array([0.58, 0.38])), axis=1)
    pts = cloud.points[inner]
    c, cam = w.config.camera, w.camera
    rays = pts - cam.origin
    dist = np.linalg.norm(rays, axis=1)
    depth = rays @ cam.cam2world[:3, 2]
    sigma = c.sigma_base_m + c.sigma_quadratic_m * (depth - c.sigma_reference_m) ** 2
    step = depth**2 / (cam.focal_px * c.baseline_m * c.subpixel)  # disparity quantum in depth
    dz_per_depth = np.abs(rays[:, 2]) / depth  # a depth error moves the point along its ray
    predicted = np.sqrt(np.mean((sigma**2 + step**2 / 12) * dz_per_depth**2))
    measured = np.std(pts[:, 2] - 0.05)
    assert measured == pytest.approx(predicted, rel=0.25)
    assert dist.min() > 0.8  # the camera is ~1.1 m from the area


def test_grazing_rays_return_nothing() -> None:
    cfg = replace(COARSE, camera=replace(COARSE.camera, grazing_deg=45.0, noise=False))
    w = SimulatedWorld(load_scenario("homogeneous-60"), config=cfg, rng=np.random.default_rng(0))
    all_pts = SimulatedWorld(load_scenario("homogeneous-60"), config=replace(
        COARSE, camera=replace(COARSE.camera, noise=False)), rng=np.random.default_rng(0)).observe()
    pts = w.observe().points
    flat = pts[np.abs(pts[:, 2] - 0.05) < 1e-9]
    rays = flat - w.camera.origin
    incidence = np.degrees(np.arccos(np.abs(rays[:, 2]) / np.linalg.norm(rays, axis=1)))
    assert incidence.max() <= 45.0 + 1e-6
    assert 0.1 * len(all_pts) < len(pts) < 0.9 * len(all_pts)


def test_flying_pixels_appear_at_depth_edges_only_when_enabled() -> None:
    def floating(p_fly: float) -> int:
        cfg = replace(COARSE, camera=replace(COARSE.camera, flying_probability=p_fly))
        cloud = SimulatedWorld(load_scenario("homogeneous-60"), config=cfg,
                               rng=np.random.default_rng(3)).observe()
        behind = cloud.xy[:, 1] > 0.405  # behind the block's back edge: table at z = 0
        return int(np.count_nonzero(behind & (cloud.z > 0.015) & (cloud.z < 0.035)))

    assert floating(0.0) == 0
    assert floating(0.3) > 10


def test_embree_and_pure_fallback_agree() -> None:
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=0.1)
    rng = np.random.default_rng(0)
    origins = np.tile([0.0, 0.0, 1.0], (500, 1))
    dirs = np.column_stack([rng.uniform(-0.12, 0.12, (500, 2)), -np.ones(500)])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    r1, _, l1 = cast_rays(mesh, origins, dirs, use_embree=True)
    r2, _, l2 = cast_rays(mesh, origins, dirs, use_embree=False)
    assert r1.size > 100 and np.array_equal(r1, r2)
    np.testing.assert_allclose(l1, l2, atol=1e-7)


def test_world_seen_through_the_numpy_caster_equals_embree() -> None:
    def cloud(use_embree: bool) -> np.ndarray:
        cam = replace(COARSE.camera, noise=False, use_embree=use_embree)
        w = SimulatedWorld(load_scenario("heterogeneous-150-rigid"),
                           config=replace(COARSE, camera=cam), rng=np.random.default_rng(0))
        return w.press((0.1, 0.2), 0.6).cloud.points

    fast, pure = cloud(True), cloud(False)
    assert abs(len(fast) - len(pure)) <= 1e-3 * len(fast)  # rays grazing a shared edge may differ
    if len(fast) == len(pure):
        np.testing.assert_allclose(fast, pure, atol=1e-6)


def test_press_returns_contact_robot_and_occluding_probe(world) -> None:
    w = _fresh(world)
    before = w.observe()
    force = ExplorationConfig().force_n
    obs = w.press((0.08, 0.2), force)
    assert isinstance(obs, PressObservation)
    contact = obs.contact
    assert contact.direction[2] < -0.99  # pushes into the surface
    assert contact.force_n == pytest.approx(force, abs=5 * w.config.force_noise_n * np.sqrt(3))
    dent = w.dent((0.08, 0.2), force)
    assert dent.depth_m > 0.002
    assert contact.tip_center[2] == pytest.approx(0.05 - dent.depth_m + 0.01)
    hull = Delaunay(obs.robot_points)
    inside = [contact.tip_center + np.array([0, 0, dz]) for dz in (0.0, 0.05, 0.1, 0.15, 0.2)]
    assert np.all(hull.find_simplex(np.array(inside)) >= 0)  # tip top, stick and hand covered
    pts = obs.cloud.points
    assert np.count_nonzero(pts[:, 2] > 0.17) > 50  # the hand is seen
    near_stick = (np.linalg.norm(pts[:, :2] - contact.tip_center[:2], axis=1) < 0.008) & (
        pts[:, 2] > contact.tip_center[2] + 0.015) & (pts[:, 2] < contact.tip_center[2] + 0.1)
    assert np.count_nonzero(near_stick) > 5  # the stick is seen
    behind = (np.abs(before.xy[:, 0] - 0.08) < 0.04) & (before.xy[:, 1] > 0.2) & (
        before.xy[:, 1] < 0.3) & (before.z < 0.06)
    behind_now = (np.abs(pts[:, 0] - 0.08) < 0.04) & (pts[:, 1] > 0.2) & (pts[:, 1] < 0.3) & (
        pts[:, 2] < 0.06)
    assert np.count_nonzero(behind_now) < 0.8 * np.count_nonzero(behind)  # occlusion
    w.release()


def test_press_refuses_bad_targets_forces_and_double_press(world) -> None:
    w = _fresh(world)
    with pytest.raises(InvalidArgumentError, match="`target_xy` must lie in the workspace"):
        w.press((0.7, 0.2), 0.5)
    with pytest.raises(InvalidArgumentError, match="`force_n` must be > 0"):
        w.press((0.3, 0.2), 0.0)
    with pytest.raises(InvalidArgumentError, match="`force_n` must be > 0"):
        w.press((0.3, 0.2), -1.0)
    with pytest.raises(InvalidArgumentError, match="`target_xy`"):
        w.press((0.3, 0.2, 0.0), 0.5)
    w.press((0.3, 0.2), 0.5)
    with pytest.raises(EnvironmentStateError, match="release"):
        w.press((0.2, 0.2), 0.5)
    w.release()
    w.press((0.2, 0.2), 0.5)
    w.release()
    assert not w.is_pressing
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        SimulatedWorld(load_scenario("homogeneous-60"), config=COARSE, rng=0)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`poisson_ratio`"):
        WorldConfig(poisson_ratio=0.5)
    with pytest.raises(InvalidArgumentError, match="`element_size_m` must be > 0"):
        WorldConfig(element_size_m=0.0)


def test_press_on_rigid_board_does_not_dent(world) -> None:
    w = _fresh(world)
    obs = w.press((0.55, 0.2), 0.6)
    assert obs.contact.tip_center[2] == pytest.approx(0.06)
    w.release()


def test_ground_truth_on_any_grid(world) -> None:
    xs, ys = np.array([0.05, 0.35, 0.55, 0.7]), np.array([0.1, 0.3])
    labels = world.ground_truth_labels(xs, ys)
    assert labels.tolist() == [[0, 1, 2, -1], [0, 1, 2, -1]]
    hardness = world.ground_truth_hardness(xs, ys)
    assert hardness[0].tolist() == [60.0, 110.0, np.inf, np.inf]
    modulus = world.ground_truth_modulus(xs, ys)
    assert modulus[0, 0] == pytest.approx(hardness_to_youngs_modulus(60.0))
    assert world.scenario.region_names == ["foam-60", "foam-110", "rigid"]
    assert [r.rigid for r in world.regions] == [False, False, True]


def test_surface_height_rest_and_dented(world) -> None:
    xs, ys = np.linspace(0.01, 0.59, 59), np.linspace(0.01, 0.39, 39)
    rest = world.surface_height(xs, ys)
    np.testing.assert_allclose(rest, 0.05)
    dent = world.dent((0.1, 0.2), 0.6)
    dented = world.surface_height(xs, ys, dent.displacement)
    assert dented.min() == pytest.approx(0.05 - dent.depth_m, abs=0.002)
    iy, ix = np.unravel_index(np.argmin(dented), dented.shape)
    assert abs(xs[ix] - 0.1) <= 0.02 and abs(ys[iy] - 0.2) <= 0.02
    np.testing.assert_allclose(dented[:, xs > 0.45], 0.05)  # the rigid board does not move
    with pytest.raises(InvalidArgumentError, match="`displacement`"):
        world.surface_height(xs, ys, np.zeros((3, 3)))


def test_same_seed_same_clouds_bit_for_bit() -> None:
    def run(seed: int) -> list[np.ndarray]:
        w = SimulatedWorld(load_scenario("heterogeneous-60-150"), config=COARSE,
                           rng=np.random.default_rng(seed))
        first = w.observe().points
        obs = w.press((0.2, 0.2), 0.6)
        return [first, obs.cloud.points, obs.contact.force]

    a, b, c = run(5), run(5), run(6)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])


def test_softer_region_dents_deeper_in_the_same_world() -> None:
    w = SimulatedWorld(load_scenario("heterogeneous-60-150"), config=COARSE,
                       rng=np.random.default_rng(0))
    soft, hard = w.dent((0.15, 0.2), 0.6), w.dent((0.45, 0.2), 0.6)
    assert soft.depth_m > hard.depth_m > 0


def test_camera_settings_are_validated() -> None:
    for bad in ({"width": -1}, {"pitch_deg": 0.0}, {"height_m": float("nan")},
                {"flying_probability": 5.0}):
        with pytest.raises(InvalidArgumentError, match=f"`{next(iter(bad))}`"):
            CameraConfig(**bad)
    with pytest.raises(InvalidArgumentError, match="`camera` must be a CameraConfig"):
        WorldConfig(camera={"width": 320})  # type: ignore[arg-type]


def test_world_does_not_import_the_estimator() -> None:
    code = ("import sys, deformap.world; "
            "bad = [m for m in sys.modules if m.startswith(('deformap.msm', 'deformap.gp', "
            "'deformap.explore'))]; print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=False)
    assert result.returncode == 0, result.stdout + result.stderr


def test_noise_switch_turns_off_camera_and_force_noise() -> None:
    w = SimulatedWorld(load_scenario("homogeneous-60"), config=WorldConfig.coarse(noise=False),
                       rng=np.random.default_rng(0))
    obs = w.press((0.3, 0.2), 0.6)
    np.testing.assert_array_equal(obs.contact.force, [0.0, 0.0, -0.6])
    far = np.all((obs.cloud.xy > 0.05) & (obs.cloud.xy < 0.12), axis=1)
    np.testing.assert_allclose(obs.cloud.z[far], 0.05, atol=1e-6)
    with pytest.raises(InvalidArgumentError, match="`hand_size_m`"):
        WorldConfig(hand_size_m=(0.1, 0.0, 0.1))
    with pytest.raises(InvalidArgumentError, match="`tip_radius_m` must be >= 1e-06"):
        WorldConfig(tip_radius_m=-0.01)


def test_testing_helper_builds_a_coarse_world() -> None:
    from deformap.testing import coarse_world

    w = coarse_world("heterogeneous-60-150", seed=3)
    assert isinstance(w, Environment) and w.config.element_size_m == 0.02


@pytest.mark.parametrize("name", ["homogeneous-60", "homogeneous-110", "heterogeneous-60-150",
                                  "heterogeneous-110-150", "heterogeneous-150-rigid", "random"])
def test_every_scenario_builds_and_softer_dents_deeper(name) -> None:
    from deformap.world import random_scenario

    sc = random_scenario(np.random.default_rng(11)) if name == "random" else load_scenario(name)
    w = SimulatedWorld(sc, config=COARSE, rng=np.random.default_rng(0))
    depths = {}
    for k, block in enumerate(w.regions):
        xy = block.polygon.mean(axis=0)
        assert w.ground_truth_labels([xy[0]], [xy[1]])[0, 0] == k
        depths[block.hardness] = w.dent(xy, 0.6).depth_m
    ordered = [depths[h] for h in sorted(depths)]
    assert all(a > b for a, b in itertools.pairwise(ordered))
    assert depths.get(np.inf, 0.0) == 0.0
