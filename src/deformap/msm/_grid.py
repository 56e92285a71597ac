"""The particle grid of a region of interest: rest positions, masses and fixed edges."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array
from deformap.errors import InvalidArgumentError

__all__ = ["ParticleGrid"]


def _check_axis(name: str, value: Any) -> NDArray[np.float64]:
    arr = check_array(name, value, (None,), what="coordinates in metres", min_rows=3)
    if np.any(np.diff(arr) <= 0):
        raise InvalidArgumentError(f"`{name}` must be strictly increasing; got {arr[:5]}...")
    return arr


@dataclass(frozen=True, kw_only=True)
class ParticleGrid:
    """One particle per heightmap cell: ``rest (ny, nx, 3)`` metres (row ``i`` at ``ys[i]``), equal
    ``masses`` ``Δx·Δy``, the ``fixed`` outer ring and the mean spacing ``spacing_m``."""

    rest: NDArray[np.float64]
    masses: NDArray[np.float64]
    fixed: NDArray[np.bool_]
    spacing_m: float

    @classmethod
    def from_heightmap(cls, xs: Any, ys: Any, z: Any) -> ParticleGrid:
        """The grid of a heightmap ``z (ny, nx)`` over axes ``xs (nx,)``, ``ys (ny,)`` (≥ 3 each)."""
        xs, ys = _check_axis("xs", xs), _check_axis("ys", ys)
        z = check_array("z", z, (ys.size, xs.size), what="heights in metres")
        gx, gy = np.meshgrid(xs, ys)
        rest = np.stack([gx, gy, z], axis=-1)
        dx, dy = float(np.mean(np.diff(xs))), float(np.mean(np.diff(ys)))
        masses = np.full(z.shape, dx * dy)
        fixed = np.zeros(z.shape, dtype=bool)
        fixed[0, :] = fixed[-1, :] = fixed[:, 0] = fixed[:, -1] = True
        for arr in (rest, masses, fixed):
            arr.setflags(write=False)
        return cls(rest=rest, masses=masses, fixed=fixed, spacing_m=0.5 * (dx + dy))
