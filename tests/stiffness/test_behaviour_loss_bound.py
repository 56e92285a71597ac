"""The loss a relaxation can give is bounded by the creep a long enough hold shows
(``LOSS_PER_CREEP``), and a press whose loss is unresolved reads elastic only under that bound."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.environment import ForceTravel, PressPhase
from deformap.stiffness import press_behaviour
from deformap.stiffness._behaviour import LOSS_FLOOR, LOSS_PER_CREEP


def _sls_press(relaxed_ratio: float, tau: float, hold: float) -> tuple[float, float]:
    """Loss ratio and hold creep fraction of a standard linear solid (creep compliance
    ``J∞ − (J∞ − J₀) e^(−t/τc)``, ``τc = τ / g∞``) pressed by a sphere (Lee & Radok: the travel
    goes as ``(∫ J dF)^(2/3)``) under a unit ramp of 1 s from zero force, a hold of ``hold``
    seconds and an unloading of 1 s; each step exact for a force linear over it."""
    tc, j_inf = tau / relaxed_ratio, 1.0 / relaxed_ratio
    # the ramp's start refined: near zero force the contact law is steepest
    ramp = np.concatenate([[0.0], np.geomspace(1e-8, 1e-2, 400), np.linspace(1e-2, 1.0, 1500)[1:]])
    t = np.concatenate([ramp, 1.0 + np.linspace(0.0, hold, 1500)[1:],
                        1.0 + hold + (1.0 - ramp[::-1])[1:]])
    force = np.concatenate([ramp, np.ones(1499), ramp[::-1][1:]])
    h = np.zeros(t.size)
    for k in range(1, t.size):
        dt = t[k] - t[k - 1]
        rate = (force[k] - force[k - 1]) / dt
        h[k] = np.exp(-dt / tc) * h[k - 1] + rate * tc * -np.expm1(-dt / tc)
    travel = np.maximum(j_inf * force - (j_inf - 1.0) * h, 0.0) ** (2.0 / 3.0)
    n_in = ramp.size + 1499
    loop = float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(travel)))
    work = float(np.sum(0.5 * (force[1:n_in] + force[:n_in - 1]) * np.diff(travel[:n_in])))
    return loop / work, 1.0 - travel[ramp.size - 1] / travel[n_in - 1]


def test_a_standard_linear_solids_loss_is_at_most_loss_per_creep_times_its_creep() -> None:
    """Over relaxed ratios 0.1–0.999 and relaxation times 1e-4–1e3 ramps, with a hold as long as
    the ramp and the unloading (2 s) or five times longer: the ratio stays below the bound and
    reaches it in the fast limit (the bound is the supremum, not a margin)."""
    ratios = [_sls_press(g, tau, hold)
              for g in (0.1, 0.5, 0.9, 0.999) for tau in np.geomspace(1e-4, 1e3, 8)
              for hold in (2.0, 10.0)]
    per_creep = [loss / creep for loss, creep in ratios if creep > 0.0]
    assert len(per_creep) == len(ratios)
    assert max(per_creep) <= LOSS_PER_CREEP
    assert max(per_creep) > 0.99 * LOSS_PER_CREEP
    # a hold shorter than the loop does not bound a slow relaxation's loss by its creep as well
    slow_loss, slow_creep = _sls_press(0.5, 1e3, 0.2)
    assert slow_loss / slow_creep > LOSS_PER_CREEP


def _record(seed: int, *, hold_s: float, creep: float, force_noise: float = 0.05) -> ForceTravel:
    """A Hertz press to 1 N over 1 s, a hold of ``hold_s`` that creeps by ``creep`` (force held),
    and an elastic unloading over 1 s; the force sensor's noise ``force_noise`` N on the ramp and
    the hold (the unloading's force as commanded: a running minimum of that noise would bias it),
    encoders 5 µm."""
    rng = np.random.default_rng(seed)
    depth, n = 0.004, 12  # a coarse ramp: the loss's σ about 0.03
    force = np.linspace(0.02, 1.0, n)
    travel = depth * force ** (2.0 / 3.0)
    noisy = rng.normal(0.0, force_noise, n)
    m = 300  # as many hold samples whatever its length: the pooled noise alike
    t_hold = np.linspace(0.0, hold_s, m + 1)[1:]
    creeping = depth / (1.0 - creep * (1.0 - np.exp(-t_hold / (0.3 * hold_s))))
    hold = PressPhase(time_s=1.0 + t_hold, travel_m=creeping - travel[0] + rng.normal(0, 5e-6, m),
                      force_n=1.0 + rng.normal(0.0, force_noise, m))
    down = np.linspace(1.0, 0.02, 101)[1:]
    back = depth * down ** (2.0 / 3.0) + (creeping[-1] - depth)
    unloading = PressPhase(
        time_s=1.0 + hold_s + np.linspace(0.0, 1.0, 101)[1:], travel_m=back - travel[0]
        + rng.normal(0, 5e-6, 100), force_n=down)
    return ForceTravel(travel_m=travel - travel[0] + rng.normal(0, 5e-6, n) * (np.arange(n) > 0),
                       force_n=np.maximum(force + noisy, 0.0), time_s=np.linspace(0.0, 1.0, n),
                       hold=hold, unloading=unloading)


@pytest.mark.parametrize("seed", range(3))
def test_an_unresolved_loss_reads_elastic_only_with_a_long_still_hold_and_no_dent(seed) -> None:
    still = press_behaviour(_record(seed, hold_s=3.0, creep=0.0))
    assert still.loss_ratio is not None and still.loss_ratio_sigma is not None
    # the loss neither shows nor is ruled out below its floor by 2 σ: the force noise hides it
    assert still.loss_ratio + 2.0 * still.loss_ratio_sigma >= LOSS_FLOOR
    assert still.behaviour == "elastic", still.evidence
    assert "no creep over a hold as long as the loop" in still.evidence
    # a hold shorter than the ramp and the unloading does not bound a slow relaxation's loss
    short = press_behaviour(_record(seed, hold_s=1.5, creep=0.0))
    assert short.behaviour == "unknown", short.evidence
    # a creep of 1 %, below the relaxation floor but above the loss's share of it: not ruled out
    creeping = press_behaviour(_record(seed, hold_s=3.0, creep=0.01))
    assert creeping.relaxation is not None and creeping.relaxation > LOSS_FLOOR / LOSS_PER_CREEP
    assert creeping.behaviour == "unknown", creeping.evidence
