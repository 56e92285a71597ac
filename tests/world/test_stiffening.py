"""The world's second contact physics: a stiffening foam layer as a two-parameter foundation
(:mod:`deformap.world._stiffening`), against closed forms and its own invariants."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig, _stiffening
from deformap.world._foundation import FoundationGrid, FoundationLayer
from deformap.world._stiffening import StiffeningFoam, graded_axis, max_grid_nodes

R = 0.01  # the tip's radius
CENTER = np.array([0.3, 0.2])
SQUARE = np.array([[0.0, 0.0], [0.6, 0.0], [0.6, 0.4], [0.0, 0.4]])


def _foam(hardness: float = 60.0, *, thickness: float = 0.05, exponent: float = 1.0,
          shear: bool = True, rigid_half: bool = False) -> StiffeningFoam:
    if rigid_half:
        blocks = (Block(name="foam", polygon=SQUARE * [0.5, 1.0], hardness_n=hardness,
                        thickness_m=thickness),
                  Block(name="board", polygon=SQUARE * [0.5, 1.0] + [0.3, 0.0], rigid=True,
                        thickness_m=thickness))
    else:
        blocks = (Block(name="foam", polygon=SQUARE, hardness_n=hardness, thickness_m=thickness),)
    return StiffeningFoam(Scenario(name="s", blocks=blocks), element_size_m=0.0075,
                          top_layer_m=0.005, layer_growth=1.5, poisson_ratio=0.3,
                          densification_strain=0.95, stiffening_exponent=exponent, shear=shear)


def _spy(monkeypatch: pytest.MonkeyPatch) -> dict:
    """Record the last press's Newton result, and the layer and grid it was solved on."""
    seen: dict = {}
    solve, displace = _stiffening.solve_press, StiffeningFoam._displace

    def spy_solve(*args, **kwargs):
        seen["result"] = solve(*args, **kwargs)
        return seen["result"]

    def spy_displace(self, layer, index, w, grid):
        seen["layer"], seen["grid"] = layer, grid
        return displace(self, layer, index, w, grid)

    monkeypatch.setattr(_stiffening, "solve_press", spy_solve)
    monkeypatch.setattr(StiffeningFoam, "_displace", spy_displace)
    return seen


@pytest.mark.parametrize(("hardness", "force"), [(60.0, 0.02), (60.0, 0.6), (250.0, 3.0)])
def test_newton_converges_and_the_contact_carries_the_commanded_force(hardness, force,
                                                                      monkeypatch) -> None:
    foam, seen = _foam(hardness), _spy(monkeypatch)
    dent = foam.dent(CENTER, force, tip_radius_m=R)
    result = seen["result"]
    assert result is not None and result.converged
    assert result.residual_n <= 1e-8 * force
    assert result.contact_force_n.sum() == pytest.approx(force, rel=1e-8)
    # Signorini: compressive contact forces only, and no free node inside the tip
    assert np.all(result.contact_force_n[result.active] >= -1e-9 * force)
    assert result.w.max() == pytest.approx(dent.depth_m, rel=1e-9)  # the pole is the deepest
    assert 0.0 < dent.depth_m < R and 0.0 < dent.contact_radius_m <= R
    assert result.active.sum() >= 9  # the contact disc is resolved by the grid


@pytest.mark.parametrize("force", [0.02, 0.1, 0.3])
def test_without_stiffening_and_shear_it_is_a_winkler_foundation(force) -> None:
    # a sphere sunk δ into a Winkler foundation of modulus k [Pa/m] displaces the volume of a
    # spherical cap, F = k π δ² (R − δ/3) (≈ π k R δ² for δ ≪ R); checked here for the 250 N
    # foam (δ < R/2 at these forces), to the grid's quadrature error
    foam = _foam(250.0, exponent=0.0, shear=False)
    dent = foam.dent(CENTER, force, tip_radius_m=R)
    k = foam.layers[0].spring_pa_per_m
    delta = dent.depth_m
    assert delta < R / 2
    assert k * math.pi * delta**2 * (R - delta / 3) == pytest.approx(force, rel=0.01)
    assert math.pi * k * R * delta**2 == pytest.approx(force, rel=0.01 + delta / R)
    # the contact disc is the cap's: a² = 2 R δ − δ²
    assert dent.contact_radius_m == pytest.approx(math.sqrt(2 * R * delta - delta**2), rel=0.1)


def test_the_layer_parameters_are_vlasovs() -> None:
    linear = FoundationLayer(modulus_pa=1e4, poisson_ratio=0.3, thickness_m=0.05)
    m = 1e4 * 0.7 / (1.3 * 0.4)
    assert linear.spring_pa_per_m == pytest.approx(m / 0.05)
    assert linear.shear_n_per_m == pytest.approx(1e4 / 2.6 * 0.05 / 3)
    # with a decaying mode shape: k = M ∫ φ'² dz and G_p = G ∫ φ² dz, by quadrature
    layer = dataclasses.replace(linear, decay=4.0)
    z = np.linspace(0.0, 0.05, 20001)
    phi, slope = layer.mode(z)
    assert phi[0] == 0.0 and phi[-1] == pytest.approx(1.0)
    assert layer.spring_pa_per_m == pytest.approx(m * np.trapezoid(slope**2, z), rel=1e-6)
    assert layer.shear_n_per_m == pytest.approx(1e4 / 2.6 * np.trapezoid(phi**2, z), rel=1e-6)
    assert dataclasses.replace(linear, decay=1e-4).spring_pa_per_m == pytest.approx(
        linear.spring_pa_per_m, rel=1e-6)  # γ → 0 is the linear mode
    # the column law: linear at small strain, unbounded toward densification
    small = layer.pressure(np.array([1e-9]))[0][0]
    assert small == pytest.approx(layer.spring_pa_per_m * 1e-9, rel=1e-6)
    limit = layer.max_deflection_m
    sigma, dsigma = layer.pressure(np.array([0.5 * limit, (1 - 1e-6) * limit]))
    assert sigma[1] > 1e4 * sigma[0] and np.all(dsigma > 0)
    h = 1e-9  # the tangent is the law's derivative
    w = np.array([0.2, 0.7]) * limit
    numeric = (layer.pressure(w + h)[0] - layer.pressure(w - h)[0]) / (2 * h)
    np.testing.assert_allclose(layer.pressure(w)[1], numeric, rtol=1e-5)


def test_the_mode_shape_is_vallabhan_and_das_fixed_point(monkeypatch) -> None:
    foam, seen = _foam(60.0), _spy(monkeypatch)
    foam.dent(CENTER, 0.6, tip_radius_m=R)
    layer, result = seen["layer"], seen["result"]
    assert layer is not None and result is not None and layer.decay > 1.0
    # the decay the solved deflection asks for is the one it was solved with (to the tolerance)
    grid_nodes = len(result.w)
    assert grid_nodes > 100
    assert seen["grid"] is not None
    assert layer.decay_for(result.w, seen["grid"]) == pytest.approx(layer.decay, rel=0.02)


def test_stiffening_makes_the_secant_stiffness_rise_with_force() -> None:
    forces = [0.3, 1.0, 3.0]
    stiff, linear = _foam(30.0, thickness=0.03), _foam(30.0, thickness=0.03, exponent=0.0)
    d_stiff = np.array([stiff.dent(CENTER, f, tip_radius_m=R).depth_m for f in forces])
    d_linear = np.array([linear.dent(CENTER, f, tip_radius_m=R).depth_m for f in forces])
    assert np.all(np.diff(np.array(forces) / d_stiff) > 0)  # secant stiffness F / δ rises
    # and more than the linear layer's (whose rise is the growing contact disc alone)
    ratio = d_linear / d_stiff
    assert ratio[0] > 1.0 and np.all(np.diff(ratio) > 0), ratio


def test_softer_blocks_dent_deeper_and_thicker_ones_too() -> None:
    depths = [_foam(h).dent(CENTER, 0.6, tip_radius_m=R).depth_m for h in (30.0, 60.0, 250.0)]
    assert depths[0] > depths[1] > depths[2] > 0.0
    thin, thick = (_foam(60.0, thickness=t).dent(CENTER, 0.6, tip_radius_m=R).depth_m
                   for t in (0.03, 0.1))
    assert thick > thin


def test_rigid_ground_does_not_dent_and_the_camera_sees_a_linear_column(monkeypatch) -> None:
    foam, seen = _foam(60.0, rigid_half=True), _spy(monkeypatch)
    rigid = foam.dent(np.array([0.45, 0.2]), 0.6, tip_radius_m=R)
    assert rigid.depth_m == 0.0 and not np.any(rigid.displacement)
    dent = foam.dent(np.array([0.15, 0.2]), 0.6, tip_radius_m=R)
    u = dent.displacement
    board = slice(foam.offsets[1], foam.n_nodes)
    assert not np.any(u[board])  # the neighbouring board is a separate body
    assert not np.any(u[:, :2])  # vertical displacement only
    grid = foam.grids[0]
    xyz = foam.rest_nodes[:grid.n_nodes]
    top = np.isclose(xyz[:, 2], 0.05)
    column = np.isclose(xyz[:, 0], xyz[top][np.argmin(u[:grid.n_nodes][top, 2]), 0]) & \
        np.isclose(xyz[:, 1], xyz[top][np.argmin(u[:grid.n_nodes][top, 2]), 1])
    uz, z = u[:grid.n_nodes][column, 2], xyz[column, 2]
    layer = seen["layer"]
    assert layer is not None
    np.testing.assert_allclose(uz, uz[np.argmax(z)] * layer.mode(z)[0], atol=1e-12)  # 0 at the
    assert uz[np.argmin(z)] == 0.0  # table, the top's deflection at the top
    assert -uz.min() <= dent.depth_m + 1e-12


def test_the_grid_is_graded_from_the_target_and_cut_at_the_block() -> None:
    axis = graded_axis(0.1, 0.0, 0.6, step=1e-3, core=6e-3, reach=0.2)
    assert 0.1 in axis and axis[0] == 0.0 and np.all(np.diff(axis) > 0)
    steps = np.diff(axis)
    assert steps.min() == pytest.approx(1e-3) and axis[-1] < 0.6  # it stops at its reach
    block = Block(name="b", polygon=SQUARE, hardness_n=60.0)
    grid = FoundationGrid.build(block, axis, axis[axis < 0.4])
    assert grid.area.sum() == pytest.approx((axis[-1] - 0.0) * (axis[axis < 0.4][-1] - 0.0))
    # the shear term annihilates a constant (no force from a uniform sink)
    np.testing.assert_allclose(grid.laplacian @ np.ones(len(grid.xy)), 0.0, atol=1e-12)
    assert len(grid.xy) <= max_grid_nodes(np.array([0.6, 0.4]), R)


def test_the_world_under_the_second_physics_records_force_against_travel() -> None:
    scenario = Scenario(name="s", blocks=(
        Block(name="foam", polygon=SQUARE, hardness_n=110.0, thickness_m=0.05),))
    world = SimulatedWorld(scenario, config=WorldConfig.coarse(physics="stiffening-foam",
                                                               noise=False),
                           rng=np.random.default_rng(0))
    obs = world.press(CENTER, 0.6)
    record = obs.force_travel
    c = world.config
    assert record is not None and len(record) == round(
        (0.6 - c.contact_threshold_n) / c.ramp_rate_n_per_s * c.sample_rate_hz) + 1
    assert record.travel_m[0] == 0.0 and np.all(np.diff(record.travel_m) > 0)
    depth = world.dent(CENTER, 0.6).depth_m
    first = world.dent(CENTER, world.config.contact_threshold_n).depth_m
    assert record.travel_m[-1] == pytest.approx(depth - first, rel=0.02)
    # the tip stands on the dented surface
    assert obs.contact.tip_center[2] == pytest.approx(0.05 - depth + R)
    world.release()
