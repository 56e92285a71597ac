"""The force noise that grows with the load (:func:`deformap.stiffness._phases.force_noise`) and
the loss σ it gives, on synthetic records with known noise."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.environment import ForceTravel, PressPhase
from deformap.stiffness import press_behaviour
from deformap.stiffness._phases import ForceNoise, force_noise, loop_loss, noise

DEPTH = 0.003  # 3 mm of travel to 0.6 N
TOP = 0.6
ST = 5e-5  # the travel's noise [m]


def _sigma(force: np.ndarray, a: float, b: float) -> np.ndarray:
    return np.sqrt(a**2 + (b * force) ** 2)


def _stretches(n_ramp: int, n_hold: int) -> list[np.ndarray]:
    """A load-controlled press's true forces: a ramp, a hold, an unloading."""
    ramp = np.linspace(0.05, TOP, n_ramp)
    return [ramp, np.full(n_hold, TOP), ramp[::-1].copy()]


def test_the_load_dependent_noise_recovers_a_known_a_and_b() -> None:
    rng = np.random.default_rng(3)
    a, b = 0.004, 0.02
    parts = [f + rng.normal(size=f.size) * _sigma(f, a, b) for f in _stretches(2000, 2000)]
    got = force_noise(parts)
    assert got.a == pytest.approx(a, rel=0.15)
    assert got.b == pytest.approx(b, rel=0.1)
    # the pooled constant lies between the smallest and the largest of the record's noise
    assert a < noise(parts) < float(_sigma(np.array(TOP), a, b))


def test_a_noise_that_does_not_grow_keeps_a_constant_and_falls_back_when_it_cannot_fit() -> None:
    rng = np.random.default_rng(4)
    parts = [f + rng.normal(size=f.size) * 0.01 for f in _stretches(2000, 2000)]
    got = force_noise(parts)
    assert got.a == pytest.approx(0.01, rel=0.05)
    assert float(got.at(TOP)) == pytest.approx(0.01, rel=0.05)
    # one force only (a hold): a and b cannot be told apart; too few samples: the pooled constant
    hold = [TOP + rng.normal(size=300) * 0.01]
    assert force_noise(hold) == ForceNoise(noise(hold))
    short = [TOP + rng.normal(size=6) * 0.01, np.linspace(0.1, 0.5, 5)]
    assert force_noise(short) == ForceNoise(noise(short))
    assert force_noise([np.zeros(50)]) == ForceNoise(0.0)


def _record(rng: np.random.Generator, a: float, b: float) -> ForceTravel:
    """An elastic Hertz press (no loss) of 28 ramp, 300 hold and 28 unloading samples, its force
    noise ``√(a² + (b F)²)``."""
    ramp, hold, unload = _stretches(28, 300)

    def travel(f: np.ndarray) -> np.ndarray:
        return np.asarray(DEPTH * ((f / TOP) ** (2.0 / 3.0) - (ramp[0] / TOP) ** (2.0 / 3.0)))

    def read(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return (travel(f) + rng.normal(size=f.size) * ST,
                np.maximum(f + rng.normal(size=f.size) * _sigma(f, a, b), 0.0))

    (t0, f0), (t1, f1), (t2, f2) = read(ramp), read(hold), read(unload)
    f2 = np.minimum.accumulate(f2)  # the controller retracts until the force falls to each level
    zero = t0[0]  # the travel is counted from the encoders' reading at first contact
    dt = 0.01
    times = np.arange(28) * dt
    return ForceTravel(travel_m=t0 - zero, force_n=f0, time_s=times,
                       hold=PressPhase(time_s=times[-1] + dt * np.arange(1, 301),
                                       travel_m=t1 - zero, force_n=f1),
                       unloading=PressPhase(time_s=times[-1] + dt * np.arange(301, 329),
                                            travel_m=t2 - zero, force_n=f2))


def test_the_loss_sigma_matches_its_spread_when_the_noise_grows_with_the_load() -> None:
    rng = np.random.default_rng(5)
    # the force noise at the top ten times that at contact: a pooled constant (mostly the hold's)
    # claims the ramp's and the unloading's force noise too large
    a, b = 0.003, 0.03
    records = [_record(rng, a, b) for _ in range(200)]
    got = [press_behaviour(r) for r in records]
    loss = np.array([g.loss_ratio for g in got], dtype=float)
    sigma = np.array([g.loss_ratio_sigma for g in got], dtype=float)
    spread = float(np.std(loss, ddof=1))
    assert abs(float(np.mean(loss))) < 3.0 * spread / np.sqrt(loss.size)  # no loss: elastic
    assert spread / float(np.median(sigma)) == pytest.approx(1.0, abs=0.2)
    pooled = []
    for r in records:
        parts = [r.force_n, r.hold.force_n, r.unloading.force_n]
        sigma_t = noise([r.travel_m, r.hold.travel_m, r.unloading.travel_m])
        m = loop_loss(r, ForceNoise(noise(parts)), sigma_t)
        assert not isinstance(m, str)
        pooled.append(m.sigma)
    assert spread / float(np.median(pooled)) < spread / float(np.median(sigma)) - 0.05


def test_a_clamped_zero_force_tail_or_a_large_scale_does_not_break_the_noise_fit() -> None:
    """An unloading whose force is clamped at zero (a run of exact zeros) fits or falls back to
    the pooled constant, finite, never a numpy error; the fit does not depend on the force's unit."""
    rng = np.random.default_rng(6)
    parts = [f + rng.normal(size=f.size) * 0.01 * f for f in _stretches(400, 1200)]
    parts[2] = np.concatenate([np.maximum(parts[2], 0.0), np.zeros(10)])
    got = force_noise(parts)
    assert np.isfinite(got.a) and np.isfinite(got.b) and got.a > 0.0
    noisy = [f + rng.normal(size=f.size) * _sigma(f, 0.005, 0.01) for f in _stretches(400, 1200)]
    small, large = force_noise(noisy), force_noise([1000.0 * f for f in noisy])
    assert large.a == pytest.approx(1000.0 * small.a, rel=1e-6)
    assert large.b == pytest.approx(small.b, rel=1e-6)


def _held(n_hold: int, rng: np.random.Generator | None, creep: float = 0.0,
          relax: float = 0.0) -> ForceTravel:
    """A Hertz loading to 0.6 N, a hold of ``n_hold`` samples over 12 s in which the travel creeps
    by ``creep`` of it and the force relaxes by ``relax`` of it, and a Hertz unloading from there."""
    ramp = np.linspace(0.05, TOP, 30)
    t_hold = np.linspace(0.0, 12.0, n_hold + 1)[1:]
    d_hold = DEPTH * (1.0 + creep * (1.0 - np.exp(-t_hold / 3.0)))
    f_hold = TOP * (1.0 - relax * (1.0 - np.exp(-t_hold / 0.3)))
    down = np.linspace(float(f_hold[-1]), 0.05, 30)
    d_down = d_hold[-1] * (down / f_hold[-1]) ** (2.0 / 3.0)
    zero = DEPTH * (ramp[0] / TOP) ** (2.0 / 3.0)  # travel counted from first contact
    d_ramp = DEPTH * (ramp / TOP) ** (2.0 / 3.0) - zero
    d_hold, d_down = d_hold - zero, d_down - zero

    def noisy(x: np.ndarray, s: float) -> np.ndarray:
        return x if rng is None else x + rng.normal(size=x.size) * s

    return ForceTravel(travel_m=noisy(d_ramp, ST), force_n=noisy(ramp, 0.005),
                       time_s=np.arange(30) * 0.01,
                       hold=PressPhase(time_s=0.29 + t_hold, travel_m=noisy(d_hold, ST),
                                       force_n=noisy(f_hold, 0.005)),
                       unloading=PressPhase(time_s=12.3 + np.arange(30) * 0.01,
                                            travel_m=noisy(d_down, ST), force_n=noisy(down, 0.005)))


def test_the_loss_sigma_does_not_grow_with_a_held_forces_hold() -> None:
    """A hold that keeps the force enters the loss by its last sample: 300 or 1200 samples of it
    give the same σ (each interior sample would add the product of its two noises)."""
    rng = np.random.default_rng(7)
    sigma = {}
    for n in (300, 1200):
        got = [loop_loss(r, ForceNoise(0.005), ST) for r in (_held(n, rng) for _ in range(20))]
        sigma[n] = float(np.median([m.sigma for m in got if not isinstance(m, str)]))
    assert sigma[1200] == pytest.approx(sigma[300], rel=0.05)


def _whole_loop(record: ForceTravel) -> float:
    """The loss along every sample of the loop (trapezoids), the hold's interior included."""
    x = np.concatenate([record.travel_m, record.hold.travel_m, record.unloading.travel_m])
    y = np.concatenate([record.force_n, record.hold.force_n, record.unloading.force_n])
    n_in = record.travel_m.size + record.hold.travel_m.size
    return float(np.trapezoid(y, x)) / float(np.trapezoid(y[:n_in], x[:n_in]))


def test_a_hold_where_force_and_travel_both_move_enters_the_loss_by_every_sample() -> None:
    """Noise-free: a hold in which the force relaxes while the travel creeps is integrated along
    its samples (the trapezoid over the whole loop); one that keeps the force gives F Δδ exactly."""
    for record in (_held(1200, None, creep=0.1, relax=0.2), _held(1200, None, creep=0.1)):
        got = loop_loss(record, ForceNoise(0.005), ST)
        assert not isinstance(got, str)
        assert got.value == pytest.approx(_whole_loop(record), rel=1e-9)
