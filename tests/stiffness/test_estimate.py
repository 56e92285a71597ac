"""Stiffness and Young's modulus from a force–travel record, on synthetic records with the issue's
sensor noise (encoders 0.05 mm, force 1 % + 5 mN): accuracy and honest σ on the contact model,
rigid detection, monotonicity, the error on physics that is not the model (measured, with a stated
bound), and bad input."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy.optimize import brentq

from deformap._validation import SettingError
from deformap.errors import InvalidArgumentError
from deformap.mechanics import hertz_indentation, layer_correction, layer_indentation_force
from deformap.stiffness import LAYER_MODEL, StiffnessConfig, StiffnessEstimate, estimate_stiffness

R = 0.01  # the probe's tip radius, 1 cm
NU = 0.33  # the estimator's default Poisson ratio: these records are made with the same one
TRAVEL_SIGMA = 5e-5
FORCE_REL, FORCE_ABS = 0.01, 0.005
CONTACT_THRESHOLD_N = 0.02  # four times the force noise at zero force

Law = Callable[[float], float]


def _depth_for(force: float, law: Law) -> float:
    high = 1e-3
    while law(high) < force:
        high *= 2.0
    return float(brentq(lambda d: law(d) - force, 0.0, high, xtol=1e-14))


def synthetic_record(rng: np.random.Generator, law: Law, force_n: float, n: int,
                     ) -> tuple[np.ndarray, np.ndarray]:
    """A press from the contact threshold to ``force_n`` at ``n`` evenly spaced load levels.

    The travel's zero is the (noisy) encoder reading at first contact, where the tip is already
    sunk by the threshold's depth; each reading then carries its own encoder and force noise.
    """
    levels = np.linspace(CONTACT_THRESHOLD_N, force_n, n)
    depth = np.array([_depth_for(f, law) for f in levels])
    encoder = rng.normal(0.0, TRAVEL_SIGMA, n)
    travel = depth - depth[0] + encoder - encoder[0]
    force = levels + rng.normal(0.0, 1.0, n) * (FORCE_REL * levels + FORCE_ABS)
    return travel, force


def in_range(travel: np.ndarray, thickness: float) -> bool:
    """Whether a press stays in the range these accuracy checks hold for: indentation at most
    half the layer and ``χ`` at most 1 (beyond them the record is refused, tested on its own
    below), and at most three quarters of the tip's radius (Hertz's paraboloid for the sphere)."""
    depth = float(travel.max())
    return (depth <= 0.45 * thickness and depth <= 0.75 * R
            and np.sqrt(R * depth) / thickness <= 0.95)


def layer_law(modulus: float, thickness: float) -> Law:
    return lambda d: float(layer_indentation_force(d, R, thickness, modulus, NU))


def half_space_law(modulus: float) -> Law:
    e_star = modulus / (1.0 - NU**2)
    return lambda d: 4.0 / 3.0 * e_star * np.sqrt(R) * d**1.5


def _draw(rng: np.random.Generator) -> tuple[float, float, float, int]:
    """E log-uniform on 2–200 kPa, h uniform on 2–10 cm, F log-uniform on 0.3–3 N, 8–20 samples."""
    modulus = float(np.exp(rng.uniform(np.log(2e3), np.log(2e5))))
    thickness = float(rng.uniform(0.02, 0.10))
    force = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
    return modulus, thickness, force, int(rng.integers(8, 21))


@pytest.fixture(scope="module")
def layer_estimates() -> list[tuple[float, StiffnessEstimate]]:
    rng = np.random.default_rng(20261123)
    out = []
    while len(out) < 150:
        modulus, thickness, force, n = _draw(rng)
        travel, measured = synthetic_record(rng, layer_law(modulus, thickness), force, n)
        if not in_range(travel, thickness):
            continue
        out.append((modulus, estimate_stiffness(travel, measured, tip_radius_m=R,
                                                thickness_m=thickness, config=NU_KNOWN)))
    return out


#: The records below are made with the estimator's own ν: its uncertainty is left out, so that
#: σ is checked against the sensor noise alone.
# the records below are made with the bonded layer's law: these tests read them with that model
# alone (the comparison of models is tests/stiffness/test_models.py)
LAYER_ONLY = StiffnessConfig(contact_models=("bonded-layer",))
NU_KNOWN = StiffnessConfig(poisson_ratio_std=0.0, contact_models=("bonded-layer",))


def test_modulus_on_the_contact_model_is_accurate(layer_estimates):
    # measured: median |relative error| 2.5 % over this draw (90th percentile 8.6 %)
    assert not any(est.rigid for _, est in layer_estimates)
    errors = np.array([est.modulus_pa / e - 1.0 for e, est in layer_estimates])
    assert np.median(np.abs(errors)) <= 0.05
    assert abs(np.median(errors)) <= 0.02  # no bias beyond the noise of the median


def test_claimed_sigma_is_honest(layer_estimates):
    # |E error| ≤ 2σ in at least 90 % of the records (measured 95 % here),
    # and the claim is not inflated either: within 1σ about two thirds of the time (71 %)
    z = np.array([(est.modulus_pa - e) / est.modulus_std_pa for e, est in layer_estimates])
    assert np.mean(np.abs(z) <= 2.0) >= 0.90
    assert 0.55 <= np.mean(np.abs(z) <= 1.0) <= 0.85


def test_stiffness_is_the_model_slope_at_the_commanded_force(layer_estimates):
    for _, est in layer_estimates[:20]:
        assert est.stiffness_n_per_m is not None and est.stiffness_std_n_per_m is not None
        assert est.modulus_pa is not None and est.modulus_std_pa is not None
        # under Hertz k ∝ E^(2/3) at a fixed force: σ_k / k = (2/3) σ_E / E when χ → 0
        ratio = (est.stiffness_std_n_per_m / est.stiffness_n_per_m) / (
            est.modulus_std_pa / est.modulus_pa)
        assert 0.5 < ratio < 1.0
        assert est.model == LAYER_MODEL and est.stiffness_lower_n_per_m is None


def test_stiffness_matches_the_true_slope():
    rng = np.random.default_rng(5)
    modulus, thickness, force = 2e4, 0.05, 1.0
    travel, measured = synthetic_record(rng, layer_law(modulus, thickness), force, 12)
    est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness,
                             commanded_force_n=force)
    depth = _depth_for(force, layer_law(modulus, thickness))
    step = 1e-7
    true_k = (layer_law(modulus, thickness)(depth + step)
              - layer_law(modulus, thickness)(depth - step)) / (2 * step)
    assert est.stiffness_n_per_m == pytest.approx(true_k, abs=3 * est.stiffness_std_n_per_m)
    assert est.depth_m == pytest.approx(depth, rel=0.05)
    assert est.max_chi == pytest.approx(np.sqrt(R * est.depth_m) / thickness)
    assert est.n_samples == 12 and est.reduced_chi2 is not None


def test_a_tip_buried_deeper_than_its_diameter_is_refused_not_read():
    # a soft, thick layer: 25 mm under a 10 mm tip is within χ ≤ 1 and half the layer, but the
    # sphere is buried and the stick holding it would press the foam: no sphere model holds
    rng = np.random.default_rng(5)
    thickness = 0.10
    travel, measured = synthetic_record(rng, layer_law(1.5e3, thickness), 1.0, 10)
    assert 2 * R < travel.max() < 0.45 * thickness
    assert np.sqrt(R * travel.max()) / thickness < 1.0
    with pytest.raises(InvalidArgumentError, match="more than its 20 mm diameter"):
        estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness,
                           commanded_force_n=1.0)
    # the same layer pressed to about the tip's radius is read (the contact radius is then
    # near the sphere's, where Hertz's paraboloid still describes it to a few per cent)
    travel, measured = synthetic_record(rng, layer_law(1.5e3, thickness), 0.3, 10)
    assert 0.5 * R < travel.max() < 2 * R
    est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness,
                             commanded_force_n=0.3)
    assert est.modulus_pa == pytest.approx(1.5e3, rel=0.25)


def test_a_press_nearly_through_the_layer_is_refused_not_read():
    # a straight line to 19 mm on a 2 cm layer: the tip is nearly on the table and no
    # bonded-layer curve explains it; a modulus read from it would be the fit's lower bound
    travel = np.linspace(0.0, 0.019, 10)
    with pytest.raises(InvalidArgumentError, match="leave the contact model's range"):
        estimate_stiffness(travel, np.linspace(0.02, 3.0, 10), tip_radius_m=R, thickness_m=0.02)
    # a soft layer pressed past half its thickness (but not past the tip's radius) is refused too
    rng = np.random.default_rng(3)
    travel, measured = synthetic_record(rng, layer_law(2e3, 0.015), 0.5, 10)
    assert 0.5 * 0.015 < travel.max() < 0.8 * R
    with pytest.raises(InvalidArgumentError, match="at most 50%"):
        estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.015)


def test_three_samples_are_enough():
    rng = np.random.default_rng(29)
    travel, measured = synthetic_record(rng, layer_law(2e4, 0.05), 2.0, 3)
    est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.05)
    assert est.n_samples == 3 and not est.rigid
    assert est.modulus_std_pa is not None and np.isfinite(est.modulus_std_pa)
    assert est.modulus_std_pa > 0


def test_poisson_ratio_is_the_callers_assumption():
    rng = np.random.default_rng(31)
    travel, measured = synthetic_record(rng, layer_law(2e4, 0.05), 1.0, 10)
    default = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.05)
    other = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.05,
                               config=StiffnessConfig(poisson_ratio=0.45))
    assert StiffnessConfig().poisson_ratio == NU
    assert default.modulus_pa is not None and other.modulus_pa is not None
    assert other.modulus_pa < default.modulus_pa  # E ∝ 1 − ν² at a fixed E*


def test_modulus_and_stiffness_are_monotone_in_the_true_modulus():
    moduli = 2e3 * 1.5 ** np.arange(12)  # 2 kPa to 173 kPa
    for force, thickness in [(0.3, 0.03), (1.0, 0.08)]:
        # from the softest modulus the press stays in the model's range at
        kept = moduli[[in_range(synthetic_record(np.random.default_rng(7),
                                                 layer_law(m, thickness), force, 8)[0],
                                thickness) for m in moduli]]
        assert kept.size >= 8
        es, ks = [], []
        for modulus in kept:
            rng = np.random.default_rng(7)  # the same noise draws for every modulus
            travel, measured = synthetic_record(rng, layer_law(modulus, thickness), force, 8)
            est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness)
            es.append(est.modulus_pa)
            ks.append(est.stiffness_n_per_m)
        assert np.all(np.diff(es) > 0) and np.all(np.diff(ks) > 0)


def test_noise_only_record_is_rigid_with_a_lower_bound():
    rng = np.random.default_rng(11)
    for _ in range(50):
        n = int(rng.integers(8, 21))
        force = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
        levels = np.linspace(CONTACT_THRESHOLD_N, force, n)
        encoder = rng.normal(0.0, TRAVEL_SIGMA, n)
        measured = levels + rng.normal(0.0, 1.0, n) * (FORCE_REL * levels + FORCE_ABS)
        est = estimate_stiffness(encoder - encoder[0], measured, tip_radius_m=R,
                                 thickness_m=0.05)
        assert est.rigid
        assert est.modulus_pa is None and est.stiffness_n_per_m is None
        assert est.modulus_std_pa is None and est.stiffness_std_n_per_m is None
        # the force gained over a travel no larger than a few encoder σ
        assert est.stiffness_lower_n_per_m is not None
        assert est.stiffness_lower_n_per_m > (force - CONTACT_THRESHOLD_N) / (10 * TRAVEL_SIGMA)


def test_stiff_foam_is_not_rigid():
    # the stiffest foam of the range, on the thinnest layer, at the lightest press: it sinks
    # about 0.4 mm, eight encoder σ; never rigid, and its σ still honest (measured: 94 % within
    # 2σ over 200 records)
    rng = np.random.default_rng(13)
    z = []
    for _ in range(100):
        travel, measured = synthetic_record(rng, layer_law(2e5, 0.02), 0.3, 8)
        est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.02)
        assert not est.rigid
        assert est.modulus_pa is not None and est.modulus_std_pa is not None
        z.append((est.modulus_pa - 2e5) / est.modulus_std_pa)
    assert np.mean(np.abs(z) <= 2.0) >= 0.90


def test_half_space_physics_read_as_a_layer():
    """A half-space Hertz curve, the estimator told h = 10 cm: it reads the table's stiffening
    that is not there, so E comes out low by about the correction at the reached χ.

    Measured over this draw: median error −6 % (range −17 % to +18 %), the correction's
    prediction −5 %, their difference's median −0.1 %; the claimed 2σ (which carries ν's
    uncertainty) covers 96 % of the records. Bound: the median error
    lies in [−15 %, 0] and within 3 % of the prediction.
    """
    rng = np.random.default_rng(17)
    errors, predicted = [], []
    while len(errors) < 100:
        modulus, _, force, n = _draw(rng)
        travel, measured = synthetic_record(rng, half_space_law(modulus), force, n)
        if not in_range(travel, 0.10):
            continue
        est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.10,
                                 config=LAYER_ONLY)
        assert est.modulus_pa is not None and est.max_chi is not None
        errors.append(est.modulus_pa / modulus - 1.0)
        predicted.append(1.0 / float(layer_correction(est.max_chi, NU)) - 1.0)
    errors_a = np.array(errors)
    assert -0.15 <= np.median(errors_a) <= 0.0
    assert abs(np.median(errors_a - np.array(predicted))) <= 0.03


def test_stiffening_foam():
    """A foam that stiffens as it is pressed, ``F ∝ δ²`` (a local modulus growing as ``√δ``);
    its true modulus is the one at the commanded force's depth.

    Measured over this draw: median |E error| 9 % (median +8 %, 5–95 %: −10 % to +23 %; the
    claimed 2σ covers 91 %), the stiffness at the commanded force 13 % low (the model's δ^1.5
    shape is flatter than δ² at the end). Bounds: median |E error| ≤ 15 %; median k error in
    [−25 %, 0].
    """
    rng = np.random.default_rng(19)
    e_errors, k_errors = [], []
    while len(e_errors) < 100:
        modulus, thickness, force, n = _draw(rng)
        depth_c = hertz_indentation(force, R, modulus, NU)
        base = half_space_law(modulus)

        def law(d: float, base: Law = base, depth_c: float = depth_c) -> float:
            return base(d) * np.sqrt(d / depth_c)

        travel, measured = synthetic_record(rng, law, force, n)
        if not in_range(travel, thickness):
            continue
        est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness)
        assert est.modulus_pa is not None and est.stiffness_n_per_m is not None
        e_errors.append(est.modulus_pa / modulus - 1.0)
        k_errors.append(est.stiffness_n_per_m / (2.0 * force / depth_c) - 1.0)
    assert np.median(np.abs(e_errors)) <= 0.15
    assert -0.25 <= np.median(k_errors) <= 0.0


# -- bad input ------------------------------------------------------------------------------------

def _good() -> dict:
    rng = np.random.default_rng(23)
    travel, measured = synthetic_record(rng, layer_law(1e4, 0.05), 1.0, 10)
    return {"travel_m": travel, "force_n": measured, "tip_radius_m": R, "thickness_m": 0.05}


def test_good_record_passes():
    assert not estimate_stiffness(**_good()).rigid


@pytest.mark.parametrize(("change", "name"), [
    (lambda a: a["travel_m"].__setitem__(3, np.nan), "travel_m"),
    (lambda a: a["force_n"].__setitem__(3, np.inf), "force_n"),
    (lambda a: a.update(travel_m=a["travel_m"][:2], force_n=a["force_n"][:2]), "travel_m"),
    (lambda a: a.update(force_n=a["force_n"][:-1]), "force_n"),
    (lambda a: a.update(travel_m=a["travel_m"][::-1].copy()), "travel_m"),
    (lambda a: a.update(force_n=np.full(10, 0.5)), "force_n"),
    (lambda a: a.update(force_n=a["force_n"][::-1].copy()), "force_n"),
    (lambda a: a.update(travel_m=a["travel_m"] * 1e3), "travel_m"),  # millimetres
    (lambda a: a.update(thickness_m=50.0), "thickness_m"),  # millimetres
    (lambda a: a.update(thickness_m=0.0), "thickness_m"),
    (lambda a: a.update(thickness_m=-0.05), "thickness_m"),
    (lambda a: a.update(thickness_m=0.001), "travel_m"),  # pressed deeper than the layer
    (lambda a: a.update(tip_radius_m=0.0), "tip_radius_m"),
    (lambda a: a.update(commanded_force_n=3.0), "force_n"),  # far from the commanded force
    (lambda a: a.update(commanded_force_n=-1.0), "commanded_force_n"),
    (lambda a: a.update(travel_m="0.001"), "travel_m"),
])
def test_bad_input_is_refused_naming_the_argument(change, name):
    args = _good()
    change(args)
    with pytest.raises(InvalidArgumentError, match=f"`{name}`"):
        estimate_stiffness(**args)


def test_travel_may_step_back_by_its_noise():
    args = _good()
    args["travel_m"][5] = args["travel_m"][4] - 2 * TRAVEL_SIGMA
    est = estimate_stiffness(**args)
    assert not est.rigid and np.isfinite(est.modulus_pa) and est.modulus_pa > 0


@pytest.mark.parametrize(("field", "value"), [
    ("poisson_ratio", 0.6), ("travel_noise_m", 0.0), ("force_noise_abs_n", -1.0),
    ("rigid_travel_sigmas", float("nan")), ("force_noise_rel", "1 %"),
])
def test_config_is_validated_naming_the_field(field, value):
    with pytest.raises(SettingError, match=f"`{field}`"):
        StiffnessConfig(**{field: value})


def test_sigma_carries_the_unknown_poisson_ratio() -> None:
    # Records of materials whose ν is anywhere in [0.2, 0.45], read with the assumed 0.33: with
    # the ν uncertainty the claimed σ covers |E error| ≤ 2σ in at least 90 % of them; the sensor
    # noise alone claims less and covers fewer.
    rng = np.random.default_rng(7)
    z_full, z_noise = [], []
    while len(z_full) < 60:
        modulus, thickness, force, n = _draw(rng)
        nu = float(rng.uniform(0.2, 0.45))
        law = lambda d, e=modulus, h=thickness, v=nu: float(  # noqa: E731
            layer_indentation_force(d, R, h, e, v))
        travel, measured = synthetic_record(rng, law, force, n)
        if not in_range(travel, thickness):
            continue
        full = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness,
                                  config=LAYER_ONLY)
        noise = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness,
                                   config=NU_KNOWN)
        assert full.modulus_pa == noise.modulus_pa  # the estimate itself does not change
        assert full.modulus_std_pa > noise.modulus_std_pa
        z_full.append((full.modulus_pa - modulus) / full.modulus_std_pa)
        z_noise.append((noise.modulus_pa - modulus) / noise.modulus_std_pa)
    assert np.mean(np.abs(z_full) <= 2.0) >= 0.90
    assert np.mean(np.abs(z_noise) <= 2.0) < np.mean(np.abs(z_full) <= 2.0)


def test_samples_beyond_the_tips_radius_are_left_out_of_the_fit():
    """Past δ = R the contact radius stops at the sphere's (a flat punch of radius R then adds
    ``2 E* R`` per metre); the record is read from its samples within R."""
    modulus, thickness = 2.0e3, 0.10
    layer = layer_law(modulus, thickness)
    e_star = modulus / (1.0 - NU**2)

    def capped(d: float) -> float:
        return layer(d) if d <= R else layer(R) + 2.0 * e_star * R * (d - R)

    errors = []
    for seed in range(12):
        travel, measured = synthetic_record(np.random.default_rng(100 + seed), capped, 0.6, 10)
        assert R < travel.max() < 2 * R
        est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness,
                                 commanded_force_n=0.6, config=NU_KNOWN)
        assert 3 <= est.n_samples < 10
        errors.append(est.modulus_pa / modulus - 1.0)
    # measured: median |error| 2.4 %; the whole record through the paraboloid read −14 %
    assert np.median(np.abs(errors)) <= 0.08


# -- model error (module docstring, Model error) ------------------------------------------------

def _noise_only_std(est: StiffnessEstimate) -> float:
    """σ(E) without the model-error term (the terms add in quadrature)."""
    assert est.modulus_std_pa is not None
    return float(np.sqrt(est.modulus_std_pa**2 - (est.model_error_pa or 0.0) ** 2))


def test_model_error_is_small_on_the_contact_model(layer_estimates):
    # On records of the model the halves differ by noise alone: the term is zero when D² < σ_D²
    # (68 % under the model; measured 62 % zero here), and σ grows little. Measured over this
    # draw: σ's median ratio 1.000, mean 1.09, 90th percentile 1.27; the coverage test above
    # runs on the σ with the term (95 % within 2σ, as without it).
    ratios = np.array([est.modulus_std_pa / _noise_only_std(est) for _, est in layer_estimates])
    tested = [est.model_error_pa for _, est in layer_estimates]
    assert all(m is not None and m >= 0 for m in tested)
    assert 0.2 <= np.mean(np.array(tested) > 0) <= 0.6
    assert np.median(ratios) <= 1.01 and np.mean(ratios) <= 1.15


def test_model_error_is_zero_on_a_noise_free_model_record():
    levels = np.linspace(CONTACT_THRESHOLD_N, 1.0, 9)
    law = layer_law(2e4, 0.05)
    depth = np.array([_depth_for(f, law) for f in levels])
    est = estimate_stiffness(depth - depth[0], levels, tip_radius_m=R, thickness_m=0.05,
                             config=LAYER_ONLY)
    assert est.model_error_pa == 0.0
    assert est.modulus_pa == pytest.approx(2e4, rel=1e-3)


def test_model_error_is_not_tested_on_three_samples():
    rng = np.random.default_rng(29)
    travel, measured = synthetic_record(rng, layer_law(2e4, 0.05), 2.0, 3)
    assert estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=0.05,
                              config=LAYER_ONLY).model_error_pa is None


def _stiffer_core(modulus: float, thickness: float, jump: float) -> tuple[Law, Law]:
    """A layer whose modulus steps up by ``jump`` (relative) between 2 % and 4 % strain, a soft
    skin over a stiffer core: the force law and the modulus factor at a depth."""
    def factor(d: float) -> float:
        return 1.0 + jump / (1.0 + np.exp(-(d / thickness - 0.03) / 0.005))

    base = layer_law(modulus, thickness)
    return (lambda d: base(d) * factor(d)), factor


def test_model_error_widens_sigma_when_the_halves_disagree():
    """A soft skin over a core twice as stiff: the modulus the press meets rises along the
    record, so no single E is the material's; the claim should reach the range of moduli the
    press crossed (from the contact depth to the commanded force's).

    Measured over this draw: σ grows by 14 % on average (the term is positive in 56 % of the
    records); ``E ± 2σ`` reaches that range in 82 % of them against 71 % without the term. Bound:
    at least 6 points more, and σ's mean ratio at least 1.08.
    """
    rng = np.random.default_rng(3)
    old, new, ratios = [], [], []
    while len(old) < 80:
        modulus, thickness, force, n = _draw(rng)
        law, factor = _stiffer_core(modulus, thickness, 1.0)
        travel, measured = synthetic_record(rng, law, force, n)
        if not in_range(travel, thickness):
            continue
        est = estimate_stiffness(travel, measured, tip_radius_m=R, thickness_m=thickness)
        assert est.modulus_pa is not None and est.modulus_std_pa is not None
        contact = _depth_for(CONTACT_THRESHOLD_N, law)
        low, high = modulus * factor(contact), modulus * factor(travel[-1] + contact)
        outside = max(low - est.modulus_pa, est.modulus_pa - high, 0.0)
        old.append(outside <= 2.0 * _noise_only_std(est))
        new.append(outside <= 2.0 * est.modulus_std_pa)
        ratios.append(est.modulus_std_pa / _noise_only_std(est))
    assert np.mean(new) >= np.mean(old) + 0.06
    assert np.mean(ratios) >= 1.08
