from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval._bench_io import IO_GOAL_S, bench_io


def test_bench_io_reports_every_timing_on_a_small_cloud() -> None:
    pytest.importorskip("rosbags")
    result = bench_io(n_points=2000, rng=np.random.default_rng(0), repeats=1)
    assert result["n_points"] == 2000 and result["goal_s"] == IO_GOAL_S
    for key in ("pcd_read_s", "pcd_read_median_s", "pointcloud2_read_s", "bag_read_s"):
        assert 0 < result[key] < 30, key


def test_bench_io_refuses_bad_arguments() -> None:
    with pytest.raises(InvalidArgumentError, match=r"`rng` must be a numpy\.random\.Generator"):
        bench_io(n_points=10, rng=0)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`n_points` must be an integer >= 1"):
        bench_io(n_points=0, rng=np.random.default_rng(0))
