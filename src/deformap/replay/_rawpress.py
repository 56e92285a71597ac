"""Presses found in a force stream: rise over the contact threshold, hold at the commanded force,
release (``docs/robot.md``, "A bag as your robot records it").

Pure arrays: the stream's times and force magnitudes in, one :class:`FoundPress` per press out.
The force's magnitude finds the presses (it needs no frame); the normal component along the press
direction, which needs the transforms, is taken per press by the reader.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["FoundPress", "find_presses"]


@dataclass(frozen=True, kw_only=True)
class FoundPress:
    """One press of the force stream, as sample indices into it.

    Parameters
    ----------
    index : int
        The press's number (0-based, in time order).
    start, end : int
        The first sample over the contact threshold (first contact), and one past the last.
    hold_start, hold_end : int
        The hold (end exclusive): in the longest run of samples within the band around the
        commanded force, from the first sample that reaches the run's mean force to the last;
        both ``-1`` when the force never entered the band.
    error : str or None
        Why the press cannot be used (the force never reached the command, the hold was too short).
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
    """The presses of a force stream.

    Parameters
    ----------
    times_ns : (n,) int
        Sample times, increasing.
    force_n : (n,) float
        The force's magnitude at each sample [N].
    commanded_n : float
        The commanded force; the hold is within ``band · commanded_n`` of it.
    contact_n : float
        Contact threshold [N].
    band : float
    hold_min_ns : int
        A run over the threshold shorter than this is noise (a spike) when it stays below the
        commanded band, and a press too short to read (returned with its error) when it reaches
        it; a hold shorter than this is refused.
    merge_ns : int
        Runs over the threshold closer than this in time are one press (noise around the
        threshold at first contact).
    topic : str
        Names the stream in errors.
    origin_ns : int
        Times in errors are seconds after this one (the bag's start).

    Returns
    -------
    list of FoundPress
        In time order; a press with ``error`` set cannot be used and says why.
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
