"""A sphere on an elastic layer bonded to the table (Dimitriadis et al. 2002): the published
coefficients, the half-space limit, monotonicity, the stiffness as the force's derivative, bad
input."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.mechanics import (
    hertz_indentation,
    layer_chi_limit,
    layer_correction,
    layer_correction_coefficients,
    layer_indentation_force,
    layer_indentation_stiffness,
)

R = 0.01


def test_incompressible_coefficients_are_the_published_ones():
    # their bonded, ν = 0.5 form: 1 + 1.133 χ + 1.283 χ² + 0.769 χ³ ± 0.0975 χ⁴ (module docstring
    # on the χ⁴ sign)
    c = layer_correction_coefficients(0.5)
    np.testing.assert_allclose(c[:4], [1.0, 1.133, 1.283, 0.769], atol=6e-4)
    assert abs(c[4]) == pytest.approx(0.0975, abs=6e-4)


def test_thin_limit_is_hertz_inverse():
    # χ → 0 (a layer far thicker than the contact): the force that sinks the sphere by Hertz's δ
    for f, e, nu in [(0.3, 2e3, 0.33), (1.0, 2e4, 0.0), (3.0, 2e5, 0.5)]:
        depth = hertz_indentation(f, R, e, nu)
        got = layer_indentation_force(depth, R, 1e6, e, nu)
        assert got == pytest.approx(f, rel=1e-6)


def test_force_is_monotone_in_depth_and_stiffer_on_thinner_layers():
    depth = np.linspace(0.0, 8e-3, 200)
    for h in (0.02, 0.05, 0.10):
        f = layer_indentation_force(depth, R, h, 1e4, 0.33)
        assert f[0] == 0.0 and np.all(np.diff(f) > 0)
    thick, mid, thin = (layer_indentation_force(depth[1:], R, h, 1e4, 0.33)
                        for h in (0.10, 0.05, 0.02))
    assert np.all(thin > mid) and np.all(mid > thick)
    assert np.all(layer_correction(np.linspace(0.0, 1.0, 50), 0.33)[1:] > 1.0)


def test_force_is_linear_in_modulus_and_keeps_shape():
    depth = np.array([[1e-3, 2e-3], [3e-3, 4e-3]])
    f1 = layer_indentation_force(depth, R, 0.05, 1e4, 0.33)
    f3 = layer_indentation_force(depth, R, 0.05, 3e4, 0.33)
    assert f1.shape == (2, 2)
    np.testing.assert_allclose(f3, 3.0 * f1, rtol=1e-12)


def test_stiffness_is_the_force_derivative():
    depth = np.linspace(1e-4, 1e-2, 30)
    step = 1e-8
    numeric = (layer_indentation_force(depth + step, R, 0.03, 5e3, 0.33)
               - layer_indentation_force(depth - step, R, 0.03, 5e3, 0.33)) / (2 * step)
    np.testing.assert_allclose(layer_indentation_stiffness(depth, R, 0.03, 5e3, 0.33), numeric,
                               rtol=1e-6)


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"depth_m": -1e-3}, "depth_m"),
    ({"depth_m": [1e-3, np.nan]}, "depth_m"),
    ({"depth_m": "1e-3"}, "depth_m"),
    ({"tip_radius_m": 0.0}, "tip_radius_m"),
    ({"thickness_m": 0.0}, "thickness_m"),
    ({"thickness_m": -0.05}, "thickness_m"),
    ({"youngs_modulus_pa": -1.0}, "youngs_modulus_pa"),
    ({"poisson_ratio": 0.6}, "poisson_ratio"),
    ({"poisson_ratio": -0.1}, "poisson_ratio"),
])
def test_bad_input_is_refused_naming_the_argument(kwargs, name):
    args = {"depth_m": 1e-3, "tip_radius_m": R, "thickness_m": 0.05, "youngs_modulus_pa": 1e4,
            "poisson_ratio": 0.33} | kwargs
    for function in (layer_indentation_force, layer_indentation_stiffness):
        with pytest.raises(InvalidArgumentError, match=f"`{name}`"):
            function(**args)


def test_force_rises_up_to_the_chi_limit_and_turns_there():
    for nu, want in [(0.0, 1.747), (0.33, 2.185), (0.5, 8.045)]:
        limit = layer_chi_limit(nu)
        assert limit == pytest.approx(want, abs=1e-3)
        h = 0.02
        depth = (np.array([0.98, 1.0, 1.02]) * limit * h) ** 2 / R
        k = layer_indentation_stiffness(depth, R, h, 1e4, nu)
        assert k[0] > 0 and abs(k[1]) < 1e-6 * k[0] and k[2] < 0
