"""Hertz contact and the analytic dent used as the β estimation's test world: reference values,
agreement between the formulas, bad input; the old homes are the same objects."""

from __future__ import annotations

import numpy as np
import pytest

import deformap.environment
import deformap.testing
import deformap.world
from deformap.errors import InvalidArgumentError
from deformap.mechanics import (
    TactileContact,
    elastic_dent,
    hardness_to_youngs_modulus,
    hertz_contact_radius,
    hertz_indentation,
    hertz_pressure_samples,
    hertz_surface_at_depth,
    hertz_surface_deflection,
    reduced_modulus,
)

hardness_to_modulus = hardness_to_youngs_modulus


def test_hardness_to_modulus_reference_values():
    # (H / 0.0323 m²) / 0.4: 60, 110, 150 N → 4.6, 8.5, 11.6 kPa
    assert [round(hardness_to_modulus(h) / 1e3, 1) for h in (60, 110, 150)] == [4.6, 8.5, 11.6]


def test_hertz_centre_depth_and_continuity():
    f, r, e, nu = 0.5, 0.01, 4644.0, 0.5
    e_star = e / (1 - nu**2)
    a = (3 * f * r / (4 * e_star)) ** (1 / 3)
    assert hertz_surface_deflection(0.0, f, r, e, nu) == pytest.approx(a * a / r, rel=1e-12)
    inside = hertz_surface_deflection(a * (1 - 1e-9), f, r, e, nu)
    outside = hertz_surface_deflection(a * (1 + 1e-9), f, r, e, nu)
    assert inside == pytest.approx(outside, rel=1e-6)
    # 1 cm tip, 0.5 N on a 60 N foam: about 7 mm
    assert 6e-3 < a * a / r < 8e-3


def test_far_field_tends_to_boussinesq_point_load():
    f, r, e, nu = 0.5, 0.01, 1e4, 0.3
    far = 0.5
    want = (1 - nu**2) * f / (np.pi * e * far)
    assert hertz_surface_deflection(far, f, r, e, nu) == pytest.approx(want, rel=1e-3)


def test_elastic_dent_contact_sits_in_the_dent():
    xs = ys = np.linspace(0.24, 0.36, 25)
    z = np.full((25, 25), 0.05)
    zd, contact = elastic_dent(xs, ys, z, (0.30, 0.30), force_n=0.5, tip_radius_m=0.01,
                               modulus_pa=hardness_to_modulus(110))
    assert contact.contact_point[2] == pytest.approx(zd[12, 12])
    assert np.all(zd <= z) and zd.min() == zd[12, 12]
    zr, rigid = elastic_dent(xs, ys, z, (0.30, 0.30), force_n=0.5, tip_radius_m=0.01,
                             modulus_pa=None)
    np.testing.assert_array_equal(zr, z)
    assert rigid.contact_point[2] == pytest.approx(0.05)


def test_indentation_is_the_deflection_under_the_centre() -> None:
    for f, r, e, nu in [(0.5, 0.01, 4644.0, 0.5), (2.0, 0.005, 2e4, 0.3), (0.1, 0.02, 1e5, 0.0)]:
        a = hertz_contact_radius(f, r, e, nu)
        assert a**3 == pytest.approx(3 * f * r / (4 * reduced_modulus(e, nu)), rel=1e-12)
        delta = hertz_indentation(f, r, e, nu)
        assert delta == pytest.approx(a * a / r, rel=1e-15)
        assert float(hertz_surface_deflection(0.0, f, r, e, nu)) == pytest.approx(delta, rel=1e-12)


def test_pressure_samples_sum_to_the_force_inside_the_disc() -> None:
    points, forces = hertz_pressure_samples(np.array([0.3, 0.2]), 0.004, 1.5)
    assert forces.sum() == pytest.approx(1.5, rel=1e-12)
    assert np.all(np.hypot(*(points - [0.3, 0.2]).T) < 0.004)
    # heavier at the centre than at the rim, as √(1 − r²/a²)
    r = np.hypot(*(points - [0.3, 0.2]).T)
    assert forces[np.argmin(r)] == forces.max() and forces[np.argmax(r)] == forces.min()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((0.5, 0.01, -1.0, 0.5), "`youngs_modulus_pa` must be > 0"),
        ((0.5, 0.01, 1e4, 0.6), r"`poisson_ratio` must lie in \(-1, 0.5\]"),
        ((0.5, 0.01, 1e4, -1.0), r"`poisson_ratio` must lie in \(-1, 0.5\]"),
        ((0.0, 0.01, 1e4, 0.5), "`force_n` must be > 0"),
        ((0.5, float("nan"), 1e4, 0.5), "`tip_radius_m` must be finite"),
    ],
)
def test_hertz_refuses_bad_input(args: tuple[float, ...], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        hertz_indentation(*args)


def test_the_old_homes_are_the_same_objects() -> None:
    assert deformap.environment.TactileContact is TactileContact
    assert deformap.testing.elastic_dent is elastic_dent
    assert deformap.testing.hertz_surface_deflection is hertz_surface_deflection
    assert deformap.testing.hardness_to_modulus is hardness_to_youngs_modulus
    assert deformap.world.hertz_indentation is hertz_indentation
    assert deformap.world.hertz_contact_radius is hertz_contact_radius
    assert deformap.world.hardness_to_youngs_modulus is hardness_to_youngs_modulus


def test_the_surface_at_a_depth_is_hertz_surface_of_any_modulus_that_sinks_that_deep() -> None:
    force, radius, modulus, nu = 0.6, 0.01, 40e3, 0.3
    r = np.linspace(0.0, 0.04, 41)
    surface = hertz_surface_deflection(r, force, radius, modulus, nu)
    depth = hertz_indentation(force, radius, modulus, nu)
    at_depth = hertz_surface_at_depth(r, depth, radius)
    assert at_depth[0] == pytest.approx(depth, rel=1e-12)
    np.testing.assert_allclose(at_depth, surface, rtol=1e-10, atol=0.0)
