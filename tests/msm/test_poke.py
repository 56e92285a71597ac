"""Poke equilibrium and β estimation: fixed points, calibration, rigid end, hardness order."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from msm_cases import dent_case

from deformap.environment import TactileContact
from deformap.errors import InvalidArgumentError
from deformap.mechanics import hertz_indentation
from deformap.msm import (
    ParticleGrid,
    ShapeMatchingConfig,
    estimate_beta,
    shape_matching_goals,
    simulate_poke,
)
from deformap.msm._poke import force_weights


def _grid(xs, ys, z):
    return ParticleGrid.from_heightmap(xs, ys, z)


@pytest.mark.parametrize("scale", ["odds", "reference"])
@pytest.mark.parametrize("mode", ["linear", "quadratic"])
def test_force_equilibrium_satisfies_the_pbd_steady_state(mode, scale):
    # sheet body: the solver's matrix form must agree with the goals computed independently;
    # on the odds scale the springs of β are k / β (the body carries β times the force)
    xs, ys, z, _, contact = dent_case(60, n=11)
    g = _grid(xs, ys, z)
    betas = np.array([0.0, 0.5, 0.98])
    cfg = ShapeMatchingConfig(mode=mode, layers=0, tol=1e-10, beta_scale=scale)
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, betas, cfg)
    assert sim.converged.all()
    goals = shape_matching_goals(g.rest, sim.positions, betas, cfg)
    w = force_weights(g.rest, g.fixed, contact, g.spacing_m)
    share = betas if scale == "odds" else np.ones_like(betas)
    want = share[:, None, None, None] * (w[..., None] * contact.force / sim.stiffness_n_per_m)
    free = ~g.fixed
    np.testing.assert_allclose((sim.positions - goals)[:, free], want[:, free], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(sim.positions[:, g.fixed], np.broadcast_to(
        g.rest[g.fixed], (3, *g.rest[g.fixed].shape)))


def test_layered_body_equilibrium_satisfies_the_pbd_steady_state():
    from deformap.msm._clusters import Clusters
    from deformap.msm._simulate import _body

    xs, ys, z, _, contact = dent_case(60, n=11)
    g = _grid(xs, ys, z)
    betas = np.array([0.0, 0.6, 0.98])
    # force, quadratic, 3 layers; the reference scale (every β carries the whole force)
    cfg = ShapeMatchingConfig(tol=1e-10, beta_scale="reference")
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, betas, cfg)
    body, body_m, body_fixed, window = _body(g.rest, g.masses, g.fixed, g.spacing_m, cfg)
    assert body.shape[0] == 4 and np.all(body_fixed[-1]) and window == (2, 3, 3)
    from deformap.msm._poke import Equilibrium

    cl = Clusters(body, body_m, window, cfg.mode, cfg.regularization)
    eq = Equilibrium(cl, body_fixed, betas)
    w = np.zeros(body_fixed.shape)
    w[0] = force_weights(g.rest, g.fixed, contact, g.spacing_m)
    force = w.reshape(-1, 1) * contact.force
    x, _, _, conv = eq.solve(body.reshape(-1, 3)[body_fixed.ravel()], force,
                             sim.stiffness_n_per_m, 1e-10, 500, g.spacing_m)
    assert conv.all()
    np.testing.assert_allclose(x[:, 0], sim.positions, atol=1e-12)
    goals = cl.goals(x, betas)
    free = ~body_fixed
    want = (w[..., None] * contact.force / sim.stiffness_n_per_m)[free]
    np.testing.assert_allclose((x - goals)[:, free], np.broadcast_to(want, (3, *want.shape)),
                               rtol=0, atol=1e-9)


def test_pinned_equilibrium_holds_the_contact_particle_and_relaxes_the_rest():
    xs, ys, z, _, contact = dent_case(60, n=11)
    g = _grid(xs, ys, z)
    cfg = ShapeMatchingConfig(contact="pinned", mode="quadratic", layers=0, tol=1e-10)
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, np.array([0.2, 0.8]), cfg)
    np.testing.assert_allclose(sim.positions[:, 5, 5], np.broadcast_to(contact.contact_point,
                                                                       (2, 3)), atol=1e-12)
    goals = shape_matching_goals(g.rest, sim.positions, np.array([0.2, 0.8]), cfg)
    free = ~g.fixed
    free[5, 5] = False
    np.testing.assert_allclose(sim.positions[:, free], goals[:, free], atol=1e-9)


@pytest.mark.parametrize("mode", ["linear", "quadratic"])
def test_force_calibration_makes_beta_zero_dent_like_the_reference_half_space(mode):
    # the reference scale's β = 0 body is the calibrated one
    xs, ys, z, _, contact = dent_case(60, n=13)
    g = _grid(xs, ys, z)
    cfg = ShapeMatchingConfig(mode=mode, beta_scale="reference")
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, np.array([0.0]), cfg)
    w = force_weights(g.rest, g.fixed, contact, g.spacing_m)
    depth = float(np.sum(w * (g.rest[..., 2] - sim.positions[0, ..., 2])))
    want = hertz_indentation(contact.force_n, contact.tip_radius_m, cfg.reference_modulus_pa,
                             cfg.poisson_ratio)
    assert depth == pytest.approx(want, rel=2e-3)


def test_odds_scale_is_rigid_at_zero_and_the_reference_body_times_beta():
    # springs k / β with the reference scale's calibrated k: β = 0 is the rest shape exactly (a
    # rigid body), and each β's dent is β times the reference body's at that β (a linear body
    # carrying β times the force; the geometric non-linearity of a 1–4 mm dent is small), so the
    # dent's depth runs from 0 to the reference's at the odds β / (1 − β) = 1 and beyond
    xs, ys, z, _, contact = dent_case(60, n=13)
    g = _grid(xs, ys, z)
    betas = np.array([0.0, 0.1, 0.5, 0.9])
    odds = simulate_poke(g.rest, g.masses, g.fixed, contact, betas,
                         ShapeMatchingConfig(beta_scale="odds"))
    ref = simulate_poke(g.rest, g.masses, g.fixed, contact, betas,
                        ShapeMatchingConfig(beta_scale="reference"))
    assert odds.stiffness_n_per_m == ref.stiffness_n_per_m
    assert odds.converged.all() and odds.iterations[0] == 0
    np.testing.assert_array_equal(odds.positions[0], g.rest)
    w = force_weights(g.rest, g.fixed, contact, g.spacing_m)
    d_odds = np.sum(w * (g.rest[..., 2] - odds.positions[..., 2]), axis=(1, 2))
    d_ref = np.sum(w * (g.rest[..., 2] - ref.positions[..., 2]), axis=(1, 2))
    np.testing.assert_allclose(d_odds[1:], betas[1:] * d_ref[1:], rtol=0.02)
    assert np.all(np.diff(d_odds) > 0)


def test_force_dent_deepens_with_beta_and_converges_fast_near_one():
    xs, ys, z, _, contact = dent_case(60, n=13)
    g = _grid(xs, ys, z)
    betas = np.array([0.0, 0.3, 0.6, 0.9, 0.98])
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, betas, ShapeMatchingConfig())
    depth = g.rest[6, 6, 2] - sim.positions[:, 6, 6, 2]
    assert np.all(np.diff(depth) > 0)
    assert sim.converged.all()
    assert np.all(sim.residual < 1e-6)
    assert sim.iterations.max() < 60  # Anderson-accelerated local–global, not PBD's ~n² steps


def test_not_converged_is_reported_not_hidden(caplog):
    xs, ys, z, _, contact = dent_case(60, n=11)
    g = _grid(xs, ys, z)
    cfg = ShapeMatchingConfig(max_iter=2, layers=0)
    with caplog.at_level(logging.WARNING, logger="deformap.msm._poke"):
        sim = simulate_poke(g.rest, g.masses, g.fixed, contact, np.array([0.5, 0.9]), cfg)
    assert not sim.converged.any()
    assert np.all(sim.residual >= cfg.tol)
    assert np.all(sim.iterations == 2)
    assert "did not converge" in caplog.text


@pytest.mark.parametrize("layers", [0, 3])
def test_pinned_rigid_surface_has_flat_error_and_rigid_end(layers):
    xs, ys, z, pts, contact = dent_case(None, n=11)
    cfg = ShapeMatchingConfig(contact="pinned", layers=layers, n_beta=10)
    est = estimate_beta(xs, ys, z, pts, contact, cfg)
    assert np.ptp(est.errors) < 1e-12
    assert est.beta == 0.0
    assert est.all_converged


@pytest.mark.parametrize("mode", ["linear", "quadratic"])
def test_force_rigid_surface_gives_the_rigid_end(mode):
    xs, ys, z, pts, contact = dent_case(None, n=11)
    est = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig(mode=mode, n_beta=10))
    assert est.beta == 0.0
    assert np.all(np.diff(est.errors) > 0)  # any simulated dent is worse than none
    assert est.all_converged


def test_force_protocol_orders_elastic_foams_by_hardness():
    # Hertz dents of a linear-elastic half-space (not shape matching) for five foams; 12 cm ROI
    betas = []
    for hardness in (30.0, 60.0, 110.0, 150.0, 250.0):
        xs, ys, z, pts, contact = dent_case(hardness, n=17, spacing=0.0075)
        est = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig(n_beta=25))
        assert est.all_converged
        last = est.betas[-1]
        assert 0.0 < est.beta < last, "the minimum must lie inside the sweep"
        assert est.errors.min() < est.errors[0] and est.errors.min() < est.errors[-1]
        betas.append(est.beta)
    assert np.all(np.diff(betas) < 0), f"β̂ must fall as hardness rises; got {betas}"


def test_estimate_reports_curve_refinement_and_uncertainty():
    xs, ys, z, pts, contact = dent_case(60, n=13)
    est = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig(n_beta=20))
    assert est.betas.size > 20  # sweep + refinement
    assert np.all(np.diff(est.betas) > 0)
    assert np.all(est.betas >= 0) and np.all(est.betas < 1)
    step = np.min(np.diff(est.betas[np.abs(est.betas - est.beta) < 0.06]))
    assert step == pytest.approx(0.01)
    assert est.beta == est.betas[np.argmin(est.errors)]
    assert 0.01 / np.sqrt(12) <= est.beta_std <= 1 / np.sqrt(12)
    assert est.protocol == "force" and est.mode == "quadratic"
    assert est.stiffness_n_per_m > 0


def test_loose_sweep_tolerance_keeps_the_estimate_and_compares_only_converged_beta():
    # the coarse sweep at sweep_tol only brackets the minimum: β̂ is the one of an all-tight
    # estimate, and β̂ and its grid neighbours are solved to tol
    xs, ys, z, pts, contact = dent_case(110, n=13)
    loose = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig())
    tight = estimate_beta(xs, ys, z, pts, contact, ShapeMatchingConfig(sweep_tol=1e-6))
    cfg = ShapeMatchingConfig()
    assert cfg.sweep_tol > cfg.tol
    assert loose.beta == tight.beta
    near = np.abs(loose.betas - loose.beta) < 0.0101
    assert near.sum() == 3
    assert np.all(loose.residual[near] < cfg.tol)
    assert np.all(loose.residual < cfg.sweep_tol) and loose.all_converged
    assert np.any(loose.residual[~near] >= cfg.tol), "the sweep was not solved loosely"
    assert np.all(loose.tolerances[near] == cfg.tol)
    assert set(loose.tolerances.tolist()) == {cfg.tol, cfg.sweep_tol}
    np.testing.assert_allclose(loose.errors[near], tight.errors[np.isin(tight.betas,
                                                                        loose.betas[near])],
                               rtol=0, atol=1e-8)


def test_without_refinement_every_beta_is_solved_to_tol():
    xs, ys, z, pts, contact = dent_case(60, n=9)
    cfg = ShapeMatchingConfig(refine=False)
    est = estimate_beta(xs, ys, z, pts, contact, cfg)
    assert est.betas.size == cfg.n_beta and cfg.coarse_tol == cfg.tol
    assert np.all(est.residual < cfg.tol)


# ---- bad input ---------------------------------------------------------------------------------

def _ok():
    xs, ys, z, pts, contact = dent_case(60, n=9)
    return xs, ys, z, pts, contact


def test_contact_far_outside_the_roi_is_refused():
    xs, ys, z, pts, _ = _ok()
    far = TactileContact(tip_center=np.array([0.9, 0.2, 0.06]), force=np.array([0, 0, -0.5]),
                         tip_radius_m=0.01)
    with pytest.raises(InvalidArgumentError, match="`contact` must press inside the ROI"):
        estimate_beta(xs, ys, z, pts, far)


def test_contact_on_the_fixed_edge_is_refused():
    xs, ys, z, pts, _ = _ok()
    edge = TactileContact(tip_center=np.array([xs[0], ys[4], 0.06]),
                          force=np.array([0, 0, -0.5]), tip_radius_m=0.01)
    with pytest.raises(InvalidArgumentError, match="fixed edge"):
        estimate_beta(xs, ys, z, pts, edge)


@pytest.mark.parametrize("betas", [[-0.1], [1.0], [0.2, 1.5], [np.nan]])
def test_beta_outside_unit_interval_is_refused(betas):
    xs, ys, z, _, contact = _ok()
    g = _grid(xs, ys, z)
    with pytest.raises(InvalidArgumentError, match="`betas`"):
        simulate_poke(g.rest, g.masses, g.fixed, contact, betas, ShapeMatchingConfig())


def test_bad_shapes_and_values_are_refused():
    xs, ys, z, pts, contact = _ok()
    g = _grid(xs, ys, z)
    cases = [
        (lambda: estimate_beta(xs, ys, z[:-1], pts, contact), "`z`"),
        (lambda: estimate_beta(xs[::-1], ys, z, pts, contact), "`xs`"),
        (lambda: estimate_beta(xs[:2], ys, z[:, :2], pts, contact), "`xs`"),
        (lambda: estimate_beta(xs, ys, z, pts[:, :2], contact), "`deformed_points`"),
        (lambda: estimate_beta(xs, ys, z, np.full((3, 3), np.nan), contact), "`deformed_points`"),
        (lambda: estimate_beta(xs, ys, z, np.empty((0, 3)), contact), "`deformed_points`"),
        (lambda: estimate_beta(xs, ys, z, pts, "contact"), "`contact`"),
        (lambda: estimate_beta(xs, ys, z, pts, contact, config={"mode": "linear"}), "`config`"),
        (lambda: simulate_poke(g.rest, -g.masses, g.fixed, contact, [0.1]), "`masses`"),
        (lambda: simulate_poke(g.rest, g.masses, g.fixed.astype(int), contact, [0.1]), "`fixed`"),
        (lambda: simulate_poke(g.rest[:2], g.masses, g.fixed, contact, [0.1]), "`rest`"),
        (lambda: shape_matching_goals(g.rest, g.rest[None, None], [0.1]), "`current`"),
        (lambda: shape_matching_goals(g.rest[..., :2], g.rest[None], [0.1]), "`rest`"),
    ]
    for call, name in cases:
        with pytest.raises(InvalidArgumentError, match=name):
            call()


@pytest.mark.parametrize("kwargs, name", [
    ({"mode": "affine"}, "`mode`"), ({"contact": "pin"}, "`contact`"),
    ({"cluster_size": 1}, "`cluster_size`"), ({"n_beta": 1}, "`n_beta`"),
    ({"beta_resolution": 0.0}, "`beta_resolution`"), ({"tol": 0.0}, "`tol`"),
    ({"max_iter": 0}, "`max_iter`"), ({"regularization": 1.0}, "`regularization`"),
    ({"reference_modulus_pa": -1.0}, "`reference_modulus_pa`"),
    ({"poisson_ratio": 0.6}, "`poisson_ratio`"),
    ({"error_tolerance_m": 0.0}, "`error_tolerance_m`"),
    ({"layers": -1}, "`layers`"), ({"layer_growth": 0.5}, "`layer_growth`"),
    ({"refine": 1}, "`refine`"), ({"sweep_tol": 1e-7}, "`sweep_tol`"),
])
def test_bad_config_is_refused(kwargs, name):
    from deformap.errors import InvalidArgumentError

    with pytest.raises(InvalidArgumentError, match=name):
        ShapeMatchingConfig(**kwargs)


@pytest.mark.parametrize("beta", [0.0, 0.5, 0.95])
def test_banded_step_solve_inverts_the_cluster_operator(rng, beta):
    # K_β x = x − M⁻¹ Σ_c (W_c + β Π_c) x on the free particles, applied cluster by cluster
    from deformap.msm._clusters import Clusters
    from deformap.msm._linsys import StepMatrices, _SparseFallback
    from deformap.msm._simulate import _body

    xs, ys, z, _, _ = dent_case(60, n=9)
    g = _grid(xs, ys, z)
    body, body_m, body_fixed, window = _body(g.rest, g.masses, g.fixed, g.spacing_m,
                                             ShapeMatchingConfig())
    cl = Clusters(body, body_m, window, "quadratic", 1e-3)
    sm = StepMatrices(cl, body_fixed)
    rhs = rng.normal(size=(len(sm.free), 3))
    x = sm.solve(beta, rhs)
    full = np.zeros((body_fixed.size, 3))
    full[sm.free] = x
    xc = cl.gather(full.reshape(1, *body_fixed.shape, 3))[0]
    t = np.einsum("cj,cjd->cd", cl.w, xc)
    per = t[:, None, :] + beta * (cl.hat @ xc)
    mapped = (cl.scatter(per[None])[0] / cl.count[..., None]).reshape(-1, 3)
    np.testing.assert_allclose((full - mapped)[sm.free], rhs, rtol=0, atol=1e-10)
    band = sm.band(beta)
    sm._factors[float(beta)] = _SparseFallback(band, sm._bw)
    np.testing.assert_allclose(sm.solve(beta, rhs), x, rtol=0, atol=1e-10)


def test_refinement_finds_the_minimum_of_the_exhaustive_grid():
    # the coarse sweep + downhill walk must land where E is lowest on the whole 0.01 grid
    # around the sweep's minimum (computed here by brute force, one batched simulation)
    from scipy.spatial import cKDTree

    from deformap.msm._beta import matching_error

    xs, ys, z, pts, contact = dent_case(110, n=13)
    cfg = ShapeMatchingConfig()
    est = estimate_beta(xs, ys, z, pts, contact, cfg)
    coarse = est.betas[np.isclose(est.betas * cfg.n_beta, np.round(est.betas * cfg.n_beta))]
    lo = max(0.0, float(coarse[np.argmin(est.errors[np.isin(est.betas, coarse)])]) - 0.1)
    grid = np.round(np.arange(lo, min(lo + 0.2, 0.99) + 1e-9, 0.01), 10)
    g = _grid(xs, ys, z)
    sim = simulate_poke(g.rest, g.masses, g.fixed, contact, grid, cfg,
                        stiffness_n_per_m=est.stiffness_n_per_m)
    errors = matching_error(sim.positions, cKDTree(pts))
    assert est.beta == pytest.approx(grid[np.argmin(errors)])
    assert est.betas.size < cfg.n_beta + grid.size / 2  # far fewer solves than the grid


def test_shared_factorisation_gives_the_equilibrium_of_a_fresh_one():
    # a β stepping with a smaller β's factorisation (the splitting S_β = S_β′ − (β − β′) S₁)
    # must reach the equilibrium of its own factorisation, to the solver's tolerance
    from deformap.msm._simulate import PokeModel

    xs, ys, z, _, contact = dent_case(60, n=13)
    g = _grid(xs, ys, z)
    cfg = ShapeMatchingConfig()
    own = PokeModel(g.rest, g.masses, g.fixed, contact, cfg)
    shared = PokeModel(g.rest, g.masses, g.fixed, contact, cfg,
                       stiffness_n_per_m=own.stiffness)
    betas = np.array([0.3, 0.45, 0.6])
    sim_own, x_own = own.solve(betas, tol=1e-9)
    shared.solve(np.array([0.3]), tol=1e-9)
    sim_shared, x_shared = shared.solve(betas, tol=1e-9, max_split=0.5)
    assert sorted(shared.system._factors) == [0.3]  # 0.45 and 0.6 stepped with β′ = 0.3
    assert sorted(own.system._factors) == [0.0, 0.3, 0.45, 0.6]
    assert sim_shared.converged.all() and sim_own.converged.all()
    split = (betas - 0.3) / (1.0 - 0.3)  # a split step stops at tol (1 − ρ)
    assert np.all(sim_shared.residual < 1e-9 * (1.0 - split))
    dent = np.abs(x_own - own.clusters.rest[None]).max()
    np.testing.assert_allclose(x_shared, x_own, rtol=0, atol=1e-7 * dent)


def _step_matrices_9x9():
    """The force protocol's step matrices of a 9×9 ROI on a 60 N dent (quadratic, 3×3)."""
    from deformap.msm._clusters import Clusters
    from deformap.msm._linsys import StepMatrices
    from deformap.msm._simulate import _body

    xs, ys, z, _, _ = dent_case(60, n=9)
    g = _grid(xs, ys, z)
    body, body_m, body_fixed, window = _body(g.rest, g.masses, g.fixed, g.spacing_m,
                                             ShapeMatchingConfig())
    return StepMatrices(Clusters(body, body_m, window, "quadratic", 1e-3), body_fixed)


def test_split_step_needs_a_smaller_factorised_beta_and_the_positions(rng):
    from deformap.errors import InvalidArgumentError

    sm = _step_matrices_9x9()
    assert sm.prepare(0.5, max_split=0.3) == 0.5  # nothing factorised below
    assert sm.prepare(0.6, max_split=0.3) == 0.5  # (0.6 − 0.5) / 0.5 = 0.2
    assert sm.prepare(0.9, max_split=0.3) == 0.9  # (0.9 − 0.5) / 0.5 = 0.8
    assert sm.prepare(0.95, max_split=0.0) == 0.95
    rhs = rng.normal(size=(len(sm.free), 3))
    with pytest.raises(InvalidArgumentError, match="split"):
        sm.solve(0.6, rhs, factor_beta=0.5)
    with pytest.raises(InvalidArgumentError, match="split"):
        sm.solve(0.5, rhs, factor_beta=0.6, x=rhs)
    # one split step from the exact solution returns it
    x = sm.solve(0.6, rhs)
    np.testing.assert_allclose(sm.solve(0.6, rhs, factor_beta=0.5, x=x), x, rtol=0, atol=1e-10)


def test_bounded_factorisations_reuse_arrays_and_refactorise_what_was_dropped(rng):
    # a β search keeps a few factorisations (least recently used dropped, its array reused):
    # every solve must be the one of an unbounded cache, also for a β dropped and refactorised
    free = _step_matrices_9x9()
    bounded = _step_matrices_9x9()
    bounded.max_factors = 2
    rhs = rng.normal(size=(len(free.free), 3))
    for beta in (0.1, 0.5, 0.9, 0.1, 0.5):
        np.testing.assert_array_equal(bounded.solve(beta, rhs), free.solve(beta, rhs))
        assert len(bounded._factors) <= 2
    assert sorted(bounded._factors) == [0.1, 0.5] and sorted(free._factors) == [0.1, 0.5, 0.9]


@pytest.mark.parametrize("seed", range(20))
def test_refinement_search_finds_the_grid_minimum_of_any_unimodal_curve(seed):
    # the parabolic search only chooses which β to solve: on any unimodal E it must stop at the
    # argmin of the exhaustive grid (here E is a function, the "solves" are look-ups)
    from deformap.msm._beta import _refine

    r = np.random.default_rng(seed)
    centre, power = r.uniform(0.0, 0.99), r.uniform(1.0, 3.0)
    scale = (lambda b: b) if seed % 2 else (lambda b: 1.0 / (1.0 - b))  # symmetric or skewed

    def curve(b):
        return float(abs(scale(b) - scale(centre)) ** power)

    class _Fake:
        def __init__(self):
            self.errors, self.tols = {}, {}

        def solved(self, b, tol):
            return self.tols.get(b, np.inf) <= tol

        def run(self, betas, tol):
            for b in np.round(betas, 10):
                if not self.solved(float(b), tol):
                    self.errors[float(b)], self.tols[float(b)] = curve(float(b)), tol

    fake = _Fake()
    fake.run(np.arange(10) / 10, 1e-4)
    _refine(fake, 0.1, 0.01, 1e-6)  # type: ignore[arg-type]
    coarse = np.arange(10) / 10
    best = coarse[np.argmin([curve(b) for b in coarse])]
    grid = np.round(np.arange(-10, 11) * 0.01 + best, 10)
    grid = grid[(grid >= 0) & (grid < 1)]
    tight = [b for b in fake.errors if fake.tols[b] == 1e-6]
    found = min(tight, key=lambda b: (fake.errors[b], b))
    assert found == pytest.approx(grid[np.argmin([curve(b) for b in grid])])
    assert len(tight) <= 8


def test_failed_in_place_factorisation_falls_back_to_the_intact_matrix(rng):
    # the banded Cholesky overwrites its input; a matrix that is not positive definite
    # (β > 1 here, never reached by the estimate) must still be solved exactly by SuperLU
    import scipy.sparse as sp

    from deformap.msm._linsys import _SparseFallback

    sm = _step_matrices_9x9()
    rhs = rng.normal(size=(len(sm.free), 3))
    x = sm.solve(1.5, rhs)
    assert isinstance(sm._factors[1.5], _SparseFallback)
    band, bw = sm.band(1.5), sm._bw
    n = band.shape[1]
    upper = sp.diags([band[bw - k, k:] for k in range(bw + 1)], list(range(bw + 1)), shape=(n, n))
    full = (upper + sp.triu(upper, k=1).T).tocsr()
    np.testing.assert_allclose(full @ x[sm._perm], (sm._scale[:, None] * rhs)[sm._perm],
                               rtol=0, atol=1e-10)


def test_beta_hat_skips_loose_and_unconverged_beta() -> None:
    from deformap.msm._beta import _best_index

    errors = np.array([3.0, 1.0, 2.0, 2.5, 0.5])
    compared = np.array([True, True, True, True, False])  # the last was only swept loosely
    converged = np.array([True, False, True, True, True])  # the lowest compared one stalled
    assert _best_index(errors, compared, converged) == 2
    assert _best_index(errors, compared, np.ones(5, dtype=bool)) == 1
    # none converged: the lowest compared one, and the estimate reports all_converged False
    assert _best_index(errors, compared, np.zeros(5, dtype=bool)) == 1
