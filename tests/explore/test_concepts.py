"""Each concept of the mapper on its own: grid, β-field, target choice, regions, dent, one step."""

from __future__ import annotations

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.environment import Workspace
from deformap.errors import EnvironmentStateError
from deformap.explore import (
    BetaField,
    BetaFieldConfig,
    ExplorationConfig,
    MapGrid,
    Mapper,
    PokeSet,
    TouchGPConfig,
    map_regions,
    measure_press,
    poke_step,
)
from deformap.explore._dent import roi_grid
from deformap.explore._targets import choose_next
from deformap.testing import coarse_world, synthetic_poke

WORKSPACE = Workspace(lower=(0.0, 0.0), upper=(0.6, 0.4))


def _pokes(xy: list[tuple[float, float]], beta: list[float], std: float = 0.03) -> PokeSet:
    records = [synthetic_poke(p, b, std).record for p, b in zip(xy, beta, strict=True)]
    return PokeSet.of(records, noise_floor=0.03)


def test_the_grid_keeps_targets_half_a_roi_inside_and_stops_where_asked() -> None:
    config = ExplorationConfig()
    grid = MapGrid.build(WORKSPACE, config)
    assert grid.shape == (80, 120) and grid.cells_xy.shape == (80 * 120, 2)
    reach = grid.cells_xy[grid.target_mask]
    half = config.touch.roi_size_m / 2
    assert reach.min(axis=0) == pytest.approx([half + 0.0025, half + 0.0025])
    assert reach.max(axis=0) == pytest.approx([0.6 - half - 0.0025, 0.4 - half - 0.0025])
    assert grid.stop_mask.all()
    targets_only = MapGrid.build(WORKSPACE, ExplorationConfig(stop_region="targets"))
    assert np.array_equal(targets_only.stop_mask, targets_only.target_mask)


def test_the_beta_field_is_the_exact_gp_posterior() -> None:
    cfg = BetaFieldConfig()
    xs, ys = WORKSPACE.grid(0.02)
    prior = BetaField(_pokes([], []), xs, ys, cfg)
    assert np.isnan(prior.mean).all()
    assert prior.variance == pytest.approx(np.full((ys.size, xs.size), cfg.signal_std**2))
    pokes = _pokes([(0.3, 0.2), (0.1, 0.1)], [0.8, 0.4], std=0.05)
    field = BetaField(pokes, xs, ys, cfg)
    # RW2006 Eq. 2.24 written out here, with the paper's kernel σe² exp(−d²/σw²) about a
    # constant prior mean: the pokes' inverse-noise-variance weighted mean
    gx, gy = np.meshgrid(xs, ys)
    cells = np.column_stack([gx.ravel(), gy.ravel()])

    def k(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d2 = np.sum((a[:, None] - b[None]) ** 2, axis=-1)
        return cfg.signal_std**2 * np.exp(-d2 / cfg.length_scale_m**2)

    gram = k(pokes.xy, pokes.xy) + np.diag(pokes.noise**2)
    cross = k(cells, pokes.xy)
    w = 1 / pokes.noise**2
    m = np.sum(w * pokes.values) / np.sum(w)
    mean = m + cross @ np.linalg.solve(gram, pokes.values - m)
    var = cfg.signal_std**2 - np.sum(cross * np.linalg.solve(gram, cross.T).T, axis=1)
    np.testing.assert_allclose(field.mean.ravel(), mean, atol=1e-9)
    np.testing.assert_allclose(field.variance.ravel(), var, atol=1e-9)
    assert field.max_variance() == pytest.approx(var.max())


def test_max_variance_after_one_poke_goes_to_the_least_known_reachable_cell() -> None:
    config = ExplorationConfig(strategy="max-variance", field="beta")  # a β-field test
    grid = MapGrid.build(WORKSPACE, config)
    field = BetaField(_pokes([(0.3, 0.2)], [0.5]), grid.xs, grid.ys, config.beta_field)
    target = choose_next(grid, field, config, np.random.default_rng(0), boundary_owed=0)
    assert target is not None and target.purpose == "variance" and target.plan is None
    reach = grid.cells_xy[grid.target_mask]
    far = reach[np.argmax(np.linalg.norm(reach - [0.3, 0.2], axis=1))]
    assert np.linalg.norm(target.xy - [0.3, 0.2]) == pytest.approx(np.linalg.norm(far - [0.3, 0.2]))


def test_a_known_map_owes_no_target_unless_boundary_pokes_are() -> None:
    config = ExplorationConfig(threshold=0.5)  # the prior's 0.09 is already under it
    grid = MapGrid.build(WORKSPACE, config)
    xy = [(0.1, 0.1), (0.1, 0.3), (0.2, 0.2), (0.4, 0.1), (0.5, 0.3), (0.45, 0.2)]
    pokes = _pokes(xy, [0.85, 0.84, 0.86, 0.40, 0.41, 0.39], std=0.01)
    field = BetaField(pokes, grid.xs, grid.ys, config.beta_field)
    assert choose_next(grid, field, config, np.random.default_rng(0), boundary_owed=0) is None
    target = choose_next(grid, field, config, np.random.default_rng(0), boundary_owed=1)
    assert target is not None and target.purpose == "boundary"
    assert 0.2 < target.xy[0] < 0.4  # on the isopleth between the two materials


def test_regions_by_isopleth_and_by_nearest_poke() -> None:
    xy = [(0.1, 0.1), (0.1, 0.3), (0.2, 0.2), (0.4, 0.1), (0.5, 0.3), (0.45, 0.2)]
    pokes = _pokes(xy, [0.85, 0.84, 0.86, 0.40, 0.41, 0.39], std=0.01)
    config = ExplorationConfig()
    grid = MapGrid.build(WORKSPACE, config)
    field = BetaField(pokes, grid.xs, grid.ys, config.beta_field)
    by_level = map_regions(field.mean, pokes, grid.cells_xy, config, field.name)
    assert by_level.n_regions == 2 and by_level.poke_labels.tolist() == [1, 1, 1, 0, 0, 0]
    nearest = map_regions(field.mean, pokes, grid.cells_xy,
                          ExplorationConfig(region_labels="nearest"), field.name)
    # a cell right by each poke takes that poke's class
    for p, label in zip(xy, nearest.poke_labels, strict=True):
        at = np.argmin(np.sum((grid.cells_xy - p) ** 2, axis=1))
        assert nearest.labels.ravel()[at] == label


def test_one_press_is_measured_without_a_field() -> None:
    world = coarse_world("homogeneous-60", seed=0)
    config = ExplorationConfig()
    mapper = Mapper(world.workspace, config)
    surface = mapper.initialise(world.observe(), np.random.default_rng(0))
    obs = world.press(np.array([0.3, 0.2]), config.force_n)
    world.release()
    poke = measure_press(obs, 0, surface, config)
    r = poke.record
    assert 0.0 <= r.beta < 1.0 and r.beta_std > 0 and len(r.betas) == len(r.errors) > 2
    assert r.purpose is None and r.max_variance_after is None and r.timings.field_s is None
    assert poke.dent is not None
    xs, ys = roi_grid(obs.contact.contact_point[:2], config.touch.roi_size_m,
                      config.surface.grid_spacing_m)
    assert poke.dent.deformed_z.shape == poke.dent.rest_z.shape == (ys.size, xs.size)
    # the dent goes down under the tip
    centre = (ys.size // 2, xs.size // 2)
    assert poke.dent.deformed_z[centre] < poke.dent.rest_z[centre] - 1e-3


def test_a_step_releases_the_press_even_when_the_estimate_fails() -> None:
    world = coarse_world("homogeneous-60", seed=0)
    mapper = Mapper(world.workspace, ExplorationConfig())  # never initialised: cannot estimate
    released = []
    with pytest.raises(EnvironmentStateError, match="initialise"):
        poke_step(mapper, 0, lambda: world.press(np.array([0.3, 0.2]), 0.6),
                  finish=lambda: released.append(world.release()))
    assert len(released) == 1 and mapper.pokes == ()


def test_one_switch_says_where_beta_uncertainty_comes_from() -> None:
    with pytest.raises(SettingError, match=r"touch\.noise_samples.*at least 2.*camera-noise"):
        ExplorationConfig(touch=TouchGPConfig(noise_samples=0))
    with pytest.raises(SettingError, match=r"touch\.noise_samples.*must be 0.*shape-matching"):
        ExplorationConfig(beta_uncertainty="shape-matching")
    world = coarse_world("homogeneous-60", seed=0)
    config = ExplorationConfig(beta_uncertainty="shape-matching",
                               touch=TouchGPConfig(noise_samples=0))
    mapper = Mapper(world.workspace, config)
    surface = mapper.initialise(world.observe(), np.random.default_rng(0))
    obs = world.press(np.array([0.3, 0.2]), config.force_n)
    world.release()
    poke = measure_press(obs, 0, surface, config)
    # the shape matcher's own uncertainty (the tile bootstrap): no camera noise is measured
    assert poke.record.camera_noise_m is None
    assert poke.estimate is not None and poke.record.beta_std == poke.estimate.beta_std > 0


def test_a_press_with_a_force_travel_record_reads_stiffness_and_modulus() -> None:
    from deformap.environment import ForceTravel, PressObservation

    world = coarse_world("homogeneous-60", seed=0)
    config = ExplorationConfig()
    mapper = Mapper(world.workspace, config)
    surface = mapper.initialise(world.observe(), np.random.default_rng(0))
    obs = world.press(np.array([0.3, 0.2]), config.force_n)
    world.release()
    assert obs.force_travel is not None  # the simulated world records it
    poke = measure_press(obs, 0, surface, config)
    r = poke.record
    assert r.stiffness is not None and not r.stiffness.rigid and r.stiffness_error is None
    assert r.layer_thickness_m == pytest.approx(0.05, abs=0.003)  # the block's 5 cm
    true = world.ground_truth_modulus(np.array([0.3]), np.array([0.2]))[0, 0]
    assert r.stiffness.modulus_pa == pytest.approx(true, rel=0.5)  # coarse mesh: the scale
    assert r.timings.stiffness_s is not None
    # a record the estimator refuses leaves the poke to the camera, and says why
    ft = obs.force_travel
    # a travel zeroed 0.3 mm off contact: within what the protocol lets through (encoder noise
    # of a whole press), beyond what the fit's contact offset may absorb
    shifted = ForceTravel(travel_m=ft.travel_m + 3e-4, force_n=ft.force_n)
    odd = PressObservation(cloud=obs.cloud, contact=obs.contact, robot_points=obs.robot_points,
                           target_xy=obs.target_xy, force_n=obs.force_n, force_travel=shifted)
    fallback = measure_press(odd, 0, surface, config).record
    assert fallback.stiffness is None
    assert "must start at first contact" in (fallback.stiffness_error or "")
    # the read record anchors the tactile points; the refused one leaves them on the tip
    assert r.depth_anchored is True and fallback.depth_anchored is False
    assert r.indentation_m == pytest.approx(r.stiffness.depth_m)
    assert fallback.indentation_m is not None and fallback.indentation_m > 0


def test_the_modulus_does_not_depend_on_the_tips_absolute_height() -> None:
    # an arm's tip height is off by a millimetre or so; the record's travel is counted from
    # first contact, so E does not see it (nor β: tests/explore/test_dent_record.py)
    from deformap.environment import PressObservation, TactileContact

    world = coarse_world("homogeneous-60", seed=0)
    config = ExplorationConfig()
    mapper = Mapper(world.workspace, config)
    surface = mapper.initialise(world.observe(), np.random.default_rng(0))
    obs = world.press(np.array([0.3, 0.2]), config.force_n)
    world.release()
    moduli = []
    for dz in (0.0, -0.001, 0.001):
        c = obs.contact
        tip = TactileContact(tip_center=c.tip_center + np.array([0.0, 0.0, dz]), force=c.force,
                             tip_radius_m=c.tip_radius_m)
        shifted = PressObservation(cloud=obs.cloud, contact=tip, robot_points=obs.robot_points,
                                   target_xy=obs.target_xy, force_n=obs.force_n,
                                   force_travel=obs.force_travel)
        stiffness = measure_press(shifted, 0, surface, config).record.stiffness
        assert stiffness is not None and stiffness.modulus_pa is not None
        moduli.append(stiffness.modulus_pa)
    assert moduli[1] == moduli[0] == moduli[2]
