"""The contact models a force–travel record is compared against (:mod:`deformap.stiffness`,
Contact models): each model's own record and dent give it the largest weight and E within 2σ; a
record between two models gives a σ that covers both; E stays the bonded layer's and the weights
move only σ."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.mechanics import (
    foundation_indentation,
    foundation_surface_deflection,
    hertz_surface_deflection,
    layer_surface_deflection,
)
from deformap.stiffness import (
    CONTACT_MODELS,
    ContactModelFit,
    DentSamples,
    StiffnessConfig,
    estimate_stiffness,
)
from deformap.stiffness._tables import contact_table

R = 0.01  # the tip's radius [m]
H = 0.05  # the layer's thickness [m]
E = 2e4  # the modulus the records are made with [Pa]
F_C = 0.6  # the commanded force [N]
CAMERA_NOISE = 5e-4  # per cloud point [m]: a sensor at close range
KNOWN = StiffnessConfig(poisson_ratio_std=0.0, contact_models=CONTACT_MODELS)


def _record(model: str, rng: np.random.Generator, n: int = 9, thickness: float = H,
            ) -> tuple[np.ndarray, np.ndarray]:
    """``model``'s press from 0.02 N to ``F_C`` with the issue's sensor noise."""
    table = contact_table(model, R, thickness, 0.33)
    levels = np.linspace(0.02, F_C, n)
    depth = table.depth_at(levels / E)
    encoder = rng.normal(0.0, 5e-5, n)
    force = levels + rng.normal(0.0, 1.0, n) * (0.01 * levels + 0.005)
    return depth - depth[0] + encoder - encoder[0], force


def _dent(model: str, rng: np.random.Generator, thickness: float = H) -> DentSamples:
    """The camera's points about ``model``'s dent at ``F_C``: a 2 mm grid to 5 cm, the tip's
    patch left out, each point with the camera's noise. Each model's own surface: the
    foundation's, the bonded layer's of its thickness, Hertz's half-space."""
    table = contact_table(model, R, thickness, 0.33)
    depth = float(table.depth_at(np.array([F_C / E]))[0])
    g = np.arange(-0.05, 0.0501, 0.002)
    xy = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    r = np.hypot(xy[:, 0], xy[:, 1])
    if model == "foundation":
        a = float(np.interp(depth, table.depth, table.contact_radius))
        sink = foundation_surface_deflection(r, a, R, thickness, 0.33)
    elif model == "bonded-layer":
        a = np.sqrt(R * depth)
        sink = layer_surface_deflection(r, depth, R, thickness, 0.33)
    else:
        a = np.sqrt(R * depth)
        sink = hertz_surface_deflection(r, 4.0 / 3.0 * np.sqrt(R) * depth**1.5, R, 1.0, 0.0)
    keep = r > 1.5 * a
    return DentSamples.of(xy[keep], sink[keep] + rng.normal(0.0, CAMERA_NOISE, int(keep.sum())),
                          0.01)


@pytest.mark.parametrize("model", CONTACT_MODELS)
def test_each_models_own_press_gives_it_the_largest_weight_and_e_within_2_sigma(model):
    # the bonded layer's and the half-space's dents share Hertz's shape outside the tip and
    # their records differ by the layer's few per cent: between the two elastic models the
    # evidence is a near-tie, so their joint weight is what the press must win
    elastic = {"bonded-layer", "half-space"}
    group = elastic if model in elastic else {model}
    hits = 0
    for seed in range(6):
        rng = np.random.default_rng(seed)
        travel, force = _record(model, rng)
        est = estimate_stiffness(travel, force, tip_radius_m=R, thickness_m=H,
                                 commanded_force_n=F_C, config=KNOWN, dent=_dent(model, rng))
        assert est.modulus_pa is not None and est.modulus_std_pa is not None
        assert {f.name for f in est.model_fits} == set(CONTACT_MODELS)
        own = next(f for f in est.model_fits if f.name == model)
        assert own.fits and abs(own.modulus_pa - E) <= 2.0 * own.modulus_std_pa
        won = sum(f.weight for f in est.model_fits if f.name in group) > 0.5
        hits += won and abs(est.modulus_pa - E) <= 2.0 * est.modulus_std_pa
    assert hits >= 5


def test_a_thin_bonded_layers_own_dent_gives_the_layer_its_weight():
    # on a 3 cm layer the base narrows the dent well inside Hertz's half-space surface, to nearly
    # the foundation's; drawn as the layer's own surface, the layer's press and dent give the
    # layer the larger weight and E within 2σ (docs/results.md, the contact models)
    config = StiffnessConfig(poisson_ratio_std=0.0)
    alone = StiffnessConfig(poisson_ratio_std=0.0, contact_models=("bonded-layer",))
    won = 0
    for seed in range(6):
        rng = np.random.default_rng(seed)
        travel, force = _record("bonded-layer", rng, thickness=0.03)
        dent = _dent("bonded-layer", rng, thickness=0.03)
        est = estimate_stiffness(travel, force, tip_radius_m=R, thickness_m=0.03,
                                 commanded_force_n=F_C, config=config, dent=dent)
        layer = estimate_stiffness(travel, force, tip_radius_m=R, thickness_m=0.03,
                                   commanded_force_n=F_C, config=alone)
        assert est.modulus_pa is not None and est.modulus_std_pa is not None
        assert layer.modulus_std_pa is not None
        assert est.modulus_pa == layer.modulus_pa  # the weights move σ only
        weight = next(f.weight for f in est.model_fits if f.name == "bonded-layer")
        won += weight > 0.5 and abs(est.modulus_pa - E) <= 2.0 * est.modulus_std_pa
    assert won >= 5


def test_a_record_between_two_models_gives_a_sigma_covering_both():
    # the force halfway (in log) between the layer's and the foundation's at each depth: the
    # record cannot tell them apart, so E is the layer's and its 2σ reaches the foundation's E
    layer, found = (contact_table(m, R, H, 0.33) for m in ("bonded-layer", "foundation"))
    depth = np.linspace(2e-4, 4e-3, 9)
    force = E * np.sqrt(layer.force_at(depth) * found.force_at(depth))
    est = estimate_stiffness(depth - depth[0], force, tip_radius_m=R, thickness_m=H,
                             config=KNOWN)
    assert est.modulus_pa is not None and est.modulus_std_pa is not None
    fits = {f.name: f for f in est.model_fits}
    low, high = sorted((fits["bonded-layer"].modulus_pa, fits["foundation"].modulus_pa))
    assert high > 1.2 * low  # the two models read this record differently
    assert est.modulus_pa == fits["bonded-layer"].modulus_pa
    assert 0.2 < fits["foundation"].weight < 0.8  # neither model is ruled out
    assert est.modulus_pa - 2 * est.modulus_std_pa <= min(f.modulus_pa for f in est.model_fits)
    assert est.modulus_pa + 2 * est.modulus_std_pa >= max(f.modulus_pa for f in est.model_fits)


def test_the_weights_move_smoothly_with_the_dent():
    # the same press seen with its dent blended from the layer's into the foundation's: the
    # foundation's weight rises from below to above one half; E stays the layer's while σ
    # widens toward the foundation's E, its 2σ reaching it once the foundation wins
    rng = np.random.default_rng(3)
    travel, force = _record("bonded-layer", rng)
    layer = _dent("bonded-layer", np.random.default_rng(4))
    found = _dent("foundation", np.random.default_rng(4))
    n = min(layer.sink_m.size, found.sink_m.size)
    moduli, stds, weights = [], [], []
    for s in np.linspace(0.0, 1.0, 21):
        sink = (1 - s) * layer.sink_m[:n] + s * found.sink_m[:n]
        est = estimate_stiffness(travel, force, tip_radius_m=R, thickness_m=H,
                                 commanded_force_n=F_C, config=KNOWN,
                                 dent=DentSamples.of(layer.offset_m[:n], sink, 0.01))
        assert est.modulus_pa is not None and est.modulus_std_pa is not None
        moduli.append(est.modulus_pa)
        stds.append(est.modulus_std_pa)
        weights.append(next(f.weight for f in est.model_fits if f.name == "foundation"))
    assert weights[0] < 0.5 < weights[-1]
    assert np.all(np.abs(np.diff(weights)) < 0.5)  # no jump from one model to the other
    assert np.ptp(moduli) == 0.0
    assert stds[-1] > 2.0 * stds[0]
    foundation_e = next(f.modulus_pa for f in est.model_fits if f.name == "foundation")
    assert foundation_e < 0.8 * moduli[0]  # the models read this press differently
    assert moduli[-1] - 2.0 * stds[-1] <= foundation_e


def test_a_dent_between_two_models_leaves_both_their_weight():
    # the dent halfway between the layer's surface and the foundation's: each point's evidence
    # favours one model or the other by the camera's noise alone, so the sum's difference is a
    # draw of mean zero whose scatter the points themselves show; a weight near 1 for either
    # model would claim a difference the press does not hold (pseudo-BMA+, module docstring)
    config = StiffnessConfig(poisson_ratio_std=0.0)
    layer, found = (contact_table(m, R, H, 0.33) for m in ("bonded-layer", "foundation"))
    depth = float(layer.depth_at(np.array([F_C / E]))[0])
    g = np.arange(-0.05, 0.0501, 0.002)
    xy = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    r = np.hypot(xy[:, 0], xy[:, 1])
    keep = r > 1.5 * np.sqrt(R * depth)
    a = float(np.interp(depth, found.depth, found.contact_radius))
    sink = 0.5 * (layer_surface_deflection(r[keep], depth, R, H, 0.33)
                  + foundation_surface_deflection(r[keep], a, R, H, 0.33))
    shared = 0
    for seed in range(12):
        rng = np.random.default_rng(seed)
        travel, force = _record("bonded-layer", rng)
        noisy = sink + rng.normal(0.0, CAMERA_NOISE, sink.size)
        est = estimate_stiffness(travel, force, tip_radius_m=R, thickness_m=H,
                                 commanded_force_n=F_C, config=config,
                                 dent=DentSamples.of(xy[keep], noisy, 0.01))
        weight = next(f.weight for f in est.model_fits if f.name == "foundation")
        shared += 0.1 < weight < 0.9
    assert shared >= 9  # the Akaike weights alone: 5 of 12


def test_the_foundation_model_is_winkler_without_shear_and_rises_with_contact():
    a = np.geomspace(1e-4, R, 50)
    depth, force = foundation_indentation(a, R, H, E, 0.33)
    assert np.all(np.diff(depth) > 0) and np.all(np.diff(force) > 0)
    # ν → 0.5 leaves no spring; a negative radius or one beyond the tip is refused by name
    with pytest.raises(InvalidArgumentError, match="poisson_ratio"):
        foundation_indentation(a, R, H, E, 0.5)
    with pytest.raises(InvalidArgumentError, match="contact_radius_m"):
        foundation_indentation(np.array([2 * R]), R, H, E, 0.33)
    # at a contact much wider than ℓ the shear ring is negligible: Winkler's F = π k R δ² with
    # k = M / h for the linear mode (the mode's decay is small on a thin layer)
    thin = 2e-3
    d, f = foundation_indentation(np.array([R]), R, thin, E, 0.33)
    m = E * 0.67 / (1.33 * 0.34)
    assert f[0] == pytest.approx(np.pi * m / thin * R * d[0] ** 2, rel=0.15)


def test_a_model_fit_record_refuses_bad_numbers_by_name():
    with pytest.raises(InvalidArgumentError, match="weight"):
        ContactModelFit(name="foundation", modulus_pa=1e4, modulus_std_pa=1e3, reduced_chi2=1.0,
                        p_value=0.5, weight=1.5)
    with pytest.raises(InvalidArgumentError, match="offset_m"):
        DentSamples.of(np.zeros((4, 3)), np.zeros(4), 0.01)
    with pytest.raises(InvalidArgumentError, match="sink_m"):
        DentSamples.of(np.zeros((4, 2)), np.zeros(3), 0.01)
