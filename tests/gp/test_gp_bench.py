"""The surface-GP benchmark: the deviations it reports are the grid GP's from the exact GP on its
own data (recomputed here), small, and not zero (two different algorithms ran); timings are real."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.eval import _bench_gp as bench
from deformap.gp import GaussianRandomField


def _exact_and_grid(n: int, seed: int) -> tuple[np.ndarray, ...]:
    """The benchmark's problem rebuilt from its documented recipe, both paths fitted."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform((0.0, 0.0), bench.WORKSPACE_M, size=(n, 2))
    z = bench._relief(xy) + bench.NOISE_STD_M * rng.standard_normal(n)
    xs = np.arange(bench.CELL_M / 2, bench.WORKSPACE_M[0], bench.CELL_M)
    ys = np.arange(bench.CELL_M / 2, bench.WORKSPACE_M[1], bench.CELL_M)
    out = []
    for method in ("exact", "grid"):
        field = GaussianRandomField(length_scale=bench.LENGTH_SCALE_M,
                                    signal_std=bench.SIGNAL_STD_M,
                                    noise_std=bench.NOISE_STD_M, method=method)  # fmt: skip
        out += list(field.fit(xy, z).predict_grid(xs, ys, return_std=True))
    return tuple(out)


def test_bench_reports_the_grid_gps_deviation_from_the_exact_gp() -> None:
    rows = bench.bench_surface_gp((300,), rng=np.random.default_rng(0))
    assert [set(r) for r in rows] == [
        {"n_points", "exact_s", "grid_s", "speedup", "max_mean_dev_m", "max_rel_std_dev"}
    ]
    row = rows[0]
    assert row["n_points"] == 300
    for key in ("exact_s", "grid_s", "speedup"):
        assert math.isfinite(row[key]) and row[key] > 0, key
    m_exact, s_exact, m_grid, s_grid = _exact_and_grid(300, 0)
    assert m_exact.shape == (80, 120)
    assert row["max_mean_dev_m"] == pytest.approx(float(np.max(np.abs(m_grid - m_exact))))
    assert row["max_rel_std_dev"] == pytest.approx(
        float(np.max(np.abs(s_grid - s_exact) / s_exact))
    )
    # what the benchmark is for: the grid path is as good as exact (10 µm, 1 %), yet it is a
    # different computation (an exact-against-exact comparison would report 0)
    assert 0 < row["max_mean_dev_m"] <= 10e-6
    assert 0 < row["max_rel_std_dev"] <= 0.01


def test_bench_refuses_bad_input() -> None:
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        bench.bench_surface_gp((300,), rng=0)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match=r"`n_points_list\[i\]`"):
        bench.bench_surface_gp((1,), rng=np.random.default_rng(0))
