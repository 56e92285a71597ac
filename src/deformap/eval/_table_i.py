"""The paper's Table I (interactions, T_h, β-regions) and the reproduction table beside it: one
row from one run's report, and the markdown (the runs are :func:`deformap.run.reproduce`'s).
"""

from __future__ import annotations

from typing import Any

__all__ = ["PAPER_TABLE_I", "markdown_table", "table_row"]

PAPER_TABLE_I: dict[str, dict[str, Any]] = {
    "homogeneous-60": {"interactions": 3, "threshold": 0.06, "regions": 1},
    "homogeneous-110": {"interactions": 3, "threshold": 0.06, "regions": 1},
    "heterogeneous-60-150": {"interactions": 4, "threshold": 0.06, "regions": 2},
    "heterogeneous-110-150": {"interactions": 4, "threshold": 0.06, "regions": 2},
    "heterogeneous-150-rigid": {"interactions": 4, "threshold": 0.06, "regions": 2},
    "heterogeneous-60-110-rigid": {"interactions": 4, "threshold": 0.06, "regions": 3},
}
"""Caccamo et al. 2016, Table I."""


def table_row(scenario: str, report: dict[str, Any], *, threshold: float) -> dict[str, Any]:
    """One row of the reproduction table from a live run's ``report`` (its T_h ``threshold``)."""
    reg, t = report["regions"], report["timings"]
    return {
        "scenario": scenario, "paper": PAPER_TABLE_I.get(scenario), "pokes": report["n_pokes"],
        "threshold": threshold, "stop_reason": report["stop_reason"],
        "regions_found": reg["found"], "regions_true": reg["true"], "accuracy": reg["accuracy"],
        "mean_iou": reg["mean_iou"], "kendall_tau": reg["kendall_tau"],
        "time_s": t["total_s"] + t["world_build_s"],
        "max_compute_per_poke_s": max(t["per_poke_compute_s"], default=0.0),
    }  # fmt: skip


def markdown_table(result: dict[str, Any]) -> str:
    """The reproduction table in markdown (``result``: ``{"seed", "strategy", "rows"}``)."""
    head = ("| scenario | paper: pokes | paper: T_h | paper: regions | pokes "
            "| regions found / true | region accuracy | mean IoU | Kendall τ | time [s] |\n"
            "|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in result["rows"]:
        paper = r["paper"] or {"interactions": "–", "threshold": "–", "regions": "–"}
        tau = "–" if r["kendall_tau"] is None else f"{r['kendall_tau']:.2f}"
        lines.append(f"| {r['scenario']} | {paper['interactions']} | {paper['threshold']} "
                     f"| {paper['regions']} | {r['pokes']} | {r['regions_found']} / "
                     f"{r['regions_true']} | {r['accuracy']:.3f} | {r['mean_iou']:.3f} | {tau} "
                     f"| {r['time_s']:.1f} |")
    note = (f"\nSeed {result['seed']}, strategy `{result['strategy']}`; time includes building "
            "the simulated world (FEM factorisation) and its presses.\n")
    return head + "\n".join(lines) + "\n" + note
