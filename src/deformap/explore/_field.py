"""The β-field ("GPR β-field"): a Gaussian random field over the pokes' βs, each poke's
uncertainty its noise (with a floor), read on the map's grid.

References
----------
Caccamo et al. (2016), Sec. III-D. Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes
for Machine Learning, Eq. 2.24 (posterior mean and variance with per-point noise).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from deformap.explore._config import BetaFieldConfig
from deformap.explore._records import PokeRecord
from deformap.gp import GaussianRandomField

__all__ = ["BetaField", "PokeSet"]


@dataclass(frozen=True, eq=False)
class PokeSet:
    """Where the pokes were and what they gave, as arrays.

    ``xy (p, 2)`` metres, ``beta (p,)``, ``noise (p,)`` each poke's uncertainty raised to the
    β-field's noise floor (what the field and the planner take as its noise).
    """

    xy: NDArray[np.float64]
    beta: NDArray[np.float64]
    noise: NDArray[np.float64]

    @classmethod
    def of(cls, records: Sequence[PokeRecord], noise_floor: float) -> PokeSet:
        xy = np.array([r.contact_xy for r in records], dtype=float).reshape(-1, 2)
        beta = np.array([r.beta for r in records], dtype=float)
        noise = np.maximum(np.array([r.beta_std for r in records], dtype=float), noise_floor)
        return cls(xy, beta, np.asarray(noise, dtype=float).reshape(-1))

    def __len__(self) -> int:
        return int(self.beta.size)


class BetaField:
    """The β-field of a set of pokes on the grid ``xs``, ``ys`` (no poke: the prior).

    Parameters
    ----------
    pokes : PokeSet
    xs : (nx,) float, ys : (ny,) float, metres
    config : BetaFieldConfig
        Prior standard deviation σe, length scale σw and the noise floor.

    Attributes
    ----------
    mean, variance : (ny, nx) float
        Posterior mean (NaN without pokes) and variance, computed once on first use.
    """

    @classmethod
    def of(cls, records: Sequence[PokeRecord], xs: NDArray[np.float64], ys: NDArray[np.float64],
           config: BetaFieldConfig) -> BetaField:
        """The β-field of the pokes ``records`` (each one's uncertainty raised to the floor)."""
        return cls(PokeSet.of(records, config.noise_floor), xs, ys, config)

    def __init__(self, pokes: PokeSet, xs: NDArray[np.float64], ys: NDArray[np.float64],
                 config: BetaFieldConfig) -> None:
        self.pokes = pokes
        self.xs, self.ys = xs, ys
        self.config = config
        self.gp: GaussianRandomField | None = None
        if len(pokes):
            self.gp = GaussianRandomField(
                length_scale=config.length_scale_m, signal_std=config.signal_std,
                noise_std=config.noise_floor, method="exact",
            ).fit(pokes.xy, pokes.beta, noise_std=pokes.noise)  # fmt: skip

    @cached_property
    def _grid(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        if self.gp is None:
            shape = (self.ys.size, self.xs.size)
            return np.full(shape, np.nan), np.full(shape, self.config.signal_std**2)
        mean, std = self.gp.predict_grid(self.xs, self.ys, return_std=True)
        return mean, std**2

    @property
    def mean(self) -> NDArray[np.float64]:
        return self._grid[0]

    @property
    def variance(self) -> NDArray[np.float64]:
        return self._grid[1]

    def max_variance(self, mask: NDArray[np.bool_] | None = None) -> float:
        """The largest variance over the flat cells ``mask`` (all cells by default)."""
        var = self.variance.ravel()
        return float(var.max() if mask is None else var[mask].max())
