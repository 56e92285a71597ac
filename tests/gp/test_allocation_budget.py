"""Every public allocator of deformap.gp checks its arrays' size against one budget before it
allocates them: a one-line error with the size, not a raw MemoryError."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from deformap import GaussianRandomField
from deformap.errors import InvalidArgumentError
from deformap.gp import (
    PosteriorDesign,
    apply_smoother,
    fit_hyperparameters,
    grid_points,
    log_marginal_likelihood,
    squared_exponential,
)

RNG = np.random.default_rng(0)
XY = RNG.uniform(0.0, 0.6, (40, 2))
Z = np.sin(XY[:, 0] * 10.0)
HUGE = np.linspace(0.0, 1.0, 200_000)  # 1.6 MB of coordinates; 298 GiB as a grid


def _field(method: str) -> GaussianRandomField:
    return GaussianRandomField(length_scale=0.1, signal_std=1.0, noise_std=0.1,
                               method=method).fit(XY, Z)  # type: ignore[arg-type]


@pytest.mark.parametrize("method", ["exact", "grid"])
def test_predict_grid_on_a_huge_grid_is_one_line_with_its_size(method: str) -> None:
    field = _field(method)
    with pytest.raises(InvalidArgumentError) as exc:
        field.predict_grid(HUGE, HUGE, return_std=True)
    text = str(exc.value)
    assert "\n" not in text and text.startswith("GaussianRandomField.predict_grid(xs, ys) needs ")
    assert "200,000 × 200,000" in text and "GiB" in text and "at most 8 GiB" in text
    assert field.predict_grid(HUGE[:300], HUGE[:200]).shape == (200, 300)  # a real map passes


# (call, arguments that ask for far more than the budget)
BIG = np.column_stack([HUGE, HUGE])
CALLS: list[tuple[str, Callable[[], Any]]] = [
    ("squared_exponential", lambda: squared_exponential(BIG, BIG, length_scale=0.1,
                                                        signal_std=1.0)),
    ("grid_points", lambda: grid_points(HUGE, HUGE)),
    ("PosteriorDesign", lambda: PosteriorDesign(XY, np.full(40, 0.1), BIG, BIG, length_scale=0.1,
                                                signal_std=1.0, candidate_noise_std=0.1)),
    ("apply_smoother", lambda: apply_smoother(BIG, np.full(len(BIG), 0.1), XY,
                                              np.zeros(len(BIG)), length_scale=0.1,
                                              signal_std=1.0)),
    ("log_marginal_likelihood", lambda: log_marginal_likelihood(
        BIG, np.arange(len(BIG), dtype=float), length_scale=0.1, signal_std=1.0, noise_std=0.1)),
    ("fit_hyperparameters", lambda: fit_hyperparameters(
        BIG, np.arange(len(BIG), dtype=float), rng=np.random.default_rng(0),
        max_points=len(BIG))),
    ("GaussianRandomField.fit", lambda: GaussianRandomField(
        length_scale=0.1, signal_std=1.0, noise_std=0.1, method="exact").fit(
            BIG, np.arange(len(BIG), dtype=float))),
]


@pytest.mark.parametrize(("name", "call"), CALLS, ids=[name for name, _ in CALLS])
def test_every_public_allocator_checks_the_budget_first(name: str, call: Callable[[], Any]
                                                        ) -> None:  # fmt: skip
    with pytest.raises(InvalidArgumentError, match=rf"^{name}\(.* needs [\d,.]+ GiB") as exc:
        call()
    assert "\n" not in str(exc.value)
