"""The in-plane anisotropy a press's dent shows, on synthetic surfaces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.stiffness._anisotropy import ANISOTROPY_FLOOR, dent_anisotropy

TIP = np.array([0.3, 0.2, 0.045])
R = 0.01


def _dent(ratio: float, axis_deg: float, *, noise_m: float = 1e-4, n: int = 6000,
          seed: int = 0) -> np.ndarray:
    """A surface at 5 cm with a Hertz-like dent (depth 6 mm, decaying as 1/(1 + (ρ/a)²)),
    stretched by ratio^(1/4) along ``axis_deg`` (Huber's orthotropy)."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(TIP[:2] - 0.07, TIP[:2] + 0.07, (n, 2))
    q = xy - TIP[:2]
    c, s = math.cos(math.radians(axis_deg)), math.sin(math.radians(axis_deg))
    u, v = c * q[:, 0] + s * q[:, 1], -s * q[:, 0] + c * q[:, 1]
    rho2 = (u / ratio**0.25) ** 2 + v**2
    z = 0.05 - 0.006 / (1.0 + rho2 / 0.012**2)
    return np.column_stack([xy, z + rng.normal(0.0, noise_m, n)])


@pytest.mark.parametrize(("ratio", "axis_deg"), [(1.5, 30.0), (3.0, -45.0), (3.0, 80.0)])
def test_a_stretched_dent_gives_its_ratio_and_stiff_axis(ratio: float, axis_deg: float) -> None:
    got = dent_anisotropy(_dent(ratio, axis_deg), TIP, R)
    assert not isinstance(got, str), got
    assert got.ratio == pytest.approx(ratio, rel=0.15)
    assert abs((got.axis_deg - axis_deg + 90.0) % 180.0 - 90.0) < 10.0
    assert 0.0 < got.ratio_sigma < 0.1 * ratio and got.axis_sigma_deg < 5.0
    assert got.isotropy == "anisotropic" and "reaches farther" in got.evidence


def test_a_round_dent_is_isotropic_and_a_noisy_one_unknown() -> None:
    got = dent_anisotropy(_dent(1.0, 0.0), TIP, R)
    assert not isinstance(got, str)
    assert got.ratio < ANISOTROPY_FLOOR and got.isotropy == "isotropic", got.evidence
    noisy = dent_anisotropy(_dent(1.0, 0.0, noise_m=3e-3, n=800), TIP, R)
    assert not isinstance(noisy, str)
    assert noisy.isotropy == "unknown", noisy.evidence


def test_the_ratio_sigma_covers_the_truth_over_seeds() -> None:
    hits = 0
    for seed in range(12):
        got = dent_anisotropy(_dent(2.0, 10.0, noise_m=5e-4, seed=seed), TIP, R)
        assert not isinstance(got, str)
        hits += abs(got.ratio - 2.0) < 2.0 * got.ratio_sigma + 0.15 * 2.0
    assert hits >= 11


def test_too_few_points_or_a_flat_surface_say_why_and_bad_input_is_refused() -> None:
    few = dent_anisotropy(_dent(2.0, 0.0)[:20], TIP, R)
    assert isinstance(few, str) and "needs 50" in few
    rng = np.random.default_rng(1)
    flat = np.column_stack([rng.uniform(0.23, 0.37, (3000, 2)), np.full(3000, 0.05)
                            + rng.normal(0, 1e-4, 3000)])
    got = dent_anisotropy(flat, TIP, R)
    assert isinstance(got, str) or got.isotropy != "anisotropic"
    with pytest.raises(InvalidArgumentError, match="tip_center"):
        dent_anisotropy(flat, [0.0, float("nan"), 0.0], R)
    with pytest.raises(InvalidArgumentError, match="tip_radius_m"):
        dent_anisotropy(flat, TIP, -1.0)
    with pytest.raises(InvalidArgumentError):
        dent_anisotropy(np.full((100, 3), np.nan), TIP, R)


@pytest.mark.parametrize("seed", range(4))
def test_a_surface_of_noise_gives_a_reason_or_a_class_never_an_error(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts = np.column_stack([rng.uniform(0.23, 0.37, (400, 2)), rng.uniform(0.0, 0.1, 400)])
    got = dent_anisotropy(pts, TIP, R)
    assert isinstance(got, str) or got.isotropy in ("isotropic", "anisotropic", "unknown")
