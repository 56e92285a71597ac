"""Small seeded surfaces shared by the gp tests."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray


def smooth_surface(xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """A bumpy height field in metres with features a few centimetres wide."""
    x, y = xy[:, 0], xy[:, 1]
    return (
        0.05
        + 0.01 * np.sin(x / 0.03) * np.cos(y / 0.04)
        + 0.004 * np.exp(-((x - 0.3) ** 2 + (y - 0.2) ** 2) / 0.05**2)
    )


@pytest.fixture
def small_data() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """60 noisy points (σ = 1 mm) on a 20 × 15 cm patch."""
    rng = np.random.default_rng(7)
    xy = rng.uniform([0.0, 0.0], [0.2, 0.15], size=(60, 2))
    return xy, smooth_surface(xy) + 0.001 * rng.standard_normal(60)


@pytest.fixture
def surface():
    """The ``smooth_surface`` height function."""
    return smooth_surface
