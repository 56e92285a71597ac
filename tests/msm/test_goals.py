"""Invariants of Müller's goals: fixed points, rigid motions, exact fits, proper rotations."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import polar
from scipy.spatial.transform import Rotation

from deformap.msm import ParticleGrid, ShapeMatchingConfig, polar_rotation, shape_matching_goals
from deformap.msm._clusters import Clusters

MODES = ("rigid", "linear", "quadratic")
BETAS = np.array([0.0, 0.3, 0.7, 0.99])


def curved_rest(rng, n=8, spacing=0.005):
    xs = np.arange(n) * spacing
    gx, gy = np.meshgrid(xs, xs)
    z = 0.05 + 0.02 * np.sin(gx / 0.02) * np.cos(gy / 0.03) + 1e-3 * rng.standard_normal(gx.shape)
    return ParticleGrid.from_heightmap(xs, xs, z).rest


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("k", [2, 3, 4])
def test_rest_shape_is_a_fixed_point_for_every_beta(rng, mode, k):
    rest = curved_rest(rng)
    cfg = ShapeMatchingConfig(mode=mode, cluster_size=k)
    cur = np.broadcast_to(rest, (BETAS.size, *rest.shape))
    goals = shape_matching_goals(rest, cur, BETAS, cfg)
    np.testing.assert_allclose(goals, cur, rtol=0, atol=1e-12)


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("seed", range(5))
def test_rigid_motion_gives_goals_equal_to_the_moved_particles(rng, mode, seed):
    rest = curved_rest(rng)
    r = Rotation.random(random_state=seed).as_matrix()
    t = np.random.default_rng(seed).normal(scale=0.1, size=3)
    moved = rest @ r.T + t
    cur = np.broadcast_to(moved, (BETAS.size, *rest.shape))
    goals = shape_matching_goals(rest, cur, BETAS, ShapeMatchingConfig(mode=mode))
    # the regularised fit truncates directions below 1e-3 of the largest moment; on this
    # curved noisy patch that bounds the error well below a micrometre
    np.testing.assert_allclose(goals, cur, rtol=0, atol=1e-7)


def _goals_at_beta_one(rest, cur, mode, regularization=1e-3):
    # β = 1 is outside the public [0, 1) range, so the cluster object is used directly
    cl = Clusters(rest, np.ones(rest.shape[:2]), (3, 3), mode, regularization)
    return cl.goals(cur[None], np.array([1.0]))[0]


def test_linear_mode_at_beta_one_reproduces_any_affine_deformation(rng):
    rest = curved_rest(rng)
    a = np.eye(3) + rng.normal(scale=0.3, size=(3, 3))
    moved = rest @ a.T + rng.normal(size=3)
    np.testing.assert_allclose(_goals_at_beta_one(rest, moved, "linear"), moved, atol=1e-12)


def test_quadratic_mode_at_beta_one_reproduces_any_quadratic_deformation(rng):
    n, h = 8, 0.005
    xs = np.arange(n) * h
    rest = ParticleGrid.from_heightmap(xs, xs, np.full((n, n), 0.05)).rest
    p = rest - rest.mean(axis=(0, 1))
    x, y = p[..., 0], p[..., 1]
    # every quadratic map of the plane into 3-D: linear part + x², y², xy terms (the z terms of
    # q̃ vanish on the flat patch, as does everything they would add)
    lin = np.eye(3) + rng.normal(scale=0.2, size=(3, 3))
    quad = rng.normal(scale=20.0, size=(3, 3))
    moved = p @ lin.T + np.einsum("dk,...k->...d", quad, np.stack([x * x, y * y, x * y], -1))
    got = _goals_at_beta_one(rest, moved, "quadratic")
    np.testing.assert_allclose(got, moved, atol=1e-12)
    # a linear-mode fit cannot: the bending is left over
    assert np.abs(_goals_at_beta_one(rest, moved, "linear") - moved).max() > 1e-5


def test_flat_patch_gives_finite_goals_and_proper_rotations(rng):
    n = 6
    xs = np.arange(n) * 0.005
    rest = ParticleGrid.from_heightmap(xs, xs, np.full((n, n), 0.05)).rest
    cur = rest + rng.normal(scale=1e-3, size=(4, *rest.shape))
    cur[0] = rest  # rank-2 A_pq exactly
    for mode in MODES:
        cl = Clusters(rest, np.ones((n, n)), (3, 3), mode, 1e-3)
        rots = cl.rotations(cl.gather(cur))
        assert np.all(np.isfinite(rots))
        np.testing.assert_allclose(np.linalg.det(rots), 1.0, atol=1e-12)
        np.testing.assert_allclose(rots @ np.swapaxes(rots, -1, -2),
                                   np.broadcast_to(np.eye(3), rots.shape), atol=1e-12)
        np.testing.assert_allclose(rots[0], np.broadcast_to(np.eye(3), rots[0].shape),
                                   atol=1e-12)
        goals = shape_matching_goals(rest, cur, BETAS, ShapeMatchingConfig(mode=mode))
        assert np.all(np.isfinite(goals))


def test_polar_rotation_matches_scipy_polar(rng):
    a = rng.normal(size=(50, 3, 3))
    a[np.linalg.det(a) < 0, :, 0] *= -1  # scipy's unitary factor is a rotation only for det > 0
    want = np.stack([polar(m)[0] for m in a])
    np.testing.assert_allclose(polar_rotation(a.copy()), want, atol=1e-10)


def test_polar_rotation_of_a_reflection_is_still_proper():
    a = np.diag([1.0, 1.0, -1.0])
    r = polar_rotation(a[None])[0]
    assert np.isclose(np.linalg.det(r), 1.0)


def test_planar_cluster_shortcut_matches_the_svd_polar_rotation(rng):
    n = 7
    xs = np.arange(n) * 0.005
    rest = ParticleGrid.from_heightmap(xs, xs, np.full((n, n), 0.05)).rest
    cl = Clusters(rest, np.ones((n, n)), (3, 3), "quadratic", 1e-3)
    assert cl.planar.all()
    r = Rotation.random(3, random_state=7).as_matrix()
    cur = np.einsum("bde,yxe->byxd", r, rest) + rng.normal(scale=1e-3, size=(3, *rest.shape))
    apq = np.swapaxes(cl.gather(cur), -1, -2) @ cl.ws
    np.testing.assert_allclose(cl.rotations(cl.gather(cur)), polar_rotation(apq.copy()),
                               atol=1e-10)


def test_layered_rotation_term_matches_the_per_cluster_sum(rng):
    # the solver's component-major box-filter path against gathering every cluster's members
    n, h = 7, 0.005
    xs = np.arange(n) * h
    sheet = ParticleGrid.from_heightmap(xs, xs, np.full((n, n), 0.05)).rest
    body = np.stack([sheet - [0.0, 0.0, d] for d in (0.0, 0.004, 0.012)])
    masses = np.ones(body.shape[:3]) * np.array([1.0, 1.5, 3.0])[:, None, None]
    cl = Clusters(body, masses, (2, 3, 3), "quadratic", 1e-3)
    assert not cl.planar.any()
    x = body[None] + rng.normal(scale=1e-3, size=(2, *body.shape))
    rs = cl.s @ np.swapaxes(cl.rotations(cl.gather(x)), -1, -2)
    want = cl.scatter(rs) / cl.count[None, ..., None]
    np.testing.assert_allclose(cl.rotation_term(x), want, rtol=0, atol=1e-14)


def test_fast_polar_rotation_matches_the_svd_polar(rng):
    from deformap.msm._polar import fast_polar_rotation

    a = rng.normal(size=(300, 3, 3))
    a[:100] = np.eye(3) + 0.05 * a[:100]  # near rotations, as in a converging solve
    a[250:260, :, 2] = 0.0  # singular: the SVD fallback
    a[260:270, :, 0] *= -np.sign(np.linalg.det(a[260:270]))[:, None]  # det < 0: fallback
    np.testing.assert_allclose(fast_polar_rotation(a.copy()), polar_rotation(a.copy()),
                               atol=1e-12)


@pytest.mark.parametrize("max_iter", [1, 2])
def test_fast_polar_rotation_falls_back_to_svd_when_newton_stops_early(rng, max_iter):
    # every matrix is safe for Newton, but the iteration budget ends before convergence: the
    # unconverged ones must get the SVD answer of the *input*, not of a half-updated iterate
    from deformap.msm._polar import fast_polar_rotation

    a = np.eye(3) + 0.5 * rng.normal(size=(200, 3, 3))
    a = a[np.linalg.det(a) > 0.1]
    np.testing.assert_allclose(fast_polar_rotation(a.copy(), max_iter=max_iter),
                               polar_rotation(a.copy()), atol=1e-12)
