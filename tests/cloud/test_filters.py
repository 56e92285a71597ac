from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from deformap.cloud import (
    HULL_TOLERANCE_M,
    PointCloud,
    crop_box,
    height_field_mask,
    points_in_hull,
    statistical_outlier_mask,
)
from deformap.errors import InvalidArgumentError

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def _rigid(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return Rotation.random(random_state=rng).as_matrix(), rng.uniform(-1.0, 1.0, 3)


def _brute_force_sor(points: np.ndarray, k: int, std_ratio: float) -> tuple[np.ndarray, ...]:
    """Open3D's RemoveStatisticalOutliers transcribed loop by loop, all pairs, no k-d tree."""
    n = len(points)
    dist = np.sqrt(((points[:, None, :] - points[None, :, :]) ** 2).sum(axis=2))
    avg = np.empty(n)
    for i in range(n):
        avg[i] = np.sort(dist[i])[:k].sum() / k  # the point itself (0) is among its k
    cloud_mean = sum(a for a in avg if a > 0) / n
    sq_sum = sum((a - cloud_mean) ** 2 for a in avg if a > 0)
    threshold = cloud_mean + std_ratio * np.sqrt(sq_sum / (n - 1))
    keep = np.array([a > 0 and a < threshold for a in avg])
    return keep, avg, threshold


# ---- crop_box ----


def test_crop_box_reference_values() -> None:
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [0.5, 2.0, 0.5]])
    mask = crop_box(pts, [0, 0, 0], [1, 1, 1])
    assert mask.dtype == np.bool_
    assert mask.tolist() == [True, True, True, False]
    assert crop_box(np.zeros((0, 3)), [0, 0, 0], [1, 1, 1]).shape == (0,)


@settings(max_examples=40, deadline=None)
@given(seed=seeds)
def test_crop_box_is_idempotent_and_commutes_with_translation_and_axis_flips(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1, 1, (200, 3))
    lo = rng.uniform(-1, 0, 3)
    hi = lo + rng.uniform(0, 1.5, 3)
    mask = crop_box(pts, lo, hi)
    kept = pts[mask]
    assert crop_box(kept, lo, hi).all()
    # A signed axis permutation plus a translation maps an axis-aligned box to one.
    perm = rng.permutation(3)
    signs = rng.choice([-1.0, 1.0], 3)
    shift = rng.uniform(-2, 2, 3)

    def move(p: np.ndarray) -> np.ndarray:
        return p[..., perm] * signs + shift

    corners = np.stack([move(lo), move(hi)])
    moved = crop_box(move(pts), corners.min(axis=0), corners.max(axis=0))
    assert np.array_equal(moved, mask)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((np.zeros((3, 2)), [0, 0, 0], [1, 1, 1]), r"`points` must be a \(n, 3\)"),
        ((np.zeros((3, 3)), [0, 0], [1, 1, 1]), r"`lower` must be a \(3,\)"),
        ((np.zeros((3, 3)), [0, 0, 0], [1, np.nan, 1]), r"`upper` .* NaN"),
        ((np.zeros((3, 3)), [0, 2, 0], [1, 1, 1]), r"`lower` must be <= `upper`"),
    ],
)
def test_crop_box_refuses_bad_input(args: tuple[object, ...], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        crop_box(*args)


# ---- statistical_outlier_mask ----


@settings(max_examples=30, deadline=None)
@given(
    seed=seeds,
    n=st.integers(min_value=2, max_value=60),
    k=st.integers(min_value=1, max_value=12),
    std_ratio=st.floats(min_value=0.01, max_value=4.0),
    duplicates=st.integers(min_value=0, max_value=6),
)
def test_outlier_mask_matches_brute_force_rule(
    seed: int, n: int, k: int, std_ratio: float, duplicates: int
) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 3)) * rng.uniform(0.01, 1.0, 3)
    # Exact duplicates give zero averages, the case where Open3D departs from the textbook rule.
    pts = np.vstack([pts, np.repeat(pts[:1], duplicates, axis=0)])
    k = min(k, len(pts))
    expected, avg, threshold = _brute_force_sor(pts, k, std_ratio)
    got = statistical_outlier_mask(pts, k, std_ratio)
    # Summation order differs between the two, so only points within round-off of the threshold
    # may disagree.
    clear = np.abs(avg - threshold) > 1e-12 * max(1.0, abs(threshold))
    assert np.array_equal(got[clear], expected[clear])


def test_outlier_mask_never_keeps_points_with_k_coincident_neighbours() -> None:
    rng = np.random.default_rng(5)
    pts = np.vstack([rng.normal(scale=0.01, size=(100, 3)), np.zeros((4, 3))])
    mask = statistical_outlier_mask(pts, 4, 3.0)
    assert not mask[-4:].any()  # average distance 0: Open3D drops them
    assert mask[:-4].mean() > 0.9


def test_outlier_mask_removes_far_points_and_keeps_the_cluster() -> None:
    rng = np.random.default_rng(3)
    cluster = rng.normal(scale=0.01, size=(300, 3))
    far = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.5]])
    mask = statistical_outlier_mask(np.vstack([cluster, far]), 10, 2.0)
    assert not mask[-2:].any()
    assert mask[:-2].mean() > 0.9


def test_outlier_mask_removes_every_point_when_all_averages_are_equal_like_open3d() -> None:
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    # k = 4: the point and its three edge neighbours, average exactly 3/4 everywhere, so s = 0
    # and m < m is false for every point.
    assert not statistical_outlier_mask(cube, 4, 1.0).any()
    # k = 1: every average is 0, and Open3D keeps only positive averages.
    assert not statistical_outlier_mask(cube, 1, 1.0).any()


@settings(max_examples=20, deadline=None)
@given(seed=seeds)
def test_outlier_mask_commutes_with_rigid_motions(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.normal(scale=0.02, size=(80, 3)), rng.uniform(-0.5, 0.5, (5, 3))])
    rot, shift = _rigid(seed)
    a = statistical_outlier_mask(pts, 8, 1.0)
    b = statistical_outlier_mask(pts @ rot.T + shift, 8, 1.0)
    _, avg, threshold = _brute_force_sor(pts, 8, 1.0)
    clear = np.abs(avg - threshold) > 1e-12
    assert clear.sum() >= len(pts) - 1
    assert np.array_equal(a[clear], b[clear])


def test_outlier_mask_parity_with_open3d() -> None:
    o3d = pytest.importorskip("open3d")
    rng = np.random.default_rng(7)
    pts = np.vstack([rng.normal(scale=0.02, size=(500, 3)), rng.uniform(-0.3, 0.3, (20, 3))])
    for k, ratio in [(5, 1.0), (20, 2.0), (10, 0.5)]:
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
        _, kept = pcd.remove_statistical_outlier(nb_neighbors=k, std_ratio=ratio)
        expected = np.zeros(len(pts), bool)
        expected[np.asarray(kept, dtype=int)] = True
        assert np.array_equal(statistical_outlier_mask(pts, k, ratio), expected)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((np.zeros((5, 3)), 6, 1.0), r"at least k=6 points .* got 5"),
        ((np.zeros((1, 3)), 1, 1.0), r"at least 2\) .* got 1"),
        ((np.zeros((5, 3)), 0, 1.0), r"`k` must be an integer >= 1"),
        ((np.zeros((5, 3)), 2.5, 1.0), r"`k` must be an integer"),
        ((np.zeros((5, 3)), 2, float("nan")), r"`std_ratio` must be finite"),
        ((np.zeros((5, 3)), 2, 0.0), r"`std_ratio` must be > 0"),
        ((np.zeros((5, 2)), 2, 1.0), r"`points` must be a \(n, 3\)"),
    ],
)
def test_outlier_mask_refuses_bad_input(args: tuple[object, ...], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        statistical_outlier_mask(*args)


# ---- points_in_hull ----


def test_points_in_hull_reference_values_on_a_unit_cube() -> None:
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    pts = np.array(
        [
            [0.5, 0.5, 0.5],  # inside
            [1.0, 0.5, 0.5],  # on a face
            [1.0 + 0.5 * HULL_TOLERANCE_M, 0.5, 0.5],  # within the tolerance
            [1.0 + 2 * HULL_TOLERANCE_M, 0.5, 0.5],  # beyond it
            [-0.1, 0.5, 0.5],
        ]
    )
    assert points_in_hull(pts, cube).tolist() == [True, True, True, False, False]
    assert points_in_hull(np.zeros((0, 3)), cube).shape == (0,)


@settings(max_examples=40, deadline=None)
@given(seed=seeds)
def test_points_in_hull_commutes_with_rigid_motions(seed: int) -> None:
    rng = np.random.default_rng(seed)
    hull = rng.normal(size=(12, 3)) * rng.uniform(0.05, 0.5, 3)
    pts = rng.uniform(-0.6, 0.6, (300, 3))
    rot, shift = _rigid(seed)
    a = points_in_hull(pts, hull)
    b = points_in_hull(pts @ rot.T + shift, hull @ rot.T + shift)
    # The hull's own vertices must count as inside, and the mask must not depend on the pose
    # except for points within round-off of a facet.
    assert points_in_hull(hull, hull).all()
    from scipy.spatial import ConvexHull

    eq = ConvexHull(hull).equations
    margin = np.max(pts @ eq[:, :3].T + eq[:, 3], axis=1)
    clear = np.abs(margin - HULL_TOLERANCE_M) > 1e-9
    assert np.array_equal(a[clear], b[clear])
    # Inside means: a convex combination of the vertices, checked by the hull of vertices + point.
    inside = pts[a & clear][:5]
    for p in inside:
        assert len(ConvexHull(np.vstack([hull, p])).vertices) == len(ConvexHull(hull).vertices)


def test_points_in_hull_removes_a_stick_from_a_cloud() -> None:
    rng = np.random.default_rng(0)
    table = np.column_stack([rng.uniform(0, 0.2, (400, 2)), np.zeros(400)])
    stick = np.column_stack([rng.uniform(0.09, 0.11, (50, 2)), rng.uniform(0.01, 0.2, 50)])
    cloud = PointCloud(np.vstack([table, stick]))
    box = np.array(
        [[x, y, z] for x in (0.085, 0.115) for y in (0.085, 0.115) for z in (0.005, 0.3)]
    )
    kept = cloud.select(~points_in_hull(cloud.points, box))
    assert len(kept) == 400
    assert np.all(kept.z == 0.0)


@pytest.mark.parametrize(
    ("hull", "message"),
    [
        (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]], float), "one plane"),
        (np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]], float), "one plane or line"),
        (np.zeros((3, 3)), "at least 4 rows"),
        (np.ones((4, 3)), "must span a volume"),
    ],
)
def test_points_in_hull_refuses_degenerate_hulls(hull: np.ndarray, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        points_in_hull(np.zeros((2, 3)), hull)


def test_points_in_hull_refuses_negative_tolerance() -> None:
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    with pytest.raises(InvalidArgumentError, match="`tolerance_m` must be >= 0"):
        points_in_hull(np.zeros((2, 3)), cube, tolerance_m=-1.0)


# ---- height field (steep faces) -------------------------------------------------------------

def _block_with_front_face(rng: np.random.Generator, noise: float = 0.0015) -> tuple:
    """The top of a 5 cm block seen by a camera in front: the top (z = 0.05) and its front face
    (y = 0, z from 0 to 0.05), with camera-like depth noise."""
    gx, gy = np.meshgrid(np.arange(0.0, 0.3, 0.003), np.arange(0.0, 0.2, 0.003))
    top = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, 0.05)])
    fx, fz = np.meshgrid(np.arange(0.0, 0.3, 0.003), np.arange(0.0, 0.05, 0.003))
    face = np.column_stack([fx.ravel(), np.zeros(fx.size), fz.ravel()])
    pts = np.vstack([top, face])
    pts += rng.normal(scale=noise / np.sqrt(3), size=pts.shape)
    return pts, len(top)


def test_height_field_mask_removes_a_vertical_face_and_keeps_the_top() -> None:
    pts, n_top = _block_with_front_face(np.random.default_rng(0))
    keep = height_field_mask(pts, k=20, max_slope_deg=60.0)
    top, face = keep[:n_top], keep[n_top:]
    face_z = pts[n_top:, 2]
    # the face below its top centimetre (where neighbourhoods mix with the top) is gone
    assert not np.any(face[face_z < 0.04])
    assert top.mean() > 0.98
    # what survives of the face is at the top edge, where it is a height anyway
    assert np.all(face_z[face] > 0.04)


@pytest.mark.parametrize("slope_deg, kept", [(0.0, True), (30.0, True), (50.0, True),
                                             (70.0, False), (85.0, False)])
def test_height_field_mask_keeps_planes_by_their_slope(slope_deg: float, kept: bool) -> None:
    rng = np.random.default_rng(1)
    uv = rng.uniform(-0.05, 0.05, size=(2000, 2))
    pts = np.column_stack([uv[:, 0], uv[:, 1], np.tan(np.radians(slope_deg)) * uv[:, 0]])
    keep = height_field_mask(pts, k=20, max_slope_deg=60.0)
    assert np.all(keep) if kept else not np.any(keep)


def test_height_field_mask_at_ninety_degrees_keeps_everything_and_is_rotation_invariant_in_z(
) -> None:
    pts, _ = _block_with_front_face(np.random.default_rng(2))
    assert np.all(height_field_mask(pts, max_slope_deg=90.0))
    rot = Rotation.from_euler("z", 37.0, degrees=True).as_matrix()
    moved = pts @ rot.T + np.array([1.0, -2.0, 0.3])
    np.testing.assert_array_equal(height_field_mask(moved), height_field_mask(pts))


@pytest.mark.parametrize("kwargs, message", [
    ({"k": 2}, "`k`"), ({"max_slope_deg": 0.0}, "`max_slope_deg`"),
    ({"max_slope_deg": 91.0}, "`max_slope_deg`"), ({"max_slope_deg": float("nan")},
                                                   "`max_slope_deg`"),
])
def test_height_field_mask_refuses_bad_arguments(kwargs: dict, message: str) -> None:
    pts, _ = _block_with_front_face(np.random.default_rng(3))
    with pytest.raises(InvalidArgumentError, match=message):
        height_field_mask(pts, **kwargs)


def test_height_field_mask_refuses_too_few_points_and_bad_points() -> None:
    with pytest.raises(InvalidArgumentError, match=r"`points`.*k=20"):
        height_field_mask(np.zeros((5, 3)))
    with pytest.raises(InvalidArgumentError, match="`points`"):
        height_field_mask(np.full((30, 3), np.nan))
