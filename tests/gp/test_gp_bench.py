from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval._bench_gp import bench_surface_gp


def test_bench_rows_have_the_contract_keys_and_grid_is_near_exact() -> None:
    rows = bench_surface_gp((300,), rng=np.random.default_rng(0))
    assert [set(r) for r in rows] == [
        {"n_points", "exact_s", "grid_s", "speedup", "max_mean_dev_m", "max_rel_std_dev"}
    ]
    row = rows[0]
    assert row["n_points"] == 300
    assert row["exact_s"] > 0 and row["grid_s"] > 0
    assert row["speedup"] == pytest.approx(row["exact_s"] / row["grid_s"])
    assert row["max_mean_dev_m"] <= 10e-6
    assert row["max_rel_std_dev"] <= 0.01


def test_bench_refuses_bad_input() -> None:
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        bench_surface_gp((300,), rng=0)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match=r"`n_points_list\[i\]`"):
        bench_surface_gp((1,), rng=np.random.default_rng(0))
