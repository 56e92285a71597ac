from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformap.cloud import DEFAULT_CAP_HALF_ANGLE_DEG, contact_cap, tactile_points
from deformap.environment import TactileContact
from deformap.errors import InvalidArgumentError

vec = st.lists(st.floats(min_value=-1.0, max_value=1.0), min_size=3, max_size=3)


@settings(max_examples=60, deadline=None)
@given(
    center=vec,
    force=vec.filter(lambda f: np.linalg.norm(f) > 1e-3),
    radius=st.floats(min_value=1e-3, max_value=0.05),
    n=st.integers(min_value=1, max_value=40),
    half_angle=st.floats(min_value=1.0, max_value=90.0),
)
def test_tactile_points_lie_on_the_sphere_within_the_cap(
    center: list[float], force: list[float], radius: float, n: int, half_angle: float
) -> None:
    pts = tactile_points(center, force, radius, n, cap_half_angle_deg=half_angle)
    assert pts.shape == (n, 3)
    c = np.asarray(center)
    u = np.asarray(force) / np.linalg.norm(force)
    rel = pts - c
    np.testing.assert_allclose(np.linalg.norm(rel, axis=1), radius, rtol=1e-12)
    cos_angle = rel @ u / radius
    assert np.all(cos_angle >= np.cos(np.radians(half_angle)) - 1e-12)
    np.testing.assert_allclose(pts[0], c + radius * u, atol=1e-15)
    # The polar angles do not depend on where the tip is or which way it presses.
    canonical = tactile_points([0, 0, 0], [0, 0, 1], 1.0, n, cap_half_angle_deg=half_angle)
    np.testing.assert_allclose(cos_angle, canonical[:, 2], atol=1e-9)
    if n > 1:  # the spiral ends on the rim and no point repeats
        np.testing.assert_allclose(cos_angle[-1], np.cos(np.radians(half_angle)), atol=1e-12)
        gaps = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(n)
        assert gaps.min() > 0


def test_tactile_points_for_a_press_straight_down_sit_below_the_centre() -> None:
    pts = tactile_points([0.3, 0.2, 0.05], [0.0, 0.0, -5.0], 0.01)
    assert pts.shape == (10, 3)
    np.testing.assert_allclose(pts[0], [0.3, 0.2, 0.04])
    # Every point of a 30° cap is at most r (1 - cos 30°) above the pole.
    rise = pts[:, 2] - 0.04
    assert rise.min() >= 0 and rise.max() == pytest.approx(0.01 * (1 - np.cos(np.radians(30))))
    assert DEFAULT_CAP_HALF_ANGLE_DEG == 30.0
    # Deterministic: the same call gives the same points; the force's magnitude does not matter.
    np.testing.assert_array_equal(pts, tactile_points([0.3, 0.2, 0.05], [0.0, 0.0, -1.0], 0.01))


def test_tactile_points_spread_over_the_cap_evenly_in_area() -> None:
    pts = tactile_points([0, 0, 0], [0, 0, -1], 1.0, 2001, cap_half_angle_deg=60.0)
    height = 1.0 + pts[:, 2]  # height above the pole, uniform in [0, 1 - cos 60°] for equal area
    counts, _ = np.histogram(height, bins=5, range=(0, 0.5))
    assert counts.min() >= 399 and counts.max() <= 401


def test_the_first_tactile_point_is_the_contact_point_of_the_contact() -> None:
    contact = TactileContact(
        tip_center=np.array([0.1, 0.2, 0.03]), force=np.array([1.0, 0.0, -4.0]), tip_radius_m=0.008
    )
    pts = tactile_points(contact.tip_center, contact.force, contact.tip_radius_m, 12)
    np.testing.assert_allclose(pts[0], contact.contact_point, rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"force_vector": [0, 0, 0]}, "`force_vector` must be a non-zero"),
        ({"tip_radius_m": 0.0}, "`tip_radius_m` must be > 0"),
        ({"n": 0}, "`n` must be an integer >= 1"),
        ({"cap_half_angle_deg": 0.0}, r"`cap_half_angle_deg` must lie in \(0, 90\]"),
        ({"cap_half_angle_deg": 120.0}, r"`cap_half_angle_deg` must lie in \(0, 90\]"),
        ({"tip_center": [0, 0]}, r"`tip_center` must be a \(3,\)"),
        ({"force_vector": [0, np.inf, 0]}, "`force_vector` .* infinite"),
    ],
)
def test_tactile_points_refuse_bad_input(kwargs: dict[str, object], message: str) -> None:
    args: dict[str, object] = {
        "tip_center": [0, 0, 0],
        "force_vector": [0, 0, -1],
        "tip_radius_m": 0.01,
        "n": 10,
    }
    args.update(kwargs)
    with pytest.raises(InvalidArgumentError, match=message):
        tactile_points(**args)  # type: ignore[arg-type]


def test_the_contact_cap_follows_the_indentation() -> None:
    r = 0.01
    # Hertz contact radius √(Rδ): a 1 mm dent on a 1 cm tip touches within 3.16 mm (18.4°)
    angle, count = contact_cap(r, 0.001)
    assert angle == pytest.approx(np.degrees(np.arcsin(np.sqrt(r * 0.001) / r)))
    assert angle == pytest.approx(18.43, abs=0.01)
    # the paper's density, ten points per 30° cap: (1 - cos 18.4°) / (1 - cos 30°) of ten
    assert count == round(10 * (1 - np.cos(np.radians(angle))) / (1 - np.cos(np.radians(30))))
    assert count == 4
    depths = [0.0, 1e-5, 2e-4, 5e-4, 1e-3, 2e-3, 4e-3, 8e-3, 0.02]
    caps = [contact_cap(r, d) for d in depths]
    angles = [a for a, _ in caps]
    counts = [n for _, n in caps]
    assert np.all(np.diff(angles) > 0) and np.all(np.diff(counts) >= 0)
    assert counts[0] == 1 and angles[0] < 0.01  # nothing sunk: the pole alone
    assert counts[-1] == 10 and angles[-1] == 90.0  # sunk past its radius: the half sphere
    assert contact_cap(r, 0.002, n=1)[1] == 1
    # points on that cap lie no higher above the pole than the tip sinks below the surface's
    # contact edge: (1 - cos θ) R = R - √(R² - Rδ) ≤ δ for δ ≤ R
    for d in (2e-4, 1e-3, 4e-3):
        angle, count = contact_cap(r, d)
        pts = tactile_points([0, 0, 0], [0, 0, -1], r, count, cap_half_angle_deg=angle)
        assert (pts[:, 2] + r).max() <= d + 1e-12


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((0.0, 0.001), "`tip_radius_m` must be > 0"),
        ((0.01, -1e-4), "`indentation_m` must be >= 0"),
        ((0.01, float("nan")), "`indentation_m`"),
        ((0.01, 0.001, 0), "`n` must be an integer >= 1"),
    ],
)
def test_the_contact_cap_refuses_bad_input(args: tuple[float, ...], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        contact_cap(*args)  # type: ignore[arg-type]
