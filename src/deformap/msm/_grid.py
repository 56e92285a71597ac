"""The particle grid of a region of interest: rest positions, masses and fixed edges."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array
from deformap.errors import InvalidArgumentError

__all__ = ["ParticleGrid", "check_axis"]


def check_axis(name: str, value: Any, *, min_size: int = 3) -> NDArray[np.float64]:
    """Validate a strictly increasing 1-D coordinate axis in metres."""
    arr = check_array(name, value, (None,), what="coordinates in metres", min_rows=min_size)
    if np.any(np.diff(arr) <= 0):
        raise InvalidArgumentError(f"`{name}` must be strictly increasing; got {arr[:5]}...")
    return arr


@dataclass(frozen=True, kw_only=True)
class ParticleGrid:
    """Particles on a regular ``(ny, nx)`` grid: one per heightmap cell.

    Parameters
    ----------
    rest : (ny, nx, 3) float, metres
        Rest positions ``p⁰`` (row ``i`` is ``ys[i]``, column ``j`` is ``xs[j]``).
    masses : (ny, nx) float, kilograms per unit areal density
        Equal masses ``Δx·Δy`` (the mean cell area): the heightmap samples the surface on a
        regular grid, and only the ratios of masses within a cluster matter for shape matching.
    fixed : (ny, nx) bool
        Particles held at rest: the ROI's outer ring (the paper's "surface fixed to the ground
        from its edges").
    spacing_m : float
        Mean particle spacing ``h``.
    """

    rest: NDArray[np.float64]
    masses: NDArray[np.float64]
    fixed: NDArray[np.bool_]
    spacing_m: float

    @classmethod
    def from_heightmap(cls, xs: Any, ys: Any, z: Any) -> ParticleGrid:
        """Build the grid from a heightmap ``z (ny, nx)`` over axes ``xs (nx,)`` and ``ys (ny,)``.

        Both axes need at least 3 values (a free interior particle).
        """
        xs = check_axis("xs", xs)
        ys = check_axis("ys", ys)
        z = check_array("z", z, (ys.size, xs.size), what="heights in metres")
        gx, gy = np.meshgrid(xs, ys)
        rest = np.stack([gx, gy, z], axis=-1)
        dx, dy = float(np.mean(np.diff(xs))), float(np.mean(np.diff(ys)))
        masses = np.full(z.shape, dx * dy)
        fixed = np.zeros(z.shape, dtype=bool)
        fixed[0, :] = fixed[-1, :] = fixed[:, 0] = fixed[:, -1] = True
        spacing = 0.5 * (dx + dy)
        for arr in (rest, masses, fixed):
            arr.setflags(write=False)
        return cls(rest=rest, masses=masses, fixed=fixed, spacing_m=spacing)

    @property
    def shape(self) -> tuple[int, int]:
        """``(ny, nx)``."""
        return (int(self.rest.shape[0]), int(self.rest.shape[1]))

