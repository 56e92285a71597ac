"""The β-field's nugget (:mod:`deformap.explore._nugget`): the scatter between places of one
material that the pokes' claimed σ does not explain, estimated per map from the pokes' classes."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore import (
    ExplorationConfig,
    Mapper,
    PokeSet,
    beta_noise_floor,
    field_settings,
    segment_regions,
)
from deformap.explore._config import BetaFieldConfig
from deformap.explore._nugget import beta_pokes, estimate_nugget, with_nugget
from deformap.explore._targets import expected_noise
from deformap.msm import ShapeMatchingConfig
from deformap.testing import synthetic_poke

CONFIG = ExplorationConfig(field="beta")
#: Five pokes of one foam that scatter 0.024 about their mean (the best split of them, 0.68 against
#: 0.72, is within the region test's smallest step, so they are one class)
ONE_FOAM = [0.70, 0.73, 0.67, 0.72, 0.69]


def _material(rng: np.random.Generator, n: int, beta: float, tau: float
              ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """``n`` pokes of one material of β ``beta``: each claims a σ of 0.004–0.012 (a camera's
    repeatability) and reads β plus its own noise plus a place-to-place scatter ``tau``."""
    std = rng.uniform(0.004, 0.012, n)
    return beta + rng.standard_normal(n) * np.hypot(std, tau), std


def _pokes(betas: np.ndarray, stds: np.ndarray, seed: int = 0) -> PokeSet:
    xy = np.random.default_rng(seed).uniform((0.0, 0.0), (0.6, 0.4), (betas.size, 2))
    return PokeSet(xy, betas, np.maximum(stds, beta_noise_floor(CONFIG)))


@pytest.mark.parametrize("tau", [0.01, 0.02, 0.05])
def test_a_known_nugget_is_recovered(tau: float) -> None:
    # 40 pokes of one material, twenty maps: the median estimate within 15 % of the scatter
    # added, every one within a factor of 2 (the camera's own σ is 0.004–0.012 beside it)
    rng = np.random.default_rng(1)
    found = []
    for _ in range(20):
        betas, stds = _material(rng, 40, 0.7, tau)
        found.append(estimate_nugget(betas, stds, np.zeros(40, dtype=np.int64)))
    assert np.median(found) == pytest.approx(tau, rel=0.15)
    assert tau / 2 < min(found) and max(found) < 2 * tau


def test_with_few_pokes_the_estimate_is_shrunk_not_lost() -> None:
    # six pokes (a map's few): the half-Cauchy prior pulls τ̂ down, but a scatter four times
    # the claimed σ still shows (median within 30 % below, never zero)
    rng = np.random.default_rng(2)
    found = [estimate_nugget(*_material(rng, 6, 0.7, 0.05), np.zeros(6, dtype=np.int64))
             for _ in range(50)]  # fmt: skip
    assert 0.035 < np.median(found) <= 0.05
    assert min(found) > 0.0


def test_without_place_to_place_scatter_the_estimate_stays_at_zero() -> None:
    rng = np.random.default_rng(3)
    found = []
    for n in (6, 12, 40):
        for _ in range(20):
            betas, stds = _material(rng, n, 0.7, 0.0)
            found.append(estimate_nugget(betas, stds, np.zeros(n, dtype=np.int64)))
    # mostly exactly zero (the prior's mode); nine in ten below the claimed σ's lower end, none
    # above its upper end
    assert np.mean(np.array(found) == 0.0) > 0.5
    assert np.quantile(found, 0.9) < 0.004
    assert max(found) < 0.012
    # so the noise the field takes is mostly the claimed σ: the nugget adds less than half of the
    # pokes' mean claimed variance
    for seed in range(10):
        betas, stds = _material(np.random.default_rng(seed), 12, 0.7, 0.0)
        pokes = with_nugget(_pokes(betas, stds), CONFIG)
        assert pokes.nugget**2 < 0.5 * np.mean(stds**2)


@pytest.mark.parametrize(("n", "tau"), [(20, 0.01), (20, 0.02), (4, 0.0), (4, 0.01)])
def test_the_step_between_two_materials_is_not_taken_for_scatter(n: int, tau: float) -> None:
    # two foams 0.12 apart in β (as 150 N and 60 N on the odds scale), n pokes each, ten maps
    rng = np.random.default_rng(5)
    found = []
    for seed in range(10):
        lower, s_lower = _material(rng, n, 0.72, tau)
        upper, s_upper = _material(rng, n, 0.84, tau)
        betas, stds = np.concatenate([lower, upper]), np.concatenate([s_lower, s_upper])
        # pooled into one class, the step would read as a scatter of about half of it
        assert estimate_nugget(betas, stds, np.zeros(betas.size, dtype=np.int64)) > 0.04
        pokes = with_nugget(_pokes(betas, stds, seed), CONFIG)
        assert np.allclose(pokes.noise, np.hypot(np.maximum(stds, beta_noise_floor(CONFIG)),
                                                 pokes.nugget))  # fmt: skip
        found.append(pokes.nugget)
    # within the region test's classes it is the scatter added (with 20 pokes a class; four leave
    # the prior to shrink it), never the step
    if n >= 20:
        assert np.median(found) == pytest.approx(tau, abs=0.003)
    assert np.median(found) <= tau + 0.003
    assert max(found) < tau + 0.015


def test_a_class_of_one_poke_tells_nothing() -> None:
    betas, stds = np.array([0.2, 0.5, 0.8]), np.full(3, 0.01)
    assert estimate_nugget(betas, stds, np.array([0, 1, 2])) == 0.0
    with pytest.raises(InvalidArgumentError, match="one class per poke"):
        estimate_nugget(betas, stds, np.array([0, 1]))
    with pytest.raises(InvalidArgumentError, match="positive"):
        estimate_nugget(betas, np.array([0.01, 0.0, 0.01]), np.zeros(3, dtype=np.int64))


def test_the_floor_is_the_beta_grids_quantisation_unless_set() -> None:
    assert CONFIG.beta_field.noise_floor is None
    assert beta_noise_floor(CONFIG) == pytest.approx(0.01 / np.sqrt(12.0))
    coarse = ExplorationConfig(field="beta",
                               shape_matching=ShapeMatchingConfig(beta_resolution=0.02))
    assert beta_noise_floor(coarse) == pytest.approx(0.02 / np.sqrt(12.0))
    assert field_settings(coarse).noise_floor == pytest.approx(0.02 / np.sqrt(12.0))
    explicit = ExplorationConfig(field="beta", beta_field=BetaFieldConfig(noise_floor=0.015))
    assert beta_noise_floor(explicit) == 0.015


def test_nugget_off_keeps_the_floor_alone() -> None:
    # the former behaviour: a floor, no nugget
    config = ExplorationConfig(field="beta",
                               beta_field=BetaFieldConfig(noise_floor=0.015, nugget="off"))
    records = [synthetic_poke((0.1 * i, 0.2), b, 0.005, index=i).record
               for i, b in enumerate(ONE_FOAM)]  # fmt: skip
    pokes = beta_pokes(records, config)
    assert pokes.nugget == 0.0 and pokes.noise.tolist() == [0.015] * 5
    # with the nugget the same pokes (scatter 0.024 about their mean against a claimed 0.005)
    # carry it
    found = beta_pokes(records, CONFIG)
    assert 0.015 < found.nugget < 0.024
    assert found.noise == pytest.approx(np.hypot(0.005, found.nugget))


def test_the_mapper_fits_the_beta_field_with_the_nugget_and_plans_with_it() -> None:
    mapper = Mapper(Workspace(lower=(0.0, 0.0), upper=(0.6, 0.4)), CONFIG)
    places = [(0.15, 0.1), (0.45, 0.1), (0.15, 0.3), (0.45, 0.3), (0.3, 0.2)]
    for i, (xy, b) in enumerate(zip(places, ONE_FOAM, strict=True)):
        mapper.add(synthetic_poke(xy, b, 0.005, index=i))
    pokes = mapper.beta_field.pokes
    assert pokes.nugget == beta_pokes([p.record for p in mapper.pokes], CONFIG).nugget > 0.015
    assert mapper.beta_field.gp is not None
    assert np.allclose(mapper.beta_field.gp.predict(pokes.xy[:1], return_std=True)[1] ** 2,
                       _posterior_var_at_first(pokes), rtol=1e-6)
    # a press far from every poke is expected to carry the nugget too
    far = expected_noise(np.array([[0.55, 0.38]]), pokes, CONFIG, CONFIG.field)
    assert far[0] == pytest.approx(np.hypot(beta_noise_floor(CONFIG), pokes.nugget))


def _posterior_var_at_first(pokes: PokeSet) -> float:
    """The exact GP posterior variance at the first poke with the pokes' noise (RW2006 2.26)."""
    d2 = np.sum((pokes.xy[:, None] - pokes.xy[None]) ** 2, axis=2)
    k = 0.3**2 * np.exp(-d2 / 0.2**2)
    gram = k + np.diag(pokes.noise**2)
    return float(k[0, 0] - k[0] @ np.linalg.solve(gram, k[:, 0]))


def test_a_class_the_region_test_could_not_examine_gives_no_scatter() -> None:
    # the stiffening-foam world's heterogeneous-110-150 map (seed 0): its first four pokes, two
    # on each foam. A pair is never split, so read as one material it would put the step between
    # the foams (0.74 against 0.64) into the nugget after the second poke, and the pairs the
    # four pokes split into would give 0.02, enough to merge the foams again
    betas = np.array([0.74, 0.64, 0.61, 0.68])
    stds = np.array([0.0149, 0.0236, 0.0348, 0.0153])
    pairs = np.array([1, 0, 0, 1])
    assert estimate_nugget(betas[:2], stds[:2], np.zeros(2, dtype=np.int64)) > 0.03
    assert estimate_nugget(betas, stds, pairs) > 0.015
    assert estimate_nugget(betas, stds, pairs, min_class_size=3) == 0.0
    assert with_nugget(_pokes(betas[:2], stds[:2]), CONFIG).nugget == 0.0
    four = with_nugget(_pokes(betas, stds), CONFIG)
    assert four.nugget == 0.0
    classes = segment_regions(np.zeros((1, 1)), betas, four.noise,
                              floor=beta_noise_floor(CONFIG)).poke_labels  # fmt: skip
    assert classes.tolist() == pairs.tolist()
