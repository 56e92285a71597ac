"""What many worlds say: ``runs.csv``, accuracy against pokes per family, ``summary.json`` and its
markdown table.

A *combination* is one strategy × field × cut, named ``strategy/field/cut``. Its pokes to a good
map in one world are the first poke after which the region accuracy is at least
:data:`GOOD_ACCURACY`; a world where it never is (or that failed) counts ``max_pokes + 1``, so a
median over worlds is never flattered by leaving the hard ones out. A map can lose that accuracy
with later pokes (a new poke can split a region wrongly), which a robot that stops could not
know: ``median_pokes_to_stay_0.9`` counts from the poke after which every later one keeps it.
A combination whose loop had nothing left to poke before ``max_pokes`` keeps its last map for the
remaining pokes.

Which combination is best. With many worlds at ``max_pokes + 1`` the median sits on a cap and
moves by a poke or two with a few worlds. ``best`` is therefore the combination
with the fewest pokes on average, ``mean_pokes_to_accuracy_0.9``: the restricted mean of the same
counts (survival analysis' restricted mean time to an event, here bounded at ``max_pokes + 1``),
which every world moves by its own count; ties go to the smaller median, then the higher median
final accuracy. ``median_pokes_ci95`` is the median's 95 % percentile-bootstrap interval over the
worlds (resampled with a fixed seed: the summary stays a function of the results).

References
----------
Royston, P., Parmar, M. K. B. (2013). Restricted mean survival time: an alternative to the hazard
ratio for the design and analysis of randomized trials with a time-to-event outcome. BMC Medical
Research Methodology 13, 152. Efron, B., Tibshirani, R. J. (1993). An Introduction to the
Bootstrap, ch. 13 (percentile intervals).

Appearance. Each row names its appearance family and ``prior`` (the arm's
``ExplorationConfig.appearance``); ``strategies`` and the curves per layout family count each
world once per appearance family, mapped with the prior (``auto``, the exploration's default);
``appearance`` sets the blind map beside it per appearance family (:mod:`._worlds_paired`).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError
from deformap.eval._world_draw import PRIORS
from deformap.eval._world_result import WorldResult
from deformap.eval._worlds_paired import _fmt, arm_stats, markdown_paired, paired_difference

__all__ = [
    "CSV_COLUMNS",
    "GOOD_ACCURACY",
    "PLAIN_ARMS",
    "accuracy_curves",
    "combination_name",
    "markdown_summary",
    "pokes_to_good",
    "runs_csv",
    "summarise_worlds",
]

#: The region accuracy a map must reach: the benchmark counts the pokes a good map takes.
GOOD_ACCURACY = 0.9
#: The arms of a benchmark of plain worlds (:meth:`deformap.eval.WorldTask.arms`).
PLAIN_ARMS = (("plain", "auto"),)

Arm = tuple[str, str]

_WORLD_COLUMNS = ("physics", "camera", "thickness_m", "force_n")
_ROW_COLUMNS = ("appearance", "prior", "strategy", "field", "cut", "poke", "purpose",
                "map_field", "threshold", "accuracy", "mean_iou", "found", "true", "kendall_tau",
                "modulus_error", "beta_spread", "poke_s", "elapsed_s")  # fmt: skip
#: Columns of ``runs.csv``: one row per world × arm × strategy × field × cut × poke (a failed world:
#: one row per arm × combination, ``poke`` empty, ``status`` failed with its ``error``).
CSV_COLUMNS = ("world", "family", *_WORLD_COLUMNS, *_ROW_COLUMNS, "status", "error")


def combination_name(strategy: str, field: str, cut: str) -> str:
    """``strategy/field/cut``."""
    return f"{strategy}/{field}/{cut}"


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else ""
    return str(value)


def runs_csv(results: Sequence[WorldResult], combinations: Sequence[tuple[str, str, str]],
             arms: Sequence[Arm] = PLAIN_ARMS) -> str:
    """``runs.csv`` of the worlds' results (in world order), as text; ``arms`` the
    ``(appearance, prior)`` each world was mapped under (a failed world's rows)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for result in sorted(results, key=lambda r: r.world["index"]):
        world = result.world
        head = [world["index"], world["family"], *(world.get(k) for k in _WORLD_COLUMNS)]
        if result.status != "ok":
            for arm in arms:
                for combination in combinations:
                    writer.writerow([_cell(v) for v in (*head, *arm, *combination)]
                                    + [""] * (len(_ROW_COLUMNS) - 5) + ["failed", result.error])
            continue
        for row in result.rows:
            writer.writerow([_cell(v) for v in (*head, *(row[k] for k in _ROW_COLUMNS))]
                            + ["ok", ""])
    return buffer.getvalue()


def _series(rows: list[dict[str, Any]], key: str, max_pokes: int) -> NDArray[np.float64]:
    """``key`` after pokes 1..max_pokes (the last map carried on; NaN for None)."""
    out = np.full(max_pokes, np.nan)
    last = np.nan
    by_poke = {int(r["poke"]): r.get(key) for r in rows}
    for k in range(1, max_pokes + 1):
        if k in by_poke:
            value = by_poke[k]
            last = np.nan if value is None else float(value)
        out[k - 1] = last
    return out


def _per_world(results: Sequence[WorldResult], combination: tuple[str, str, str],
               max_pokes: int, arms: Sequence[Arm] = PLAIN_ARMS) -> list[dict[str, Any]]:
    """One entry per world and arm for one combination: index, layout family, arm, accuracy
    and modulus-error series, and whether the last map has the true region count."""
    out = []
    for result in results:
        world = result.world
        for appearance, prior in arms:
            entry = {"index": int(world["index"]), "family": world["family"],
                     "appearance": appearance, "prior": prior, "failed": True}
            if result.status == "ok":
                rows = [r for r in result.rows
                        if (r["strategy"], r["field"], r["cut"]) == combination
                        and (r["appearance"], r["prior"]) == (appearance, prior)]
                found, true = (_series(rows, k, max_pokes)[-1] for k in ("found", "true"))
                entry.update(failed=False, accuracy=_series(rows, "accuracy", max_pokes),
                             modulus_error=_series(rows, "modulus_error", max_pokes),
                             right_count=bool(found == true))
            out.append(entry)
    return out


def _pokes_to_good(entry: dict[str, Any], max_pokes: int, *, stay: bool = False) -> int:
    """The first poke with accuracy ≥ :data:`GOOD_ACCURACY` (``stay``: from which every later
    poke keeps it); ``max_pokes + 1`` when there is none."""
    if entry["failed"]:
        return max_pokes + 1
    good = entry["accuracy"] >= GOOD_ACCURACY
    if stay:
        bad = np.flatnonzero(~good)
        first = 0 if not bad.size else int(bad[-1]) + 1
        return first + 1 if first < max_pokes else max_pokes + 1
    hits = np.flatnonzero(good)
    return int(hits[0]) + 1 if hits.size else max_pokes + 1


def pokes_to_good(results: Sequence[WorldResult], combination: tuple[str, str, str],
                  max_pokes: int, arm: Arm = PLAIN_ARMS[0]) -> dict[int, int]:
    """Each world's pokes to :data:`GOOD_ACCURACY` under one combination and ``arm``
    (``(appearance, prior)``), by world index (``max_pokes + 1`` where never, or where the world
    failed): what ``summary.json``'s medians are taken over, for comparing two combinations
    world by world."""
    return {e["index"]: _pokes_to_good(e, max_pokes)
            for e in _per_world(results, combination, max_pokes, [arm])}


def _median(values: Sequence[float]) -> float | None:
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.median(finite)) if finite else None


#: Resamples of the median's bootstrap interval, and their fixed seed.
_BOOTSTRAP = 2000
_BOOTSTRAP_SEED = 0


def _median_interval(counts: Sequence[int]) -> list[float] | None:
    """The 95 % percentile-bootstrap interval of the median of ``counts`` (None without any)."""
    if not counts:
        return None
    # sorted: the same interval whatever order the worlds finished in
    values = np.sort(np.asarray(counts, dtype=float))
    draws = np.random.default_rng(_BOOTSTRAP_SEED).integers(0, values.size,
                                                            (_BOOTSTRAP, values.size))
    medians = np.median(values[draws], axis=1)
    # bounds that are medians a resample gave (no interpolation between two of them)
    return [float(np.percentile(medians, 2.5, method="lower")),
            float(np.percentile(medians, 97.5, method="higher"))]


def _stats(entries: list[dict[str, Any]], max_pokes: int) -> dict[str, Any]:
    done = [e for e in entries if not e["failed"]]
    counts = [_pokes_to_good(e, max_pokes) for e in entries]
    return {
        "median_pokes_to_accuracy_0.9": _median(counts),
        "median_pokes_ci95": _median_interval(counts),
        # every world's count, a never (or failed) one at max_pokes + 1: module docstring
        "mean_pokes_to_accuracy_0.9": float(np.mean(counts)) if counts else None,
        "median_pokes_to_stay_0.9": _median([_pokes_to_good(e, max_pokes, stay=True)
                                             for e in entries]),
        # when most worlds never get there the medians saturate at max_pokes + 1; the share does not
        "share_reaching_0.9": (sum(c <= max_pokes for c in counts) / len(counts)
                               if counts else None),
        "final_accuracy_median": _median([float(e["accuracy"][-1]) for e in done]),
        "modulus_error_median": _median([float(e["modulus_error"][-1]) for e in done]),
        "worlds": len(entries),
        "failed": len(entries) - len(done),
    }


def summarise_worlds(results: Sequence[WorldResult],
                     combinations: Sequence[tuple[str, str, str]], max_pokes: int,
                     arms: Sequence[Arm] = PLAIN_ARMS) -> dict[str, Any]:
    """``summary.json``: ``{"strategies": {NAME: {STAT: …, "by_family": {FAMILY: {STAT: …}}}}}``
    (NAME a :func:`combination_name`, STAT the keys of :func:`_stats`) with ``best`` (module
    docstring), ``max_pokes``, ``failed_worlds`` (index and error of each world that failed twice)
    and ``appearance`` (:func:`_appearance`); ``arms`` the ``(appearance, prior)`` each world was
    mapped under, ``strategies`` counting each world once per appearance family, under the prior."""
    # by index, whatever order the worlds finished in
    results = sorted(results, key=lambda r: int(r.world["index"]))
    strategies: dict[str, Any] = {}
    own = [arm for arm in arms if arm[1] == PRIORS[1]]
    for combination in combinations:
        entries = _per_world(results, combination, max_pokes, own)
        families = sorted({e["family"] for e in entries})
        strategies[combination_name(*combination)] = {
            **_stats(entries, max_pokes),
            "by_family": {f: _stats([e for e in entries if e["family"] == f], max_pokes)
                          for f in families},
        }  # fmt: skip

    def rank(name: str) -> tuple[float, float, float]:
        s = strategies[name]
        mean, median = s["mean_pokes_to_accuracy_0.9"], s["median_pokes_to_accuracy_0.9"]
        final = s["final_accuracy_median"]
        return (math.inf if mean is None else mean, math.inf if median is None else median,
                -(final if final is not None else -1.0))

    best = min(strategies, key=rank) if strategies else None
    return {"strategies": strategies, "best": best, "max_pokes": max_pokes,
            "good_accuracy": GOOD_ACCURACY,
            "failed_worlds": [{"index": r.world["index"], "error": r.error}
                              for r in results if r.status != "ok"],
            "appearance": _appearance(results, combinations, max_pokes, arms)}  # fmt: skip


def _appearance(results: Sequence[WorldResult], combinations: Sequence[tuple[str, str, str]],
                max_pokes: int, arms: Sequence[Arm]) -> dict[str, Any]:
    """``{APPEARANCE: {NAME: {"blind": …, "prior": …, "paired_worlds",
    "mean_pokes_difference", "mean_pokes_difference_ci95"}}}``: each arm's
    :func:`~deformap.eval._worlds_paired.arm_stats` (``blind`` ``None`` for a family mapped
    under the prior only) and the paired difference of the pokes to :data:`GOOD_ACCURACY`,
    prior − blind, over the same worlds (:mod:`._worlds_paired`)."""
    out: dict[str, Any] = {}
    for appearance in dict.fromkeys(a for a, _ in arms):
        per: dict[str, Any] = {}
        for combination in combinations:
            counts: dict[str, list[int]] = {}
            entry: dict[str, Any] = {"blind": None}
            for prior, name in zip(PRIORS, ("blind", "prior"), strict=True):
                if (appearance, prior) not in arms:
                    continue
                entries = _per_world(results, combination, max_pokes, [(appearance, prior)])
                done = [e for e in entries if not e["failed"]]
                counts[name] = [_pokes_to_good(e, max_pokes) for e in entries]
                entry[name] = arm_stats(counts[name], [float(e["accuracy"][-1]) for e in done],
                                        [e["right_count"] for e in done])
            entry.update(paired_difference(counts["prior"], counts["blind"]) if "blind" in counts
                         else {"paired_worlds": 0, "mean_pokes_difference": None,
                               "mean_pokes_difference_ci95": None})
            per[combination_name(*combination)] = entry
        out[appearance] = per
    return out


def accuracy_curves(results: Sequence[WorldResult],
                    combinations: Sequence[tuple[str, str, str]], max_pokes: int, *,
                    arms: Sequence[Arm] = PLAIN_ARMS, prior: str = PRIORS[1],
                    by: str = "layout") -> dict[str, dict[str, NDArray[np.float64]]]:
    """Per family, per combination: the ``(n_worlds, max_pokes)`` accuracies of the worlds that
    ran under ``prior`` (``"off"``: the blind map, of the painted families of ``arms``), the
    figure's bands come from these. ``by``: ``"layout"``, the layout families and ``"all"`` (each
    world once per appearance family); ``"appearance"``, the appearance families."""
    if by not in ("layout", "appearance"):
        raise InvalidArgumentError(f"`by` must be 'layout' or 'appearance'; got {by!r}")
    key = "family" if by == "layout" else "appearance"
    chosen_arms = [arm for arm in arms if arm[1] == prior]
    out: dict[str, dict[str, NDArray[np.float64]]] = {}
    for combination in combinations:
        entries = [e for e in _per_world(results, combination, max_pokes, chosen_arms)
                   if not e["failed"]]
        panels = (["all", *sorted({e[key] for e in entries})] if by == "layout"
                  else list(dict.fromkeys(e[key] for e in entries)))
        for family in panels:
            chosen = [e["accuracy"] for e in entries if family in ("all", e[key])]
            out.setdefault(family, {})[combination_name(*combination)] = (
                np.array(chosen).reshape(-1, max_pokes))
    return out


def _interval(ci: Sequence[float] | None) -> str:
    return "" if ci is None else f" ({ci[0]:g}–{ci[1]:g})"


def markdown_summary(summary: dict[str, Any]) -> str:
    """The summary as a markdown table: one row per combination, overall and per family."""
    k = summary["max_pokes"]
    families = sorted({f for s in summary["strategies"].values() for f in s["by_family"]})
    head = ["combination", "worlds", "median pokes to 0.9 (95 % interval)", "mean pokes to 0.9",
            "to stay at 0.9", "reach 0.9", "final accuracy", "E error", *families]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, s in summary["strategies"].items():
        per = [_fmt(s["by_family"].get(f, {}).get("median_pokes_to_accuracy_0.9"), "g")
               for f in families]  # fmt: skip
        mark = " (best)" if name == summary["best"] else ""
        lines.append("| " + " | ".join([
            f"{name}{mark}", f"{s['worlds']}" + (f" ({s['failed']} failed)" if s["failed"] else ""),
            _fmt(s["median_pokes_to_accuracy_0.9"], "g") + _interval(s.get("median_pokes_ci95")),
            _fmt(s.get("mean_pokes_to_accuracy_0.9"), ".1f"),
            _fmt(s.get("median_pokes_to_stay_0.9"), "g"),
            _fmt(s.get("share_reaching_0.9"), ".0%"), _fmt(s["final_accuracy_median"], ".3f"),
            _fmt(s["modulus_error_median"], ".2f"), *per]) + " |")  # fmt: skip
    lines.append("")
    lines.append(f"Pokes to region accuracy {summary['good_accuracy']:g} (median over worlds, "
                 f"with its 95 % bootstrap interval, and mean; a world that never reaches it "
                 f"counts {k + 1}; best: the fewest mean pokes); to stay: from the poke after which "
                 "it stays there; reach: the share of worlds that reach it by the last poke; "
                 "final accuracy and the modulus "
                 f"field's median relative E error after {k} pokes; the family columns are "
                 "median pokes to 0.9.")
    paired = markdown_paired(summary)
    return "\n".join(lines) + "\n" + ("\n" + paired if paired else "")
