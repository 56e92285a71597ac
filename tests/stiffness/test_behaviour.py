"""What one press reveals: relaxation, loss, kept dent and class, on synthetic records."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import ForceTravel, PressPhase
from deformap.errors import InvalidArgumentError
from deformap.stiffness import press_behaviour, released_dent

DEPTH = 0.004  # 4 mm of travel to 1 N
K = 1.0 / DEPTH**1.5  # Hertz: F = K δ^1.5
SF, ST = 0.004, 2e-5  # force and travel noise


def _ramp(rng: np.random.Generator, n: int = 30) -> tuple[np.ndarray, ...]:
    travel = np.linspace(0.0, DEPTH, n)
    force = K * travel**1.5
    return (np.abs(travel + rng.normal(0, ST, n)) * (np.arange(n) > 0),
            np.maximum(force + rng.normal(0, SF, n), 0.0), np.linspace(0.0, 1.0, n))


def _unloading(rng: np.random.Generator, residual_m: float, start_s: float, n: int = 30,
               stop_n: float = 0.0, top_n: float = 1.0) -> PressPhase:
    """Hertz unloading from ``top_n`` to ``stop_n`` newtons that leaves ``residual_m``."""
    k = top_n / (DEPTH - residual_m) ** 1.5
    force = np.linspace(top_n, stop_n, n)
    travel = residual_m + (force / k) ** (2 / 3)
    return PressPhase(time_s=start_s + np.linspace(0.05, 1.0, n),
                      travel_m=travel + rng.normal(0, ST, n),
                      force_n=np.maximum(force + rng.normal(0, SF, n), 0.0))


def _relaxing_hold(rng: np.random.Generator, fraction: float, tau_s: float, n: int = 50,
                   span_s: float = 10.0, creep: bool = False) -> PressPhase:
    # the material relaxes from the ramp's end (t = 0, its last sample); the hold's samples follow
    t = np.linspace(0.05, span_s, n)
    shape = 1.0 - fraction * (1.0 - np.exp(-t / tau_s))
    if creep:  # force held, travel grows: t_start / t(t) = shape
        travel, force = DEPTH / shape, np.full(n, 1.0)
    else:
        travel, force = np.full(n, DEPTH), 1.0 * shape
    return PressPhase(time_s=1.0 + t, travel_m=travel + rng.normal(0, ST, n),
                      force_n=force + rng.normal(0, SF, n))


def _record(seed: int = 0, hold: bool | PressPhase = False,
            unloading: float | PressPhase | None = None) -> ForceTravel:
    rng = np.random.default_rng(seed)
    travel, force, time = _ramp(rng)
    held = (_relaxing_hold(rng, 0.0, 1.0) if hold is True
            else hold if isinstance(hold, PressPhase) else None)
    end = 1.0 if held is None else float(held.time_s[-1])
    unload = (_unloading(rng, unloading, end) if isinstance(unloading, float) else unloading)
    return ForceTravel(travel_m=travel, force_n=force, time_s=time, hold=held, unloading=unload)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize(("fraction", "tau_s"), [(0.3, 2.0), (0.15, 0.8), (0.5, 4.0)])
def test_an_exponential_relaxation_gives_its_fraction_and_time_constant(
        seed: int, fraction: float, tau_s: float) -> None:
    hold = _relaxing_hold(np.random.default_rng([seed, 9]), fraction, tau_s)
    got = press_behaviour(_record(seed, hold=hold))
    true = fraction * (1.0 - math.exp(-10.0 / tau_s))  # 1 − F_end / F_start over the hold
    assert got.relaxation_mode == "force"
    assert got.relaxation is not None and abs(got.relaxation - true) < 0.05
    assert got.tau_s is not None and abs(got.tau_s / tau_s - 1.0) < 0.2
    assert got.tau_sigma_s is not None and 0.0 < got.tau_sigma_s < 0.2 * tau_s
    assert got.behaviour == "viscoelastic", got.evidence
    assert "the hold relaxes" in got.evidence


def test_a_creep_under_a_held_force_is_read_from_the_travel() -> None:
    hold = _relaxing_hold(np.random.default_rng(3), 0.2, 1.5, creep=True)
    got = press_behaviour(_record(hold=hold))
    assert got.relaxation_mode == "travel"
    assert got.relaxation is not None and abs(got.relaxation - 0.2 * (1 - math.exp(-10 / 1.5))) < 0.05
    assert got.tau_s is not None and abs(got.tau_s / 1.5 - 1.0) < 0.2
    assert got.behaviour == "viscoelastic"


def test_the_relaxation_sigma_covers_the_truth_over_seeds() -> None:
    hits = 0
    for seed in range(40):
        hold = _relaxing_hold(np.random.default_rng([seed, 5]), 0.2, 2.0)
        got = press_behaviour(_record(seed, hold=hold))
        assert got.relaxation is not None and got.relaxation_sigma is not None
        hits += abs(got.relaxation - 0.2 * (1 - math.exp(-5.0))) < 2 * got.relaxation_sigma
    assert hits >= 34  # ~95 % expected within 2 σ


@pytest.mark.parametrize("residual_m", [0.0005, 0.001, 0.002])
def test_a_hysteresis_loop_gives_its_known_loss(residual_m: float) -> None:
    # loading W = K δm^2.5 / 2.5; returned W' = F_m (δm − δr) / 2.5
    got = press_behaviour(_record(unloading=residual_m))
    w_in = K * DEPTH**2.5 / 2.5
    w_back = 1.0 * (DEPTH - residual_m) / 2.5
    true = 1.0 - w_back / w_in
    assert got.loss_ratio is not None and got.loss_ratio_sigma is not None
    assert abs(got.loss_ratio - true) < max(3 * got.loss_ratio_sigma, 0.01)
    assert got.loss_ratio_sigma < 0.02


@pytest.mark.parametrize("residual_m", [0.0, 0.0005, 0.0015])
@pytest.mark.parametrize("stop_n", [0.0, 0.3])
def test_an_unloading_gives_its_residual_dent_extrapolated_when_it_stops_early(
        residual_m: float, stop_n: float) -> None:
    rng = np.random.default_rng(11)
    unload = _unloading(rng, residual_m, 1.0, stop_n=stop_n)
    got = press_behaviour(_record(unloading=unload))
    assert got.residual_dent_m is not None and got.residual_dent_sigma_m is not None
    assert abs(got.residual_dent_m - residual_m) < 1e-4
    assert got.residual_dent_sigma_m < 1e-4


@pytest.mark.parametrize("seed", range(30))
def test_an_elastic_press_is_flagged_elastic(seed: int) -> None:
    got = press_behaviour(_record(seed, hold=True, unloading=0.0))
    assert got.behaviour == "elastic", got.evidence
    assert got.relaxation is not None and abs(got.relaxation) < 0.02


def test_a_kept_dent_with_a_still_hold_is_plastic() -> None:
    got = press_behaviour(_record(hold=True, unloading=0.001))
    assert got.behaviour == "plastic", got.evidence
    assert "a dent remains" in got.evidence


def test_the_camera_dent_alone_with_a_still_hold_is_plastic_and_none_is_elastic() -> None:
    record = _record(hold=True)
    assert press_behaviour(record, released=(0.001, 5e-5)).behaviour == "plastic"
    assert press_behaviour(record, released=(0.0, 3e-5)).behaviour == "elastic"
    # a camera too noisy to rule a dent out leaves the class unknown
    assert press_behaviour(record, released=(0.0, 1e-3)).behaviour == "unknown"


def test_a_dent_without_a_hold_cannot_tell_creep_from_yield() -> None:
    got = press_behaviour(_record(unloading=0.001))
    assert got.behaviour == "unknown"
    assert "creep cannot be told from yield" in got.evidence


@pytest.mark.parametrize("record", [None, "ramp"])
def test_a_ramp_only_or_no_record_is_unknown_never_elastic(record: str | None) -> None:
    rec = None if record is None else _record()
    got = press_behaviour(rec)
    assert got.behaviour == "unknown"
    assert got.evidence == ("no force–travel record" if rec is None
                            else "no hold or unloading recorded")
    assert got.to_dict()["behaviour"] == "unknown" and got.to_dict()["loss_ratio"] is None


def test_a_short_hold_gives_a_fraction_but_no_time_constant() -> None:
    rng = np.random.default_rng(0)
    # two samples after the ramp's last: three in all, too few for the exponential
    hold = PressPhase(time_s=[2.0, 3.0], travel_m=[DEPTH] * 2, force_n=[0.8, 0.7])
    got = press_behaviour(_record(hold=hold, unloading=_unloading(rng, 0.0, 3.0, top_n=0.7)))
    assert got.tau_s is None and "needs 4" in got.evidence
    assert got.relaxation is not None and abs(got.relaxation - (1 - 0.7 / 1.0)) < 0.01
    assert got.behaviour == "viscoelastic"


def test_a_noisy_hold_neither_shows_nor_rules_out_relaxation() -> None:
    rng = np.random.default_rng(4)
    n = 8
    hold = PressPhase(time_s=1.1 + np.arange(n), travel_m=np.full(n, DEPTH),
                      force_n=1.0 + rng.normal(0, 0.03, n) - 0.01 * np.arange(n) / n)
    got = press_behaviour(_record(hold=hold))
    assert got.behaviour == "unknown", got.evidence


def test_the_samples_after_contact_is_lost_do_not_move_the_dent() -> None:
    # after the force reaches zero the tip retracts off the surface: its travel there is the
    # tip's, not the dent's
    unload = _unloading(np.random.default_rng(5), 0.001, 1.0)
    tail = PressPhase(time_s=np.concatenate([unload.time_s, 2.0 + 0.1 * np.arange(1, 6)]),
                      travel_m=np.concatenate([unload.travel_m, 0.001 - 4e-4 * np.arange(1, 6)]),
                      force_n=np.concatenate([unload.force_n, np.zeros(5)]))
    plain = press_behaviour(_record(unloading=unload))
    got = press_behaviour(_record(unloading=tail))
    # the same reading (the pooled noise estimate alone moves with the extra samples)
    assert got.residual_dent_m is not None and plain.residual_dent_m is not None
    assert got.residual_dent_m == pytest.approx(plain.residual_dent_m, abs=2e-6)
    assert abs(got.residual_dent_m - 0.001) < 1e-4


def _dented(depth_m: float, n: int = 12000, noise_m: float = 3e-4) -> PointCloud:
    rng = np.random.default_rng(2)
    xy = rng.uniform([0.25, 0.15], [0.35, 0.25], (n, 2))
    z = 0.05 - depth_m * np.exp(-np.sum((xy - [0.3, 0.2]) ** 2, axis=1) / 0.006**2)
    return PointCloud(np.column_stack([xy, z + rng.normal(0, noise_m, n)]))


@pytest.mark.parametrize("depth_m", [0.0, 0.0005, 0.002])
def test_the_camera_dent_after_release_is_measured(depth_m: float) -> None:
    got = released_dent(_dented(depth_m).points, [0.3, 0.2, 0.056], 0.005)
    assert isinstance(got, tuple)
    dent, sigma = got
    # the median within one tip radius of a Gaussian dent of width 6 mm reads a bit shallow
    assert abs(dent - depth_m * 0.8) < max(0.25 * depth_m, 3 * sigma)
    assert 0.0 < sigma < 6e-5  # ~94 points within the tip, ~750 in the ring, 0.3 mm noise


def test_a_camera_dent_with_too_few_points_says_why() -> None:
    got = released_dent(np.array([[0.3, 0.2, 0.05]]), [0.3, 0.2, 0.056], 0.005)
    assert isinstance(got, str) and "needs 5 of each" in got


@pytest.mark.parametrize("bad", [(float("nan"), 1e-4), (0.001, float("inf")), (0.001, -1.0)])
def test_a_bad_camera_dent_is_refused_naming_it(bad: tuple[float, float]) -> None:
    with pytest.raises(InvalidArgumentError, match="`released`"):
        press_behaviour(_record(hold=True), released=bad)


def test_a_record_of_the_wrong_type_or_with_nan_is_refused() -> None:
    import types

    with pytest.raises(InvalidArgumentError, match="`record` must be a ForceTravel"):
        press_behaviour((np.zeros(3), np.ones(3)))  # type: ignore[arg-type]
    hold = types.SimpleNamespace(time_s=np.array([1.0, np.nan]), travel_m=np.zeros(2),
                                 force_n=np.ones(2))
    unchecked = types.SimpleNamespace(travel_m=np.zeros(3), force_n=np.ones(3),
                                      time_s=np.arange(3.0), hold=hold, unloading=None)
    with pytest.raises(InvalidArgumentError, match=r"`record\.hold\.time_s` holds NaN"):
        press_behaviour(unchecked)


@pytest.mark.parametrize(("change", "field"), [
    ({"time_s": "backwards"}, "`time_s` must increase"),
    ({"hold": "empty"}, "`travel_m` must have at least 2 rows"),
    ({"unloading": "rising"}, "`unloading.force_n` must fall"),
    ({"force_n": "nan"}, "`force_n`.*NaN"),
    ({"hold": "inf"}, "`time_s`.*NaN or infinite"),
])
def test_every_bad_record_is_refused_before_it_is_read(change: dict[str, object],
                                                       field: str) -> None:
    rng = np.random.default_rng(0)
    travel, force, time = _ramp(rng)
    fields: dict[str, object] = {"travel_m": travel, "force_n": force, "time_s": time}
    with pytest.raises(InvalidArgumentError, match=field):
        for key, value in change.items():
            if value == "backwards":
                value = np.linspace(1.0, 0.0, 30)
            elif value == "empty":
                value = PressPhase(time_s=[], travel_m=[], force_n=[])
            elif value == "rising":
                value = PressPhase(time_s=[1.1, 1.2, 1.3], travel_m=[0.004, 0.003, 0.002],
                                   force_n=[0.5, 0.9, 0.1])
            elif value == "nan":
                value = np.where(np.arange(30) == 5, np.nan, force)
            elif value == "inf":
                value = PressPhase(time_s=[1.1, np.inf, 1.3], travel_m=[0.004] * 3,
                                   force_n=[1.0] * 3)
            fields[key] = value
        press_behaviour(ForceTravel(**fields))  # type: ignore[arg-type]


def test_a_poke_record_keeps_its_behaviour_through_the_journal() -> None:
    import dataclasses
    import json

    from deformap.errors import FileFormatError
    from deformap.explore import ContactRecord, PokeRecord, PokeTimings
    from deformap.mechanics import TactileContact
    from deformap.stiffness._anisotropy import Anisotropy

    shape = Anisotropy(ratio=2.0, ratio_sigma=0.1, axis_deg=30.0, axis_sigma_deg=2.0,
                       isotropy="anisotropic", evidence="the dent reaches farther one way")
    behaviour = press_behaviour(_record(hold=_relaxing_hold(np.random.default_rng(0), 0.3, 2.0),
                                        unloading=0.0005), modulus=(5e4, 1e3), anisotropy=shape)
    assert behaviour.isotropy == "anisotropic" and behaviour.anisotropy_axis_deg == 30.0
    assert behaviour.modulus_relaxed_pa is not None
    record = PokeRecord(
        index=0, target_xy=(0.3, 0.2), contact_xy=(0.3, 0.2),
        contact=ContactRecord.of(TactileContact(tip_center=[0.3, 0.2, 0.05], force=[0, 0, -1.0],
                                                tip_radius_m=0.01)),
        force_n=1.0, beta=0.5, beta_std=0.01, betas=(0.5,), errors=(1e-3,), iterations=1,
        residual=0.0, converged=True, n_roi_points=10, camera_noise_m=None,
        timings=PokeTimings(filter_s=0.1, touch_gp_s=0.1, beta_s=0.1), behaviour=behaviour)
    data = json.loads(json.dumps(record.to_dict(), allow_nan=False))
    assert data["behaviour"]["behaviour"] == "viscoelastic"
    assert PokeRecord.from_dict(data) == record
    old = dict(data)
    del old["behaviour"]  # a journal written before behaviours: read back without one
    assert PokeRecord.from_dict(old) == dataclasses.replace(record, behaviour=None)
    for key, bad, message in (("behaviour", "elastic-ish", "`poke.behaviour.behaviour` must be"),
                              ("relaxation", "0.3", "`poke.behaviour.relaxation` must be a"),
                              ("relaxation_mode", "time", "`poke.behaviour.relaxation_mode`"),
                              ("isotropy", "round", "`poke.behaviour.isotropy`"),
                              ("colour", 1, "unknown key")):
        broken = {**data, "behaviour": {**data["behaviour"], key: bad}}
        with pytest.raises(FileFormatError, match=message):
            PokeRecord.from_dict(broken)


def test_a_camera_too_coarse_to_rule_out_a_dent_does_not_veto_the_record() -> None:
    # an elastic record, and a camera whose dent reading (0.1 ± 0.3 mm) can neither show nor rule
    # out a tenth of a millimetre: the record's sharper reading decides
    record = _record(0, hold=True, unloading=0.0)
    assert press_behaviour(record).behaviour == "elastic"
    got = press_behaviour(record, released=(1e-4, 3e-4))
    assert got.behaviour == "elastic", got.evidence
    # a camera that shows a dent is heard
    assert press_behaviour(record, released=(2e-3, 1e-4)).behaviour != "elastic"


def test_a_hold_where_neither_moves_is_read_as_a_held_force() -> None:
    # the force scatters without a trend and the travel barely moves: neither trends beyond its
    # noise, so the robot is taken to hold the force (and the travel to be what would creep)
    rng = np.random.default_rng(8)
    n = 12
    hold = PressPhase(time_s=1.0 + 0.25 * np.arange(1, n + 1),
                      travel_m=DEPTH + rng.normal(0, ST / 4, n),
                      force_n=1.0 + rng.normal(0, 0.02, n))
    got = press_behaviour(_record(hold=hold, unloading=_unloading(rng, 0.0, 4.5)))
    assert got.relaxation_mode == "travel"
    assert got.tau_s is None and "moves within its noise" in got.evidence
    assert got.behaviour != "viscoelastic", got.evidence


def test_the_record_dent_floor_is_what_a_drifting_sensor_zero_moves() -> None:
    from deformap.stiffness._behaviour import (
        DENT_FLOOR_M,
        RELAXATION_FLOOR,
        record_dent_floor,
    )
    record = _record(hold=True)
    largest = max(float(record.travel_m.max()), float(record.hold.travel_m.max()))
    assert record_dent_floor(record) == pytest.approx(RELAXATION_FLOOR ** (2 / 3) * largest)
    shallow = ForceTravel(travel_m=[0.0, 1e-4, 2e-4], force_n=[0.0, 0.5, 1.0])
    assert record_dent_floor(shallow) == DENT_FLOOR_M


def test_a_branch_off_the_contact_law_widens_the_dent_sigma() -> None:
    rng = np.random.default_rng(6)
    clean = _unloading(rng, 0.001, 1.0)
    wavy = PressPhase(time_s=clean.time_s, force_n=clean.force_n,
                      travel_m=clean.travel_m + 3e-4 * np.sin(np.linspace(0, 9, len(clean))))
    a = press_behaviour(_record(unloading=clean))
    b = press_behaviour(_record(unloading=wavy))
    assert a.residual_dent_sigma_m is not None and b.residual_dent_sigma_m is not None
    assert b.residual_dent_sigma_m > 4 * a.residual_dent_sigma_m


@pytest.mark.parametrize("creep", [False, True])
def test_the_relaxed_modulus_follows_from_the_instantaneous_and_the_hold(creep: bool) -> None:
    hold = _relaxing_hold(np.random.default_rng(2), 0.3, 1.0, creep=creep)
    got = press_behaviour(_record(hold=hold, unloading=0.0), modulus=(50e3, 2e3))
    assert got.modulus_instantaneous_pa == 50e3 and got.modulus_instantaneous_sigma_pa == 2e3
    assert got.relaxation is not None and got.modulus_relaxed_pa is not None
    # position held: the force (so E) falls by the fraction, 0.3 (1 − e^{-10}); force held: the
    # travel grows by 1 / (1 − 0.3) and as E^(-2/3) (Hertz), so E falls to 0.7^(3/2)
    assert got.modulus_relaxed_pa / 50e3 == pytest.approx(0.7**1.5 if creep else 0.7, abs=0.03)
    assert got.modulus_relaxed_sigma_pa is not None
    assert 2e3 * 0.5 <= got.modulus_relaxed_sigma_pa < 0.1 * got.modulus_relaxed_pa
    assert got.to_dict()["modulus_relaxed_pa"] == got.modulus_relaxed_pa


def test_a_modulus_without_a_hold_is_only_the_instantaneous_and_a_bad_one_is_refused() -> None:
    got = press_behaviour(_record(unloading=0.0), modulus=(50e3, 2e3))
    assert got.modulus_instantaneous_pa == 50e3 and got.modulus_relaxed_pa is None
    for bad in [(0.0, 1.0), (float("nan"), 1.0), (5e4, -1.0)]:
        with pytest.raises(InvalidArgumentError, match="`modulus`"):
            press_behaviour(_record(unloading=0.0), modulus=bad)


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("residual_m", [0.0, 1e-3])
def test_a_noise_free_record_gives_its_dent(residual_m: float) -> None:
    """A record without noise (a simulation's, noise off: a long still hold makes the pooled
    noise exactly 0) weighs its unloading samples alike."""
    travel = np.linspace(0.0, DEPTH, 30)
    force = K * travel**1.5
    force[0] = 0.02  # contact
    k = 1.0 / (DEPTH - residual_m) ** 1.5
    down = np.linspace(1.0, 0.02, 30)
    hold = PressPhase(time_s=1.0 + np.linspace(0.01, 3.0, 300), travel_m=np.full(300, DEPTH),
                      force_n=np.full(300, 1.0))
    record = ForceTravel(travel_m=travel, force_n=force, time_s=np.linspace(0.0, 1.0, 30),
                         hold=hold,
                         unloading=PressPhase(time_s=4.0 + np.linspace(0.05, 1.0, 30),
                                              travel_m=residual_m + (down / k) ** (2 / 3),
                                              force_n=down))
    got = press_behaviour(record)
    assert got.residual_dent_m == pytest.approx(residual_m, abs=5e-5)
    assert got.residual_dent_sigma_m is not None and math.isfinite(got.residual_dent_sigma_m)
