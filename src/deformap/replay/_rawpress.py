"""Presses found in a force stream: rise over the contact threshold, hold at the commanded force,
release (``docs/robot.md``). Pure arrays: times and force magnitudes in, one :class:`FoundPress`
per press out."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["FoundPress", "find_presses"]


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
