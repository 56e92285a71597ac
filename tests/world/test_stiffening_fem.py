"""The world's third contact physics: the FEM of a continuum foam that stiffens as it is compressed,
solved by Newton's method (:mod:`deformap.world._stiffening_fem`), on the coarse test mesh (its
exploration through the normal loop: ``tests/world/test_physics_config.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig, hertz_pressure_samples
from deformap.world._densification import strain_operator, volumetric_stress, volumetric_tangent
from deformap.world._fem import FoamBody, HexGrid, graded_levels
from deformap.world._foam import FoamModel
from deformap.world._stiffening_fem import StiffeningFem

R = 0.01  # the tip's radius
CENTER = np.array([0.15, 0.1])
MESH = {"element_size_m": 0.02, "top_layer_m": 0.01, "layer_growth": 1.5, "poisson_ratio": 0.3}


def _scenario(hardness: float = 30.0, thickness: float = 0.05) -> Scenario:
    square = np.array([[0.0, 0.0], [0.3, 0.0], [0.3, 0.2], [0.0, 0.2]])
    return Scenario(name="s", blocks=(Block(name="foam", polygon=square, hardness_n=hardness,
                                            thickness_m=thickness),))


def _foam(exponent: float = 1.0, *, densification: float = 0.95, hardness: float = 30.0,
          **kwargs: float) -> StiffeningFem:
    return StiffeningFem(_scenario(hardness), densification_strain=densification,
                         stiffening_exponent=exponent, **MESH, **kwargs)


@pytest.mark.parametrize("exponent", [0.0, 1.0, 2.5])
def test_the_law_is_the_column_law_and_its_tangent_is_its_derivative(exponent) -> None:
    m0, ed = 2.0e4, 0.9
    eps = np.linspace(-0.2, 0.85, 400)
    stress = volumetric_stress(eps, np.full(eps.size, m0), densification=ed, exponent=exponent)
    tangent = volumetric_tangent(eps, np.full(eps.size, m0), densification=ed, exponent=exponent)
    # confined compression: the linear solid's M₀ ε plus the stiffening is σ = M₀ ε / (1 − ε/ε_d)^m
    squeezed = eps > 0
    column = m0 * eps[squeezed] / (1 - eps[squeezed] / ed) ** exponent
    assert m0 * eps[squeezed] + stress[squeezed] == pytest.approx(column, rel=1e-12)
    assert np.all(stress[~squeezed] == 0.0) and np.all(tangent[~squeezed] == 0.0)
    h = 1e-7
    numeric = (volumetric_stress(eps + h, np.full(eps.size, m0), densification=ed,
                                 exponent=exponent)
               - volumetric_stress(eps - h, np.full(eps.size, m0), densification=ed,
                                   exponent=exponent)) / (2 * h)
    assert tangent[np.abs(eps) > 1e-6] == pytest.approx(numeric[np.abs(eps) > 1e-6], rel=1e-5,
                                                         abs=1e-6 * m0)
    if exponent == 1.0:  # the tangent of the brief: M₀ / (1 − ε/ε_d)² under confined compression
        assert m0 + tangent[squeezed] == pytest.approx(m0 / (1 - eps[squeezed] / ed) ** 2)
    assert np.isinf(volumetric_stress(np.array([ed]), np.array([m0]), densification=ed,
                                      exponent=1.0)).all()


def test_the_strain_operator_reads_each_elements_mean_volume_change() -> None:
    grid = HexGrid(origin=np.zeros(2), dx=0.02, dy=0.015, nx=3, ny=2,
                   levels=graded_levels(0.05, 0.01, 1.5), active=np.ones((2, 3), bool))
    body = FoamBody(grid, 1e4, poisson_ratio=0.3)
    op = strain_operator(body)
    xyz = grid.node_xyz()
    # a uniform squeeze u_z = −ε z (0 at the table, free elsewhere): every element reads ε
    u = np.zeros((grid.n_nodes, 3))
    u[:, 2] = -0.07 * xyz[:, 2]
    assert op.matrix.T @ u.ravel()[body.free] == pytest.approx(np.full(6 * grid.nz, 0.07))
    # a shear u_x = γ z changes no volume; a stretch reads a negative compression
    u[:] = 0.0
    u[:, 0] = 0.1 * xyz[:, 2]
    assert np.abs(op.matrix.T @ u.ravel()[body.free]).max() < 1e-12
    u[:, 2] = 0.03 * xyz[:, 2]
    assert op.matrix.T @ u.ravel()[body.free] == pytest.approx(np.full(6 * grid.nz, -0.03))
    assert op.volume.sum() == pytest.approx(0.06 * 0.03 * 0.05)
    assert op.constrained_pa == pytest.approx(np.full(6 * grid.nz, 1e4 * 0.7 / (1.3 * 0.4)))


def _load(foam: StiffeningFem, force: float, radius: float) -> np.ndarray:
    grid = foam.grids[0]
    points, forces = hertz_pressure_samples(CENTER, radius, force)
    inside, nodes, weights = grid.locate(points)
    load = np.zeros((grid.n_nodes, 3))
    np.add.at(load[:, 2], nodes[inside].ravel(), -(weights[inside] * forces[inside, None]).ravel())
    return load


@pytest.mark.parametrize("near", [48, 2])
def test_newton_converges_to_equilibrium_whatever_the_near_set(near) -> None:
    # the residual recomputed here from the assembled K₀ and the law, over every free unknown
    foam = _foam(near_elements=near, tolerance=1e-10)
    load = _load(foam, 2.0, 0.008)
    u = foam._respond(0, load, CENTER).ravel()
    body, op = foam.bodies[0], foam.operators[0]
    free = body.free
    strain = op.matrix.T @ u[free]
    stress = op.volume * volumetric_stress(strain, op.constrained_pa, densification=0.95,
                                           exponent=1.0)
    residual = body.stiffness[free][:, free] @ u[free] + op.matrix @ stress - load.ravel()[free]
    assert np.linalg.norm(residual) <= 1e-9 * 2.0
    assert strain.max() > 0.05  # it was pressed into the nonlinear range
    # the answer is the equilibrium's, not the near set's: 2 elements (the rest joining or
    # carried by the outer rounds) give the 48 elements' displacements
    reference = _foam(tolerance=1e-10)._respond(0, load, CENTER).ravel()
    assert u == pytest.approx(reference, rel=1e-7, abs=1e-12)


def test_forgetting_drops_the_linear_unit_responses_too() -> None:
    foam = _foam(0.0)
    foam.dent(CENTER, 0.6, tip_radius_m=R)
    assert foam._columns  # the exponent-0 press solved by the linear FEM's unit responses
    foam.forget()
    assert not foam._columns and not foam._near


def test_without_stiffening_it_is_the_linear_fem() -> None:
    linear = FoamModel(_scenario(), **MESH)
    for force in (0.3, 0.6, 2.0):
        ref = linear.dent(CENTER, force, tip_radius_m=R)
        off = _foam(0.0).dent(CENTER, force, tip_radius_m=R)
        assert off.depth_m == ref.depth_m and np.array_equal(off.displacement, ref.displacement)
        # the limit m → 0: the Newton solve, with a vanishing stiffening
        faint = _foam(1e-9, tolerance=1e-12).dent(CENTER, force, tip_radius_m=R)
        assert faint.depth_m == pytest.approx(ref.depth_m, rel=1e-8)
        assert faint.contact_radius_m == pytest.approx(ref.contact_radius_m, rel=1e-8)


def test_stiffening_makes_the_dent_strictly_shallower() -> None:
    for force in (0.3, 0.6, 2.0):
        depths = [_foam(m, densification=ed).dent(CENTER, force, tip_radius_m=R).depth_m
                  for m, ed in ((0.0, 0.95), (1.0, 0.95), (1.0, 0.6), (2.0, 0.6))]
        assert all(np.diff(depths) < 0), depths
        assert depths[-1] > 0.0


def _world(seed: int = 0, noise: bool = False, **overrides: object) -> SimulatedWorld:
    config = WorldConfig.coarse(physics="stiffening-fem", noise=noise, **overrides)
    return SimulatedWorld(_scenario(), config=config, rng=np.random.default_rng(seed))


def test_the_record_is_monotone_deterministic_and_stiffer_than_the_fems() -> None:
    world = _world()
    record = world.force_travel(CENTER, 0.6)
    c = world.config
    assert record is not None and record.travel_m.size == round(
        (0.6 - c.contact_threshold_n) / c.ramp_rate_n_per_s * c.sample_rate_hz) + 1
    assert record.travel_m[0] == 0.0 and np.all(np.diff(record.travel_m) > 0)
    assert np.all(np.diff(record.force_n) > 0)
    fem = SimulatedWorld(_scenario(), config=WorldConfig.coarse(noise=False),
                         rng=np.random.default_rng(0)).force_travel(CENTER, 0.6)
    assert fem is not None
    assert np.all(record.travel_m[1:] < fem.travel_m[1:])
    # and without stiffening the world's record is the FEM's, to the bit
    flat = _world(stiffening_exponent=0.0).force_travel(CENTER, 0.6)
    assert flat is not None and np.array_equal(flat.travel_m, fem.travel_m)
    # seeded: the same seed gives the same noisy record, bit for bit
    a = _world(seed=4, noise=True).force_travel(CENTER, 0.6)
    b = _world(seed=4, noise=True).force_travel(CENTER, 0.6)
    assert a is not None and b is not None
    assert np.array_equal(a.travel_m, b.travel_m) and np.array_equal(a.force_n, b.force_n)


def test_a_press_is_solved_the_same_whatever_was_pressed_before() -> None:
    """The near sets and warm starts a press leaves are not carried to the next press: a run
    resumed without its earlier pokes presses a place again to the bit (issue 14's resume)."""
    fresh = _world().dent(CENTER, 0.6)
    world = _world()
    world.dent(CENTER, 0.3)  # the same place, lighter, first
    world.dent(CENTER + 0.03, 0.6)  # and another place
    again = world.dent(CENTER, 0.6)
    assert again.depth_m == fresh.depth_m
    assert np.array_equal(again.displacement, fresh.displacement)
