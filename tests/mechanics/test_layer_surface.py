"""The bonded layer's surface about a sphere (Lebedev & Ufliand's kernel under Hertz's pressure):
Hertz's surface on a deep layer, a narrower dent on a thinner one, the kernel's link to the
force series' α₀, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from deformap.errors import InvalidArgumentError
from deformap.mechanics import (
    hertz_contact_radius,
    hertz_surface_deflection,
    layer_correction_coefficients,
    layer_surface_deflection,
)
from deformap.mechanics._layer_surface import _kernel_deficit

R = 0.01


def test_a_deep_layer_has_hertz_surface() -> None:
    force, modulus, nu = 0.6, 20e3, 0.33
    r = np.linspace(0.0, 0.03, 61)
    hertz = hertz_surface_deflection(r, force, R, modulus, nu)
    depth = float(hertz[0])
    assert hertz_contact_radius(force, R, modulus, nu) == pytest.approx(np.sqrt(R * depth))
    layer = layer_surface_deflection(r, depth, R, 1e3, nu)
    np.testing.assert_allclose(layer, hertz, rtol=0, atol=1e-4 * depth)


def test_the_surface_vanishes_a_few_layers_out_and_far_points_cost_nothing() -> None:
    depth, h = 0.005, 0.03
    a = np.sqrt(R * depth)
    w = layer_surface_deflection([a + 2 * h, a + 10 * h, 1e9], depth, R, h, 0.3)
    assert abs(w[0]) < 1e-3 * depth and abs(w[1]) < 1e-4 * depth and w[2] == 0.0


def test_a_thinner_layer_has_a_narrower_dent() -> None:
    depth = 0.004
    r = np.array([0.01, 0.02])
    widths = [layer_surface_deflection(r, depth, R, h, 0.33) for h in (0.1, 0.05, 0.03)]
    assert np.all(np.diff(np.array(widths), axis=0) < 0)


@pytest.mark.parametrize("nu", [0.3, 0.5])
def test_the_kernel_gives_the_force_series_first_coefficient(nu: float) -> None:
    # Dimitriadis et al.'s α₀ is −∫ (1 − L) for the bonded layer; their fit holds to ~1 % here
    alpha = -np.pi / 2.0 * layer_correction_coefficients(nu)[1]
    deficit = quad(lambda u: float(_kernel_deficit(np.array(u), nu)), 0.0, 40.0)[0]
    assert deficit == pytest.approx(-alpha, rel=0.01)


def test_bad_input_names_the_field() -> None:
    with pytest.raises(InvalidArgumentError, match="depth_m"):
        layer_surface_deflection([0.0], -1e-3, R, 0.05, 0.3)
    with pytest.raises(InvalidArgumentError, match="poisson_ratio"):
        layer_surface_deflection([0.0], 1e-3, R, 0.05, 0.6)
    with pytest.raises(InvalidArgumentError, match="`r`"):
        layer_surface_deflection([np.nan], 1e-3, R, 0.05, 0.3)
    # a contact hundreds of layers wide is outside the first-order picture: refused, not a
    # quadrature of millions of points
    with pytest.raises(InvalidArgumentError, match="thickness_m"):
        layer_surface_deflection([0.1], 1e-3, R, 1e-5, 0.3)
