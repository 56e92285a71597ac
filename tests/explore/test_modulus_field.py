"""The modulus field over ln E (issue 13, item 3): each poke's value and noise, rigid pokes at
their detection bound, pokes without a record left out, the settings, and the map running on it."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore import (
    ExplorationConfig,
    MapGrid,
    Mapper,
    ModulusField,
    ModulusFieldConfig,
    PokeResult,
    field_settings,
    rigid_modulus_bound,
)
from deformap.explore._choice import unread_radius_m
from deformap.explore._modulus import modulus_reading
from deformap.explore._targets import BOUNDARY_SPACING_ROI
from deformap.stiffness import ContactModelFit, StiffnessEstimate
from deformap.testing import synthetic_poke

CONFIG = ModulusFieldConfig()
NU = 0.33
XS = np.linspace(0.0, 0.6, 31)
YS = np.linspace(0.0, 0.4, 21)


def _soft(modulus: float, rel_std: float = 0.03) -> StiffnessEstimate:
    return StiffnessEstimate(
        stiffness_n_per_m=500.0, stiffness_std_n_per_m=10.0, stiffness_lower_n_per_m=None,
        modulus_pa=modulus, modulus_std_pa=rel_std * modulus, contact_offset_m=0.0,
        depth_m=0.002, max_chi=0.3, reduced_chi2=1.0, rigid=False, n_samples=8)  # fmt: skip


def _rigid(lower: float = 2.0e4) -> StiffnessEstimate:
    return StiffnessEstimate(
        stiffness_n_per_m=None, stiffness_std_n_per_m=None, stiffness_lower_n_per_m=lower,
        modulus_pa=None, modulus_std_pa=None, contact_offset_m=None, depth_m=1e-5,
        max_chi=None, reduced_chi2=None, rigid=True, n_samples=8)  # fmt: skip


def _poke(xy: tuple[float, float], estimate: StiffnessEstimate | None, index: int = 0, *,
          error: str | None = None, thickness: float | None = 0.05) -> PokeResult:
    poke = synthetic_poke(xy, 0.5, index=index)
    record = dataclasses.replace(poke.record, stiffness=estimate, stiffness_error=error,
                                 layer_thickness_m=thickness)  # fmt: skip
    return PokeResult(record)


def _field(pokes: list[PokeResult]) -> ModulusField:
    return ModulusField.of_records([p.record for p in pokes], XS, YS, CONFIG, NU)


def test_the_field_is_over_ln_e_and_interpolates_the_pokes_within_their_noise() -> None:
    moduli = [5e3, 2e4, 8e4]
    places = [(0.1, 0.1), (0.3, 0.3), (0.5, 0.1)]
    pairs = enumerate(zip(places, moduli, strict=True))
    field = _field([_poke(xy, _soft(e), i) for i, (xy, e) in pairs])
    assert np.allclose(field.pokes.values, np.log(moduli))
    for (x, y), e in zip(places, moduli, strict=True):
        col, row = int(np.argmin(abs(XS - x))), int(np.argmin(abs(YS - y)))
        # within two of the poke's noise on the ln E axis (its 3 % raised to the 10 % floor)
        assert abs(field.mean[row, col] - np.log(e)) < 2 * CONFIG.noise_floor
        assert field.median_pa[row, col] == pytest.approx(e, rel=0.25)
        assert field.std[row, col] < CONFIG.noise_floor
    # far from every poke the std returns toward the prior's
    assert field.std.max() > 0.5 * CONFIG.signal_std


def test_a_pokes_relative_error_is_its_noise_raised_to_the_floor() -> None:
    field = _field([_poke((0.1, 0.1), _soft(1e4, 0.02), 0),
                    _poke((0.5, 0.3), _soft(1e4, 0.4), 1)])
    assert field.pokes.noise.tolist() == pytest.approx([CONFIG.noise_floor, 0.4])


def test_a_poke_enters_with_its_reference_models_sigma_not_the_models_spread() -> None:
    # the foundation listed first, as a report may hold it: the bonded layer is found by name
    fits = (ContactModelFit(name="foundation", modulus_pa=7e3, modulus_std_pa=400.0,
                            reduced_chi2=1.0, p_value=0.5, weight=0.6),
            ContactModelFit(name="bonded-layer", modulus_pa=1e4, modulus_std_pa=500.0,
                            reduced_chi2=1.1, p_value=0.4, weight=0.4))
    estimate = dataclasses.replace(_soft(1e4, 0.25), model_fits=fits)
    reading = modulus_reading(_poke((0.3, 0.2), estimate).record, CONFIG, NU)
    assert reading.log_std == pytest.approx(500.0 / 1e4)  # not the estimate's 0.25
    assert modulus_reading(_poke((0.3, 0.2), _soft(1e4, 0.25)).record, CONFIG,
                           NU).log_std == pytest.approx(0.25)  # no models: the estimate's σ


def test_a_rigid_poke_sits_at_its_detection_bound_not_at_a_huge_number() -> None:
    rigid = _poke((0.3, 0.2), _rigid(2.0e4), 0, thickness=None)
    reading = modulus_reading(rigid.record, CONFIG, NU)
    assert reading.rigid and reading.excluded is None
    assert reading.log_std == CONFIG.rigid_log_std
    # Hertz: F = 4/3 E/(1-ν²) √R δ^1.5 with δ = F / k_lower (0.6 N over 2·10⁴ N/m = 30 µm)
    depth = 0.6 / 2.0e4
    expected = 0.6 / (4 / 3 / (1 - NU**2) * np.sqrt(0.01) * depth**1.5)
    assert np.exp(reading.log_modulus) == pytest.approx(expected, rel=1e-9)
    assert 1e5 < expected < 1e9
    # on a bonded layer the same travel means a lower modulus (the layer is stiffer at unit E)
    on_layer = rigid_modulus_bound(_poke((0.3, 0.2), _rigid(2.0e4), thickness=0.01).record, NU)
    assert on_layer < expected
    # a stiffer record (a larger lower bound on k) gives a larger bound
    assert rigid_modulus_bound(_poke((0.3, 0.2), _rigid(4.0e4), thickness=None).record, NU) \
        > expected
    with pytest.raises(InvalidArgumentError, match="record"):
        rigid_modulus_bound(_poke((0.3, 0.2), _soft(1e4)).record, NU)


def test_pokes_without_a_usable_record_are_left_out_and_say_why() -> None:
    pokes = [_poke((0.1, 0.1), _soft(1e4), 0), _poke((0.3, 0.2), None, 1),
             _poke((0.5, 0.3), None, 2, error="`force_n` must rise"), _poke((0.5, 0.1), _rigid(), 3)]
    field = _field(pokes)
    assert field.pokes.index.tolist() == [0, 3]
    why = [r.excluded for r in field.readings]
    assert why[0] is None and why[3] is None
    assert "no force–travel record" in why[1]
    assert "`force_n` must rise" in why[2]
    assert [r.to_dict()["used"] for r in field.readings] == [True, False, False, True]


def test_without_a_modulus_the_field_is_its_prior() -> None:
    field = _field([_poke((0.1, 0.1), None)])
    assert not len(field.pokes)
    assert np.isnan(field.mean).all()
    assert np.allclose(field.variance, CONFIG.signal_std**2)


def test_settings_in_beta_units_are_the_same_fraction_of_the_modulus_prior() -> None:
    config = ExplorationConfig(field="modulus", threshold=0.06)
    beta, modulus = field_settings(config, "beta"), field_settings(config)
    assert modulus.name == "modulus" and beta.name == "beta"
    prior_beta = config.beta_field.signal_std**2
    prior_modulus = config.modulus_field.signal_std**2
    assert modulus.threshold / prior_modulus == pytest.approx(beta.threshold / prior_beta)
    assert modulus.min_step / config.modulus_field.signal_std == pytest.approx(
        beta.min_step / config.beta_field.signal_std)
    assert field_settings(ExplorationConfig()).name == "modulus"  # the default


@pytest.mark.parametrize("bad", [{"signal_std": 0.0}, {"length_scale_m": -0.1},
                                 {"noise_floor": 0.0}, {"rigid_log_std": -1.0}])
def test_bad_modulus_settings_are_refused_naming_the_field(bad: dict[str, float]) -> None:
    (name,) = bad
    with pytest.raises(SettingError, match=name):
        ModulusFieldConfig(**bad)


def test_an_unknown_field_is_refused() -> None:
    with pytest.raises(SettingError, match="field"):
        ExplorationConfig(field="hardness")  # type: ignore[arg-type]


def _mapper(field: str) -> Mapper:
    config = ExplorationConfig(field=field, max_pokes=6)  # type: ignore[arg-type]
    return Mapper(Workspace(), config)


def test_the_map_runs_on_the_modulus_field_when_asked() -> None:
    mapper = _mapper("modulus")
    soft, stiff = [(0.1, 0.1), (0.15, 0.3), (0.1, 0.2)], [(0.5, 0.1), (0.45, 0.3), (0.5, 0.2)]
    pokes = [_poke(xy, _soft(5e3 * (1 + 0.05 * i)), i) for i, xy in enumerate(soft)]
    pokes += [_poke(xy, _soft(5e4 * (1 + 0.05 * i)), 3 + i) for i, xy in enumerate(stiff)]
    for poke in pokes:  # every poke the same β: only the modulus tells the two halves apart
        mapper.add(poke)
    assert mapper.map_field is mapper.modulus_field
    assert mapper.threshold == field_settings(mapper.config).threshold
    assert mapper.max_variance() == mapper.modulus_field.max_variance(mapper.grid.stop_mask)
    regions = mapper.regions()
    assert regions.n_regions == 2
    assert regions.poke_labels.tolist() == [0, 0, 0, 1, 1, 1]  # ln E: the softest class first
    on_beta = _mapper("beta")
    for poke in pokes:
        on_beta.add(poke)
    assert on_beta.regions().n_regions == 1


def test_field_modulus_without_a_record_falls_back_to_beta_and_says_so() -> None:
    mapper = _mapper("modulus")
    mapper.add(_poke((0.3, 0.2), None))
    assert mapper.map_field_name == "beta" and mapper.map_field is mapper.beta_field
    assert mapper.field_fallback is not None
    assert re.match(r"`exploration.field` 'modulus' fell back to 'beta': poke 1 gave no modulus "
                    r"\(.*no force–travel record", mapper.field_fallback)
    assert mapper.threshold == field_settings(mapper.config, "beta").threshold == 0.06
    assert mapper.config.field == "modulus"  # the settings say what was asked for
    mapper.add(_poke((0.1, 0.1), None, 1))
    assert len(mapper.beta_field.pokes) == 2
    # a first poke with a modulus keeps the modulus field, a later one without is left out of it
    kept = _mapper("modulus")
    kept.add(_poke((0.3, 0.2), _soft(10e3)))
    kept.add(_poke((0.1, 0.1), None, 1))
    assert kept.map_field_name == "modulus" and kept.field_fallback is None
    assert len(kept.modulus_field.pokes) == 1 and len(kept.beta_field.pokes) == 2
    assert len(_mapper("beta").add(_poke((0.3, 0.2), None)).record.contact_xy) == 2


def test_a_first_poke_without_modulus_does_not_decide_the_run() -> None:
    mapper = _mapper("modulus")
    mapper.add(_poke((0.3, 0.2), None, 0, error="the record was refused"))
    assert mapper.map_field_name == "beta" and mapper.field_fallback is not None
    assert mapper.config.field == "modulus"  # what was asked for, never rewritten
    result = mapper.result("max_pokes", {})
    assert result.config.field == "modulus" and result.map_field_name == "beta"
    assert result.map_field is result.beta_field
    on_beta = mapper.beta_field  # fitted at the poke, as the map field then
    assert len(on_beta.pokes) == 1 and mapper.map_field is on_beta
    mapper.add(_poke((0.1, 0.1), _soft(5e3), 1))  # a modulus arrives: back on the modulus field
    assert mapper.map_field_name == "modulus" and mapper.field_fallback is None
    assert mapper.map_field is mapper.modulus_field
    # fitted again, lazily
    assert len(mapper.beta_field.pokes) == 2 and mapper.beta_field is not on_beta


def test_a_place_read_twice_in_vain_leaves_the_targets_and_the_stopping_rule() -> None:
    config = ExplorationConfig(field="modulus", max_pokes=12)
    mapper = Mapper(Workspace(), config)
    mapper.add(_poke((0.1, 0.1), _soft(5e3), 0))
    n = 1
    mapper.add(_poke((0.4, 0.2), None, n, error="too deep"))
    before = mapper.max_variance()
    mapper.add(_poke((0.42, 0.2), None, n + 1, error="too deep"))  # the same place again
    # the modulus field maps on; the place is out of the targets and the stopping rule
    assert mapper.map_field_name == "modulus" and mapper.field_fallback is None
    assert mapper.unread_places == [(0.4, 0.2), (0.42, 0.2)]  # about both presses
    radius = unread_radius_m(config)
    assert radius == BOUNDARY_SPACING_ROI * config.touch.roi_size_m
    grid = mapper.grid  # the map itself still covers every cell
    gone = ((np.hypot(*(grid.cells_xy - (0.4, 0.2)).T) <= radius)
            | (np.hypot(*(grid.cells_xy - (0.42, 0.2)).T) <= radius))
    choice = mapper.choice_grid
    assert gone.any() and not (choice.target_mask & gone).any()
    assert (choice.target_mask == grid.target_mask & ~gone).all()
    assert (choice.stop_mask == grid.stop_mask & ~gone).all()
    assert mapper.max_variance() == mapper.modulus_field.max_variance(choice.stop_mask)
    # (the field's length scale, 0.2 m, spreads the pokes around over the disc: here it is not
    # where the variance is largest, and the rule's value stays)
    assert mapper.max_variance() <= before == mapper.modulus_field.max_variance(grid.stop_mask)
    for seed in range(5):
        target = mapper.next_target(np.random.default_rng(seed))
        assert target is not None
        assert min(np.hypot(*(target.xy - xy)) for xy in [(0.4, 0.2), (0.42, 0.2)]) > radius
    mapper.add(_poke((0.5, 0.3), _soft(6e3), n + 2))
    assert mapper.map_field_name == "modulus"
    result = mapper.result("max_pokes", {})
    assert result.unread_places == ((0.4, 0.2), (0.42, 0.2)) and result.field_fallback is None
    assert (result.stop_cells == choice.stop_mask).all()
    assert result.max_variance == mapper.modulus_field.max_variance(choice.stop_mask)


def test_a_run_without_any_modulus_maps_on_beta_with_every_place() -> None:
    """A camera-only run maps on β, which reads the place: nothing is avoided."""
    mapper = Mapper(Workspace(), ExplorationConfig(field="modulus"))
    mapper.add(_poke((0.3, 0.2), None, 0, error="too deep"))
    mapper.add(_poke((0.305, 0.2), None, 1, error="too deep"))
    assert mapper.map_field_name == "beta" and mapper.unread_places == []
    assert (mapper.choice_grid.target_mask == mapper.grid.target_mask).all()
    mapper.add(_poke((0.1, 0.1), _soft(5e3), 2))  # a modulus: back on the modulus field
    assert mapper.map_field_name == "modulus" and mapper.field_fallback is None
    mapper.add(_poke((0.31, 0.2), None, 3, error="too deep"))  # the place again: now avoided
    assert mapper.map_field_name == "modulus" and len(mapper.unread_places) == 3


def test_going_to_beta_after_avoided_places_gives_the_targets_back() -> None:
    small = Workspace(lower=(0.0, 0.0), upper=(0.12, 0.06))
    mapper = Mapper(small, ExplorationConfig(field="modulus", max_pokes=8))
    mapper.add(_poke((0.03, 0.03), _soft(5e3), 0))
    mapper.add(_poke((0.09, 0.03), None, 1, error="too deep"))
    mapper.add(_poke((0.09, 0.03), None, 2, error="too deep"))
    assert mapper.map_field_name == "modulus" and len(mapper.unread_places) == 2
    assert mapper.choice_grid.target_mask.sum() < mapper.grid.target_mask.sum()
    mapper.add(_poke((0.04, 0.03), None, 3, error="too deep"))
    mapper.add(_poke((0.04, 0.03), None, 4, error="too deep"))  # no target would be left
    assert mapper.map_field_name == "beta"
    assert "no target would be left without it" in (mapper.field_fallback or "")
    assert (mapper.choice_grid.target_mask == mapper.grid.target_mask).all()
    assert (mapper.choice_grid.stop_mask == mapper.grid.stop_mask).all()


def test_a_grid_without_every_target_is_none_and_the_run_goes_to_beta() -> None:
    grid = MapGrid.build(Workspace(), ExplorationConfig())
    with pytest.raises(InvalidArgumentError, match=r"`centres` must be an \(n, 2\) array"):
        grid.without(np.array([0.3, 0.2, 0.1]), 0.05)
    with pytest.raises(InvalidArgumentError, match="`radius_m` must be a positive number"):
        grid.without(np.array([[0.3, 0.2]]), -0.05)
    assert grid.without(np.array([[0.3, 0.2]]), 10.0) is None  # the whole workspace gone
    kept = grid.without(np.zeros((0, 2)), 0.05)
    assert kept is not None and (kept.target_mask == grid.target_mask).all()
    assert len(kept.plan_candidates) == len(grid.plan_candidates)
    part = grid.without(np.array([[0.3, 0.2]]), 0.05)
    assert part is not None and len(part.plan_candidates) < len(grid.plan_candidates)
    assert (np.hypot(*(part.plan_candidates - (0.3, 0.2)).T) > 0.05).all()
    # a tiny workspace whose only place cannot be read: nothing left, so β for good
    small = Workspace(lower=(0.0, 0.0), upper=(0.06, 0.06))  # every target within the disc
    mapper = Mapper(small, ExplorationConfig(field="modulus", max_pokes=4))
    mapper.add(_poke((0.03, 0.03), _soft(5e3), 0))
    mapper.add(_poke((0.03, 0.03), None, 1, error="too deep"))
    mapper.add(_poke((0.031, 0.03), None, 2, error="too deep"))
    assert mapper.map_field_name == "beta" and mapper.unread_places == []
    assert mapper.field_fallback is not None
    assert "no target would be left without it" in mapper.field_fallback


def test_the_planner_is_told_the_pokes_made_not_the_pokes_in_the_field() -> None:
    from deformap.explore._targets import choose_next

    mapper = Mapper(Workspace(), ExplorationConfig(field="modulus", max_pokes=4))
    mapper.add(_poke((0.3, 0.2), _soft(5e3), 0))
    mapper.add(_poke((0.1, 0.1), None, 1, error="left out"))
    mapper.add(_poke((0.5, 0.3), None, 2, error="left out"))
    assert len(mapper.map_field.pokes) == 1 and mapper.map_field_name == "modulus"
    target = mapper.next_target(np.random.default_rng(0))
    assert target is not None and target.plan is not None
    assert len(target.plan.targets) <= 1  # 4 pokes in all, 3 made: one left to plan
    counted_from_field = choose_next(mapper.grid, mapper.map_field, mapper.config,
                                     np.random.default_rng(0), boundary_owed=0)
    assert counted_from_field is not None and counted_from_field.plan is not None
    assert len(counted_from_field.plan.targets) > 1  # what it planned before


def test_under_the_modulus_field_the_beta_field_is_fitted_on_first_use_and_is_the_same(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from deformap.explore import _mapper as mapper_module

    fits = []
    real = mapper_module.beta_pokes
    monkeypatch.setattr(mapper_module, "beta_pokes", lambda *a: fits.append(1) or real(*a))
    mapper = _mapper("modulus")
    xys = [(0.1, 0.1), (0.15, 0.3), (0.5, 0.1), (0.45, 0.3), (0.3, 0.2)]
    for i, xy in enumerate(xys):
        mapper.add(_poke(xy, _soft(5e3 * (1 + 2 * (xy[0] > 0.3))), i))
    assert fits == []  # five pokes on the modulus field, no β-field fitted
    lazy = mapper.beta_field
    assert len(fits) == 1 and mapper.beta_field is lazy  # fitted once, then kept
    on_beta = _mapper("beta")  # fitted eagerly at every poke, as the β map needs it
    for i, xy in enumerate(xys):
        on_beta.add(_poke(xy, _soft(5e3 * (1 + 2 * (xy[0] > 0.3))), i))
    assert len(fits) == 1 + len(xys)
    np.testing.assert_array_equal(lazy.mean, on_beta.beta_field.mean)
    np.testing.assert_array_equal(lazy.pokes.noise, on_beta.beta_field.pokes.noise)
    mapper.add(_poke((0.2, 0.25), _soft(5e3), 5))  # a new poke: the next use fits it again
    assert len(mapper.beta_field.pokes) == 6 and len(fits) == 2 + len(xys)


def test_a_resumed_run_finds_the_same_unread_places_from_its_journalled_records() -> None:
    """What ``explore(done=…)`` does with a killed run's journal: each record read back from its
    JSON line is added again in order, and the unread places follow from them alone."""
    import json

    from deformap.explore import PokeRecord

    config = ExplorationConfig(field="modulus", max_pokes=12)
    first = Mapper(Workspace(), config)
    for poke in (_poke((0.1, 0.1), _soft(5e3), 0), _poke((0.4, 0.2), None, 1, error="too deep"),
                 _poke((0.42, 0.2), None, 2, error="too deep"), _poke((0.5, 0.3), _soft(6e3), 3)):
        first.add(poke)
    assert len(first.unread_places) == 2
    resumed = Mapper(Workspace(), config)
    for added in first.pokes:
        line = json.loads(json.dumps(added.record.to_dict()))
        resumed.add(PokeResult(PokeRecord.from_dict(line)))
    assert resumed.unread_places == first.unread_places
    assert (resumed.choice_grid.target_mask == first.choice_grid.target_mask).all()
    assert resumed.max_variance() == first.max_variance()
    assert resumed.map_field_name == "modulus"


def test_the_field_choice_is_a_pure_function_of_the_pokes_and_the_choice_before() -> None:
    from deformap.explore._choice import FieldChoice, choose_map_field

    config = ExplorationConfig(field="modulus", max_pokes=12)
    grid = MapGrid.build(Workspace(), config)
    radius = unread_radius_m(config)
    records = [_poke((0.1, 0.1), _soft(5e3), 0).record,
               _poke((0.4, 0.2), None, 1, error="too deep").record,
               _poke((0.42, 0.2), None, 2, error="too deep").record]
    choice = FieldChoice(name="modulus", grid=grid)
    for n in range(1, len(records) + 1):
        modulus = ModulusField.of_records(records[:n], grid.xs, grid.ys, config.modulus_field,
                                          config.stiffness.poisson_ratio)
        before = choice
        choice = choose_map_field(before, "modulus", records[:n], modulus, grid, radius)
        again = choose_map_field(before, "modulus", records[:n], modulus, grid, radius)
        assert (again.name, again.fallback, again.unread_places) == (
            choice.name, choice.fallback, choice.unread_places)
    assert choice.name == "modulus" and choice.fallback is None
    assert choice.unread_places == ((0.4, 0.2), (0.42, 0.2))
    assert choice.grid.target_mask.sum() < grid.target_mask.sum()
    # under field: beta the choice is the β-field on the whole grid, whatever the pokes
    beta = choose_map_field(choice, "beta", records, modulus, grid, radius)
    assert beta.name == "beta" and beta.grid is grid and beta.unread_places == ()
    assert config.field == "modulus"
