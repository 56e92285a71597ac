"""Reference values of the analytic Hertz dent used as the β estimation's test world."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.testing import elastic_dent, hardness_to_modulus, hertz_surface_deflection


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
