"""Foam FEM: parity with scikit-fem's generic assembly, convergence, Hertz, stiffness ordering."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import Basis, ElementHex1, ElementVectorH1, MeshHex, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

from deformap.explore import ExplorationConfig
from deformap.world import (
    Block,
    Scenario,
    hertz_contact_radius,
    hertz_indentation,
    hertz_pressure_samples,
)
from deformap.world._fem import FoamBody, HexGrid, graded_levels
from deformap.world._foam import FoamModel
from deformap.world._polygon import rectangle


def _box_grid(length: float, thickness: float, h: float, top: float, growth: float) -> HexGrid:
    n = round(length / h)
    return HexGrid(origin=np.zeros(2), dx=length / n, dy=length / n, nx=n, ny=n,
                   levels=graded_levels(thickness, top, growth), active=np.ones((n, n), bool))


def _press_quarter(grid: HexGrid, body: FoamBody, radius: float, force: float) -> np.ndarray:
    """Hertz pressure of ``force`` centred on the corner (0, 0) of a quarter model."""
    points, forces = hertz_pressure_samples(np.zeros(2), radius, force, n_across=240)
    inside, nodes, weights = grid.locate(points)
    load = np.zeros((grid.n_nodes, 3))
    np.add.at(load[:, 2], nodes[inside].ravel(), -(weights[inside] * forces[inside, None]).ravel())
    assert -load[:, 2].sum() == pytest.approx(force / 4, rel=0.02)
    return load


def test_structured_assembly_equals_scikit_fem_generic_assembly_per_element_modulus() -> None:
    levels = graded_levels(0.05, 0.01, 1.5)
    grid = HexGrid(origin=np.zeros(2), dx=0.02, dy=0.015, nx=3, ny=2, levels=levels,
                   active=np.ones((2, 3), bool))
    modulus = np.random.default_rng(0).uniform(3e3, 12e3, size=(grid.nz, 2, 3))
    body = FoamBody(grid, modulus, poisson_ratio=0.3)
    mesh = MeshHex.init_tensor(np.linspace(0, 0.06, 4), np.linspace(0, 0.03, 3), levels)
    centroids = mesh.p[:, mesh.t].mean(axis=1).T
    ref = None
    for e, c in enumerate(centroids):
        i, j = int(c[0] // 0.02), int(c[1] // 0.015)
        k = int(np.searchsorted(levels, c[2]) - 1)
        basis = Basis(mesh, ElementVectorH1(ElementHex1()), elements=np.array([e]))
        part = asm(linear_elasticity(*lame_parameters(modulus[k, j, i], 0.3)), basis)
        ref = part if ref is None else ref + part
    # our node (i, j, k) -> scikit-fem's node with the same coordinates
    ours = grid.node_xyz()
    order = np.lexsort(ours.T[::-1])
    theirs = np.lexsort(mesh.p[::-1])
    node_map = np.empty(grid.n_nodes, dtype=int)
    node_map[order] = theirs
    perm = (3 * np.arange(grid.n_nodes)[:, None] + np.arange(3)).ravel()
    nodal = Basis(mesh, ElementVectorH1(ElementHex1())).nodal_dofs
    skfem_dofs = np.column_stack([nodal[c, node_map] for c in range(3)]).ravel()
    assert perm.size == skfem_dofs.size
    k_ref = ref.toarray()[np.ix_(skfem_dofs, skfem_dofs)]
    np.testing.assert_allclose(body.stiffness.toarray(), k_ref, atol=1e-10 * np.abs(k_ref).max())


def test_thick_block_matches_analytic_hertz_within_20_percent() -> None:
    modulus, nu, force, tip = 4644.0, 0.3, 0.3, 0.01
    a = hertz_contact_radius(force, tip, modulus, nu)
    grid = _box_grid(0.06, 0.06, 0.004, 0.003, 1.3)  # quarter of 12 x 12 x 6 cm, ~8 a deep
    body = FoamBody(grid, modulus, poisson_ratio=nu, symmetry=("x_min", "y_min"))
    u = body.solve(_press_quarter(grid, body, a, force))
    depth = -u[grid.node_id(0, 0, grid.nz), 2]
    analytic = hertz_indentation(force, tip, modulus, nu)
    assert depth == pytest.approx(analytic, rel=0.20)
    assert np.all(u[grid.node_xyz()[:, 2] == 0] == 0)  # bonded to the table


def test_compliance_converges_at_second_order_under_refinement() -> None:
    """Mean displacement under the load (compliance / F) on a small block, h = 8, 4, 2 mm."""
    values = []
    for h in (0.008, 0.004, 0.002):
        grid = _box_grid(0.04, 0.02, h, h, 1.0)
        body = FoamBody(grid, 4644.0, poisson_ratio=0.3, symmetry=("x_min", "y_min"))
        load = _press_quarter(grid, body, 0.015, 0.3)
        u = body.solve(load)
        values.append(float(load[:, 2] @ u[:, 2]) / float(-load[:, 2].sum()))
    d1, d2 = values[1] - values[0], values[2] - values[1]
    rate = np.log2(d1 / d2)
    assert d1 > d2 > 0  # stiffer-than-exact from below, gaps shrinking
    assert 1.5 < rate < 2.5, f"observed order {rate:.2f}"


def _small_world(hardness: float) -> FoamModel:
    block = Block(name="f", polygon=rectangle(0.0, 0.0, 0.16, 0.16), hardness_n=hardness)
    return FoamModel(Scenario(name="s", blocks=(block,)), element_size_m=0.0075,
                     top_layer_m=0.005, layer_growth=1.5, poisson_ratio=0.3)


def test_stiffer_foam_dents_less_and_default_force_dents_clearly() -> None:
    from deformap.world import WorldConfig
    from deformap.world._camera import DepthCamera

    config = WorldConfig()
    camera = DepthCamera(config.camera, (0.3, 0.2))
    c = config.camera
    target = np.array([0.08, 0.08])
    rng_m = float(np.linalg.norm(np.array([*target, 0.05]) - camera.origin))
    sigma = c.sigma_base_m + c.sigma_quadratic_m * (rng_m - c.sigma_reference_m) ** 2
    depths = []
    for hardness in (60.0, 110.0, 150.0):
        dent = _small_world(hardness).dent(target, ExplorationConfig().force_n, tip_radius_m=0.01)
        assert dent.contact_radius_m <= 0.01
        depths.append(dent.depth_m)
    assert depths[0] > depths[1] > depths[2]
    assert depths[2] > 1.5 * sigma  # the 150 N foam still dents beyond the pixel noise
    assert depths[0] < 0.025  # less than half of the 5 cm block


def test_homogeneous_blocks_share_the_unit_modulus_factorisation_and_solve_exactly() -> None:
    """Two homogeneous blocks of one mesh solve on one factorisation, scaled by 1/E, and give
    what a direct sparse solve of their own stiffness gives; a graded block factorises its own."""
    from scipy.sparse.linalg import spsolve

    grid = _box_grid(0.06, 0.03, 0.01, 0.005, 1.5)
    load = np.zeros((grid.n_nodes, 3))
    top = np.flatnonzero(np.isclose(grid.node_xyz()[:, 2], 0.03))
    load[top[len(top) // 2], 2] = -0.5
    soft = FoamBody(grid, 2.0e3, poisson_ratio=0.3)
    hard = FoamBody(grid, 2.0e4, poisson_ratio=0.3)
    assert hard._lu is soft._lu  # one factorisation for both
    for body in (soft, hard):
        k_ff = body.stiffness[body.free][:, body.free].tocsc()
        direct = spsolve(k_ff, load.ravel()[body.free])
        np.testing.assert_allclose(body.solve(load).ravel()[body.free], direct, rtol=1e-8,
                                   atol=1e-15)
    np.testing.assert_allclose(hard.solve(load), soft.solve(load) / 10.0, rtol=1e-12, atol=0)
    graded = np.full((grid.nz, grid.ny, grid.nx), 2.0e3)
    graded[0] = 4.0e3
    other = FoamBody(grid, graded, poisson_ratio=0.3)
    assert other._lu is not soft._lu
    k_ff = other.stiffness[other.free][:, other.free].tocsc()
    np.testing.assert_allclose(other.solve(load).ravel()[other.free],
                               spsolve(k_ff, load.ravel()[other.free]), rtol=1e-8, atol=1e-15)
    # another Poisson ratio is another stiffness
    assert FoamBody(grid, 2.0e3, poisson_ratio=0.25)._lu is not soft._lu


def test_a_homogeneous_solve_does_not_depend_on_what_was_built_before() -> None:
    """Bit for bit: the unit-modulus factorisation is of K₁ assembled at E = 1, not of the first
    block's stiffness scaled back (which differs in the last bits from one history to another)."""
    from deformap.world import _fem

    grid = _box_grid(0.06, 0.03, 0.01, 0.005, 1.5)
    load = np.zeros((grid.n_nodes, 3))
    top = np.flatnonzero(np.isclose(grid.node_xyz()[:, 2], 0.03))
    load[top[len(top) // 3], 2] = -0.3
    _fem._UNIT_FACTORS.clear()
    alone = FoamBody(grid, 37.0e3, poisson_ratio=0.3).solve(load)
    _fem._UNIT_FACTORS.clear()
    FoamBody(grid, 1.3e3, poisson_ratio=0.3)  # fills the cache first
    after = FoamBody(grid, 37.0e3, poisson_ratio=0.3).solve(load)
    assert np.array_equal(alone, after)


def _two_blocks() -> FoamModel:
    blocks = (Block(name="soft", polygon=rectangle(0.0, 0.0, 0.08, 0.12), hardness_n=40.0),
              Block(name="hard", polygon=rectangle(0.08, 0.0, 0.16, 0.12), hardness_n=150.0,
                    thickness_m=0.03))
    return FoamModel(Scenario(name="s", blocks=blocks), element_size_m=0.0075,
                     top_layer_m=0.005, layer_growth=1.5, poisson_ratio=0.3)


@pytest.mark.parametrize("target", [(0.04, 0.06), (0.081, 0.05), (0.12, 0.03)])
def test_a_press_from_unit_responses_is_the_press_solved_load_by_load(
        target: tuple[float, float]) -> None:
    """The press's unit responses under the tip, summed, give the displacements of one solve per
    load to rounding (inside a block, by the seam where the patch loads both, on a thinner
    block), with the same patch iterations; the press takes one solve call per body."""
    direct, columns = _two_blocks(), _two_blocks()
    direct.max_unit_columns = 0
    calls: list[int] = []
    for body in columns.bodies.values():
        solve = body.solve_free

        def counted(rhs: np.ndarray, solve=solve) -> np.ndarray:  # type: ignore[no-untyped-def]
            calls.append(1 if rhs.ndim == 1 else rhs.shape[1])
            return solve(rhs)

        body.solve_free = counted  # type: ignore[method-assign]
    xy = np.array(target)
    iterations = []
    for force in (0.8, 0.4, 0.2):  # as a record's levels: the largest first, one press
        a = direct.dent(xy, force, tip_radius_m=0.01)
        b = columns.dent(xy, force, tip_radius_m=0.01)
        assert b.iterations == a.iterations
        iterations.append(a.iterations)
        assert b.depth_m == pytest.approx(a.depth_m, rel=1e-12)
        assert b.contact_radius_m == pytest.approx(a.contact_radius_m, rel=1e-12)
        np.testing.assert_allclose(b.displacement, a.displacement, rtol=0,
                                   atol=1e-12 * float(np.abs(a.displacement).max()))
    assert sum(iterations) > 3  # the patch iterated
    loaded_bodies = len(columns._columns)
    assert 1 <= loaded_bodies <= 2 and len(calls) == loaded_bodies  # one call a body
    assert all(1 < n <= columns.max_unit_columns for n in calls)
    # a press elsewhere starts afresh, forget() or not: bit for bit a fresh model's press there
    elsewhere = xy + np.array([0.013, 0.021])
    again = columns.dent(elsewhere, 0.8, tip_radius_m=0.01)
    fresh = _two_blocks().dent(elsewhere, 0.8, tip_radius_m=0.01)
    assert np.array_equal(again.displacement, fresh.displacement)
    columns.forget()
    assert not columns._columns and columns._reach is None


def _top_load(model: FoamModel, index: int, xy: tuple[float, float], force: float) -> np.ndarray:
    """A vertical point load on the top node of block ``index`` nearest ``xy``."""
    grid, body = model.grids[index], model.bodies[index]
    nodes = grid.node_xyz()
    top = np.flatnonzero(np.isclose(nodes[:, 2], grid.levels[-1]))
    node = top[np.argmin(np.hypot(*(nodes[top, :2] - np.asarray(xy)).T))]
    load = np.zeros((grid.n_nodes, 3))
    load[node, 2] = -force
    assert 3 * node + 2 in body.free
    return load


def test_a_load_beyond_the_solved_unit_responses_solves_the_missing_ones_or_falls_back() -> None:
    """Within a press, a load on a node outside the tip's disc adds its unit response (one more
    call of one column); past the cap the load is solved as it comes; both to rounding."""
    model = _two_blocks()
    xy = np.array([0.04, 0.06])
    model.dent(xy, 0.4, tip_radius_m=0.01)
    z, _ = model._columns[0]
    far = _top_load(model, 0, (0.015, 0.02), 0.3)  # 5 cm from the tip
    body = model.bodies[0]
    expected = body.solve(far)
    got = model._respond(0, far, xy)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    assert model._columns[0][0].shape[1] == z.shape[1] + 1
    other = _top_load(model, 0, (0.07, 0.11), 0.2)
    model.max_unit_columns = model._columns[0][0].shape[1]  # no room for one more
    got = model._respond(0, other, xy)
    np.testing.assert_array_equal(got, body.solve(other))  # the load solved as it came
    assert model._columns[0][0].shape[1] == model.max_unit_columns


def test_long_columns_past_the_byte_bound_are_not_kept(monkeypatch) -> None:
    from deformap.world import _foam

    model = _two_blocks()
    monkeypatch.setattr(_foam, "MAX_UNIT_BYTES", 8 * model.bodies[0].n_dofs * 3)
    xy = np.array([0.04, 0.06])
    direct = _two_blocks()
    direct.max_unit_columns = 0
    a, b = direct.dent(xy, 0.4, tip_radius_m=0.01), model.dent(xy, 0.4, tip_radius_m=0.01)
    assert not model._columns
    assert np.array_equal(a.displacement, b.displacement)


def test_a_press_needing_more_unit_responses_than_allowed_is_solved_load_by_load() -> None:
    capped, direct = _two_blocks(), _two_blocks()
    capped.max_unit_columns, direct.max_unit_columns = 3, 0
    xy = np.array([0.04, 0.06])
    a = direct.dent(xy, 1.0, tip_radius_m=0.01)
    b = capped.dent(xy, 1.0, tip_radius_m=0.01)
    assert not capped._columns  # nothing solved as columns
    assert np.array_equal(a.displacement, b.displacement) and a.depth_m == b.depth_m
