"""The appearance axis of many worlds: the blind map and the prior, per appearance family, paired.

A painted world is mapped twice on the same presses (:meth:`deformap.eval.WorldTask.arms`):
``ExplorationConfig.appearance`` off (*blind*) and ``auto`` (*prior*). Per appearance family and
combination, each arm's pokes to :data:`~deformap.eval.GOOD_ACCURACY` (a world never there, or
failed, at ``max_pokes + 1``: the restricted mean of :mod:`deformap.eval._worlds_summary`), its
median final accuracy and the share of worlds whose last map has as many regions as the truth;
and the *paired* difference of the mean pokes, prior − blind over the same worlds, with its 95 %
Student-t interval: the two arms of a world share its layout, its presses' noise and its streams,
so the difference of each world's counts takes out the spread between worlds that the two means
each carry.

References
----------
Student (1908). The probable error of a mean. Biometrika 6(1), 1–25 (the paired t interval).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy import stats

from deformap.errors import InvalidArgumentError

__all__ = ["PAIRED_COLUMNS", "arm_stats", "markdown_paired", "paired_cells", "paired_difference"]


def arm_stats(counts: Sequence[int], finals: Sequence[float], right: Sequence[bool]
              ) -> dict[str, Any]:
    """One arm over a family's worlds: ``counts`` each world's pokes to the good accuracy (the
    cap for a world never there or failed), ``finals`` and ``right`` the final accuracy and
    whether the last map's region count is the truth's, of the worlds that ran."""
    return {"worlds": len(counts),
            "median_pokes_to_accuracy_0.9": float(np.median(counts)) if counts else None,
            "mean_pokes_to_accuracy_0.9": float(np.mean(counts)) if counts else None,
            "final_accuracy_median": float(np.median(finals)) if finals else None,
            "share_right_count": float(np.mean(right)) if right else None}  # fmt: skip


def paired_difference(prior: Sequence[int], blind: Sequence[int]) -> dict[str, Any]:
    """Mean of ``prior[i] − blind[i]`` (each world's pokes to the good accuracy under both
    arms) and its 95 % Student-t interval (``None`` below two worlds).

    Raises
    ------
    InvalidArgumentError
        The two sequences are of different lengths.
    """
    if len(prior) != len(blind):
        raise InvalidArgumentError(f"paired counts must be of one length; got {len(prior)} and "
                         f"{len(blind)}")
    d = np.asarray(prior, float) - np.asarray(blind, float)
    mean = float(d.mean()) if d.size else None
    interval = None
    if d.size >= 2:
        half = float(stats.t.ppf(0.975, d.size - 1) * d.std(ddof=1) / math.sqrt(d.size))
        interval = [float(d.mean()) - half, float(d.mean()) + half]
    return {"paired_worlds": int(d.size), "mean_pokes_difference": mean,
            "mean_pokes_difference_ci95": interval}


def _fmt(value: Any, spec: str) -> str:
    return "–" if value is None else format(value, spec)


def paired_cells(entry: Mapping[str, Any]) -> list[str]:
    """One family × combination of ``summary["appearance"]`` as table cells: worlds, median and
    mean pokes to 0.9 blind and with the prior, the paired difference with its interval, final
    accuracy and right region count, blind and with the prior."""
    blind, prior = entry.get("blind") or {}, entry["prior"]
    ci = entry.get("mean_pokes_difference_ci95")
    both = lambda key, spec: (f"{_fmt(blind.get(key), spec)} / "  # noqa: E731
                              f"{_fmt(prior.get(key), spec)}")
    return [str(prior["worlds"]), both("median_pokes_to_accuracy_0.9", "g"),
            both("mean_pokes_to_accuracy_0.9", ".1f"),
            _fmt(entry.get("mean_pokes_difference"), "+.2f")
            + ("" if ci is None else f" ({ci[0]:+.2f} to {ci[1]:+.2f})"),
            both("final_accuracy_median", ".3f"), both("share_right_count", ".0%")]


#: The columns of :func:`paired_cells`, after the family and the combination.
PAIRED_COLUMNS = ("worlds", "median pokes to 0.9, blind / prior", "mean, blind / prior",
                  "mean difference, prior − blind (95 % t interval)",
                  "final accuracy, blind / prior", "right region count, blind / prior")


def markdown_paired(summary: Mapping[str, Any]) -> str:
    """``summary["appearance"]`` as a markdown table (one row per appearance family ×
    combination), or ``""`` where no family was mapped blind beside the prior."""
    families = summary.get("appearance", {})
    if not any(e.get("blind") for per in families.values() for e in per.values()):
        return ""
    head = ["appearance", "combination", *PAIRED_COLUMNS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for family, per in families.items():
        for name, entry in per.items():
            lines.append("| " + " | ".join([family, name, *paired_cells(entry)]) + " |")
    k = summary["max_pokes"]
    lines.append("")
    lines.append(f"Each painted world mapped twice on the same presses: blind "
                 f"(exploration.appearance off) and with the appearance prior (auto). Pokes to "
                 f"region accuracy {summary['good_accuracy']:g} (a world that never reaches it "
                 f"counts {k + 1}); the difference is the mean over the same worlds of each "
                 f"world's prior − blind count; final accuracy (median) and the share of worlds "
                 f"with the true region count after {k} pokes.")
    return "\n".join(lines) + "\n"
