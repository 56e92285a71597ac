"""Presses found in a force stream: rise over the contact threshold, hold at the commanded force,
release (``docs/robot.md``). Pure arrays: times and force magnitudes in, one :class:`FoundPress`
per press out; a press's samples become its force–travel record (:func:`press_record`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.environment import ForceTravel, PressPhase
from deformap.errors import DeformapError

__all__ = ["CONTACT_NOISE_MULTIPLE", "FoundPress", "NoiseFloor", "block_means", "block_size",
           "contact_threshold", "find_presses", "noise_floor", "onset", "press_record"]

#: The contact threshold is this many times the noise's rms magnitude: a sample of noise alone
#: crosses it with probability below 6.4e-5 (P(|Z| > 4) with all the noise on one axis; far less
#: when three axes share it, χ²₃ > 48: 3e-10), and a crossing shorter than ``hold_min_s`` that
#: does not reach the commanded force is ignored as a spike.
CONTACT_NOISE_MULTIPLE = 4.0

#: A sensor whose noise cannot be measured (a quantised or simulated one) gets a threshold of
#: this fraction of the commanded force, the force controller's own resolution.
MIN_CONTACT_FRACTION = 0.01


@dataclass(frozen=True)
class NoiseFloor:
    """The force sensor's noise with the probe free, per axis [N] (``std``), the reading then
    (``baseline``), from ``n_samples`` quiet samples in ``n_windows`` spans before presses."""

    std: NDArray[np.float64]
    baseline: NDArray[np.float64]
    n_samples: int
    n_windows: int

    @property
    def rms_n(self) -> float:
        """The rms magnitude of the noise vector [N]."""
        return float(np.sqrt(np.sum(self.std**2)))


def _clipped(samples: NDArray[np.float64]) -> NDArray[np.bool_]:
    """The samples within 4 robust σ of the median on every axis, the σ re-estimated on the
    kept ones until nothing changes (the quiet part of a span that also holds a ramp's foot)."""
    keep = np.ones(len(samples), dtype=bool)
    for _ in range(20):
        kept = samples[keep]
        med = np.median(kept, axis=0)
        sigma = 1.4826 * np.median(np.abs(kept - med), axis=0)
        new = np.asarray((np.abs(samples - med) <= 4.0 * np.maximum(sigma, 1e-12)).all(axis=1))
        if (new == keep).all() or new.sum() < 3:
            break
        keep = new
    return keep


def noise_floor(force: NDArray[np.float64]) -> NoiseFloor:
    """The noise of the force stream ``force (n, 3)`` with the probe free: in the span before
    each press (from the end of the last run over half the stream's 99th-percentile magnitude,
    the presses' force whatever was commanded, to the start of the next), the samples that sigma
    clipping keeps; ``std`` per axis is the median over the spans of their standard deviations,
    ``baseline`` the first span's median (the sensor's offset)."""
    mag = np.linalg.norm(force, axis=1)
    runs = _runs(mag > float(np.percentile(mag, 99)) / 2)
    starts = [0] + [end for _, end in runs]
    ends = [start for start, _ in runs] + [len(force)]
    stds, bases, count = [], [], 0
    for a, b in zip(starts, ends, strict=True):
        if b - a < 10:
            continue
        span = force[a:b]
        keep = _clipped(span)
        if keep.sum() < 10:
            continue
        stds.append(span[keep].std(axis=0, ddof=1))
        bases.append(np.median(span[keep], axis=0))
        count += int(keep.sum())
    if not stds:
        return NoiseFloor(np.zeros(3), np.zeros(3), 0, 0)
    return NoiseFloor(np.median(np.array(stds), axis=0), bases[0], count, len(stds))


def contact_threshold(noise: NoiseFloor, commanded_n: float) -> float:
    """:data:`CONTACT_NOISE_MULTIPLE` times the noise's rms magnitude, at least
    :data:`MIN_CONTACT_FRACTION` of the commanded force."""
    return max(CONTACT_NOISE_MULTIPLE * noise.rms_n, MIN_CONTACT_FRACTION * commanded_n)


@dataclass(frozen=True, kw_only=True)
class FoundPress:
    """One press, as sample indices into the force stream.

    ``index`` numbers it (0-based, in time order); ``start`` is first contact and ``end`` one past the
    last sample over the threshold. The hold ``[hold_start, hold_end)`` runs, in the longest run of
    samples within the band around the commanded force, from the first sample reaching the run's mean
    to the last (``-1`` when the force never entered the band). ``error`` says why it is unusable.
    """

    index: int
    start: int
    end: int
    hold_start: int = -1
    hold_end: int = -1
    error: str | None = None


def _runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``(start, end)`` of each run of True (end exclusive)."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(),
                    strict=True))  # fmt: skip


def find_presses(times_ns: NDArray[np.int64], force_n: NDArray[np.float64], *, commanded_n: float,
                 contact_n: float, band: float, hold_min_ns: int, merge_ns: int, topic: str,
                 origin_ns: int = 0) -> list[FoundPress]:
    """The presses of a force stream (``times_ns`` increasing, ``force_n`` magnitudes [N]), in
    time order, a press that cannot be used carrying its error.

    Runs over ``contact_n`` closer than ``merge_ns`` are one press; one shorter than ``hold_min_ns``
    is a spike when it stays below the band ``commanded_n · (1 ± band)`` and a press too short when
    it reaches it; a hold shorter than ``hold_min_ns`` is refused. ``topic`` names the stream and
    times in errors are seconds after ``origin_ns``.
    """
    runs = _runs(force_n > contact_n)
    merged: list[list[int]] = []
    for start, end in runs:
        if merged and times_ns[start] - times_ns[merged[-1][1] - 1] < merge_ns:
            merged[-1][1] = end
        else:
            merged.append([start, end])
    presses: list[FoundPress] = []
    lo, hi = commanded_n * (1 - band), commanded_n * (1 + band)
    for start, end in merged:
        index = len(presses)
        seg = force_n[start:end]
        # numbered from 1 in messages, as the pokes and their files are
        where = (f"press {index + 1} (t = {(times_ns[start] - origin_ns) / 1e9:.3f}–"
                 f"{(times_ns[end - 1] - origin_ns) / 1e9:.3f} s on {topic!r})")  # fmt: skip
        lasted = int(times_ns[end - 1] - times_ns[start])
        if lasted < hold_min_ns:
            if float(seg.max()) < lo:  # a spike of sensor noise over the threshold
                continue
            # it reached the commanded force: a press too short to read, said, not dropped
            presses.append(FoundPress(index=index, start=start, end=end, error=(
                f"{where}: over the contact threshold for only {lasted / 1e9:.3f} s; at least "
                f"{hold_min_ns / 1e9:g} s expected (`hold_min_s`)")))
            continue
        holds = _runs((seg >= lo) & (seg <= hi))
        if not holds:
            presses.append(FoundPress(index=index, start=start, end=end, error=(
                f"{where}: the force never reached the commanded {commanded_n:.4g} N (within "
                f"{band:.0%}); it peaked at {float(seg.max()):.4g} N")))
            continue
        h0, h1 = max(holds, key=lambda r: times_ns[start + r[1] - 1] - times_ns[start + r[0]])
        h0, h1 = start + h0, start + h1
        # held from the first sample that reaches the force held (the band's top of the ramp is
        # still rising, the dent still forming) to the last one before the release
        settled = np.flatnonzero(force_n[h0:h1] >= force_n[h0:h1].mean())
        h0, h1 = h0 + int(settled[0]), h0 + int(settled[-1]) + 1
        held = int(times_ns[h1 - 1] - times_ns[h0])
        error = None
        if held < hold_min_ns:
            error = (f"{where}: held the commanded {commanded_n:.4g} N for {held / 1e9:.3f} s; "
                     f"at least {hold_min_ns / 1e9:g} s expected (`hold_min_s`)")
        presses.append(FoundPress(index=index, start=start, end=end, hold_start=h0, hold_end=h1,
                                  error=error))  # fmt: skip
    return presses


def block_size(n: int, noise_n: float, rise_n: float) -> int:
    """The fewest samples ``k`` whose mean rises, along a ramp of ``n`` samples rising by
    ``rise_n``, by four times its noise (``noise_n / √k``) from one block to the next:
    ``k = ⌈(4 n noise / rise)^(2/3)⌉``, between 1 and a third of the samples."""
    if n < 3 or rise_n <= 0.0 or noise_n <= 0.0:
        return 1
    return max(1, min(int(np.ceil((4.0 * n * noise_n / rise_n) ** (2.0 / 3.0))), n // 3))


def block_means(travel: NDArray[np.float64], force: NDArray[np.float64], noise_n: float
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """A ramp's samples after the first (contact, kept as it is) averaged in consecutive blocks
    of :func:`block_size`, so that noise cannot make the record step back. Unchanged when the
    block is one sample."""
    n = len(force) - 1
    k = block_size(n, noise_n, float(force[-1] - force[0]))
    if k <= 1:
        return travel, force
    blocks = n // k
    # the blocks end at the last sample (the force reached); the first few left over join none
    skip = n - blocks * k
    rest_t = travel[1 + skip:].reshape(blocks, k).mean(axis=1)
    rest_f = force[1 + skip:].reshape(blocks, k).mean(axis=1)
    return np.concatenate([travel[:1], rest_t]), np.concatenate([force[:1], rest_f])


def press_record(travel: NDArray[np.float64], force: NDArray[np.float64],
                 seconds: NDArray[np.float64], noise_n: float, notes: dict[str, Any],
                 hold: tuple[NDArray[np.float64], ...]) -> ForceTravel | None:
    """The record of a press: its ramp's ``travel``, ``force`` and ``seconds`` since first contact
    (one per sample), averaged by :func:`block_means`, and as its hold the samples ``hold`` =
    ``(seconds, travel, force)`` from the one after the ramp's last (the first to reach the force
    held) to the end of the hold, as they are. No unloading: the record stops where the hold does.

    Ramp samples the record refuses leave none, ``notes["force_travel"]`` saying why (β then comes
    from the camera alone); times that do not increase (a repeated stamp) or a hold it refuses
    leave the ramp alone, ``notes["record_times"]`` saying why."""
    ramp_travel, ramp_force = block_means(travel, force, noise_n)
    ramp_seconds = block_means(seconds, force, noise_n)[0]  # the same blocks
    try:
        ramp = ForceTravel(travel_m=ramp_travel, force_n=ramp_force)
    except DeformapError as exc:
        # a force step, or a ramp the sensor's noise hides: the camera still reads the dent
        notes["force_travel"] = (f"the ramp's force–travel record cannot be read ({exc}); "
                                 "β from the camera alone, no modulus")
        return None
    try:
        phase = (PressPhase(time_s=hold[0], travel_m=hold[1], force_n=hold[2])
                 if len(hold[0]) >= 2 else None)
        return ForceTravel(travel_m=ramp.travel_m, force_n=ramp.force_n, time_s=ramp_seconds,
                           hold=phase)
    except DeformapError as exc:
        notes["record_times"] = f"the record keeps its ramp alone, without times ({exc})"
        return ramp


def onset(force: NDArray[np.float64], start: int, floor: int, noise: NoiseFloor, k: int) -> int:
    """The sample of first contact: from ``start`` (the first over the contact threshold) back
    towards ``floor``, the earliest sample whose ``k`` readings up to it, less the sensor's
    ``baseline``, still average more than :data:`CONTACT_NOISE_MULTIPLE` times that mean's noise
    (``rms / √k``): the foot of the ramp that the threshold on single samples cuts off. The
    window looks back, so noise cannot put contact before the force began to rise."""
    if noise.rms_n <= 0.0 or start - k <= floor:
        return start
    level = CONTACT_NOISE_MULTIPLE * noise.rms_n / np.sqrt(k)
    seg = force[floor: start + 1] - noise.baseline
    csum = np.concatenate([np.zeros((1, 3)), np.cumsum(seg, axis=0)])
    i = start - floor  # the window of sample i is seg[i - k + 1 : i + 1]
    while i - k >= 0 and float(np.linalg.norm((csum[i] - csum[i - k]) / k)) > level:
        i -= 1
    return floor + i
