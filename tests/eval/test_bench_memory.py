"""The memory benchmark: its rows' keys, baselines, and a fresh process per case."""

from __future__ import annotations

import sys

import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval._bench_memory import bench_memory, measure_case

ROW_KEYS = {"case", "size", "traced_peak_mib", "rss_before_mib", "rss_peak_mib", "rss_added_mib",
            "seconds", "baseline"}  # fmt: skip


def test_bench_memory_rows_in_process() -> None:
    result = bench_memory(gp_sizes=(60, 1000), exact_max_points=1000, beta_side=6, isolate=False)
    assert set(result) == {"surface_gp", "beta_estimation"}
    gp, beta = result["surface_gp"], result["beta_estimation"]
    assert [(r["case"], r["size"]) for r in gp] == [("gp-exact", 60), ("gp-exact", 1000),
                                                   ("gp-grid", 60), ("gp-grid", 1000)]  # fmt: skip
    assert [(r["case"], r["size"]) for r in beta] == [("beta-loop", 6), ("beta-batched", 6)]
    for row in gp + beta:
        assert set(row) == ROW_KEYS
        assert row["traced_peak_mib"] > 0 and row["seconds"] > 0
        assert row["rss_added_mib"] is None  # this process's history would count
    assert [r["baseline"] for r in gp] == [None, None, "gp-exact", "gp-exact"]
    assert [r["baseline"] for r in beta] == [None, "beta-loop"]
    # what the benchmark shows: the exact GP's peak grows at least by its N × N covariance
    # (float64), the grid GP's much less
    peak = {(r["case"], r["size"]): r["traced_peak_mib"] for r in gp}
    covariance_growth_mib = (1000**2 - 60**2) * 8 / 2**20
    assert peak["gp-exact", 1000] - peak["gp-exact", 60] > covariance_growth_mib
    assert peak["gp-grid", 1000] - peak["gp-grid", 60] < covariance_growth_mib / 2


def test_a_case_in_a_fresh_process_reports_its_resident_set() -> None:
    row = measure_case("gp-grid", 60, seed=1)
    assert set(row) == ROW_KEYS and row["traced_peak_mib"] > 0
    if sys.platform.startswith("linux"):
        # the child imported numpy and scipy before measuring, then allocated its arrays
        assert row["rss_before_mib"] > 10
        assert row["rss_peak_mib"] > row["rss_before_mib"] and row["rss_added_mib"] > 0


def test_bad_cases_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="`case` must be one of"):
        measure_case("gp-fast", 100)
    with pytest.raises(InvalidArgumentError, match="`size`"):
        measure_case("beta-batched", 2)
