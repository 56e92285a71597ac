"""The fields over the pokes: :class:`PokeField`, a Gaussian random field over the pokes' values,
each poke's uncertainty its noise, read on the map's grid; its two kinds, the β-field ("GPR
β-field", :class:`BetaField`: each σ with a floor, plus the map's nugget,
:mod:`deformap.explore._nugget`) and the modulus field over ln E
(:class:`deformap.explore.ModulusField`, :mod:`deformap.explore._modulus`); and the settings
either takes when the map runs on it (:func:`field_settings`).

References
----------
Caccamo et al. (2016), Sec. III-D. Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes
for Machine Learning, Eq. 2.24 (posterior mean and variance with per-point noise).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Self

import numpy as np
from numpy.typing import NDArray

from deformap.explore._appearance_prior import AppearanceModels, AppearancePrior
from deformap.explore._config import (
    BetaFieldConfig,
    ExplorationConfig,
    FieldName,
    ModulusFieldConfig,
)
from deformap.explore._records import PokeRecord
from deformap.gp import GaussianRandomField

__all__ = ["REGION_MIN_STEP_BETA", "BetaField", "FieldSettings", "PokeField", "PokeSet",
           "beta_noise_floor", "field_settings"]

#: Smallest difference of two region classes' mean β that separates them
#: (:func:`deformap.explore.segment_regions`'s ``min_step`` under the β-field).
REGION_MIN_STEP_BETA = 0.05


@dataclass(frozen=True)
class FieldSettings:
    """What the target choice, the stopping rule and the regions read of the field they run on,
    in that field's units (β, or ln E for the modulus field).

    Attributes
    ----------
    name : {"beta", "modulus"}
    signal_std, length_scale_m, noise_floor : float
        The field's prior (σe, σw) and its noise floor (the β-field's resolved by
        :func:`beta_noise_floor`).
    threshold : float
        ``T_h`` on the field's variance.
    min_step : float
        Smallest difference of two region classes' means.
    """

    name: FieldName
    signal_std: float
    length_scale_m: float
    noise_floor: float
    threshold: float
    min_step: float


def beta_noise_floor(config: ExplorationConfig) -> float:
    """The smallest σ a poke's β is credited with: ``beta_field.noise_floor`` when set, else the
    β grid's quantisation, ``shape_matching.beta_resolution / √12``."""
    floor = config.beta_field.noise_floor
    if floor is None:
        return float(config.shape_matching.beta_resolution / np.sqrt(12.0))
    return float(floor)


def field_settings(config: ExplorationConfig, name: FieldName | None = None) -> FieldSettings:
    """The settings of the field ``name`` (default: ``config.field``); the modulus field scales
    ``T_h`` by the ratio of the prior variances and the regions' step by that of the stds."""
    beta = config.beta_field
    if (name or config.field) == "beta":
        return FieldSettings("beta", beta.signal_std, beta.length_scale_m, beta_noise_floor(config),
                             config.threshold, REGION_MIN_STEP_BETA)  # fmt: skip
    modulus = config.modulus_field
    ratio = modulus.signal_std / beta.signal_std
    return FieldSettings("modulus", modulus.signal_std, modulus.length_scale_m,
                         modulus.noise_floor, config.threshold * ratio**2,
                         REGION_MIN_STEP_BETA * ratio)  # fmt: skip


@dataclass(frozen=True, eq=False)
class PokeSet:
    """Where the pokes were and what they gave, as arrays.

    ``xy (p, 2)`` metres; ``values (p,)`` β or ln E [ln Pa]; ``noise (p,)`` each poke's σ raised
    to the field's floor and, with a nugget, ``√(σ² + nugget²)``; ``index (p,)`` the pokes'
    ``PokeRecord.index`` (default ``0 .. p-1``); ``nugget`` the scatter between places of one
    material (0: none); ``thickness (p,)`` the layer's thickness at each poke [m], or ``None``.
    """

    xy: NDArray[np.float64]
    values: NDArray[np.float64]
    noise: NDArray[np.float64]
    index: NDArray[np.int64] | None = None
    nugget: float = 0.0
    thickness: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        if self.index is None:
            object.__setattr__(self, "index", np.arange(self.values.size, dtype=np.int64))

    @classmethod
    def of(cls, records: Sequence[PokeRecord], noise_floor: float) -> PokeSet:
        """The pokes' βs, each σ raised to ``noise_floor``, no nugget."""
        xy = np.array([r.contact_xy for r in records], dtype=float).reshape(-1, 2)
        beta = np.array([r.beta for r in records], dtype=float)
        noise = np.maximum(np.array([r.beta_std for r in records], dtype=float), noise_floor)
        index = np.array([r.index for r in records], dtype=np.int64)
        return cls(xy, beta, np.asarray(noise, dtype=float).reshape(-1), index,
                   thickness=layer_thickness(records))

    def __len__(self) -> int:
        return int(self.values.size)


def layer_thickness(records: Sequence[PokeRecord]) -> NDArray[np.float64] | None:
    """Each poke's layer thickness [m] (``PokeRecord.layer_thickness_m``, the surface model's
    height at the contact), or ``None`` unless every poke has one."""
    values = [r.layer_thickness_m for r in records]
    if not values or any(v is None for v in values):
        return None
    return np.array(values, dtype=float)


class PokeField:
    """A Gaussian random field over the values of a set of pokes, read on the grid ``xs``, ``ys``
    (no poke: the prior). The prior mean is the pokes' inverse-noise-variance weighted mean, so
    far from every poke the field reverts to what the pokes say on average.

    Parameters
    ----------
    pokes : PokeSet
    xs : (nx,) float, ys : (ny,) float, metres
    config : BetaFieldConfig or ModulusFieldConfig
        Prior standard deviation σe and length scale σw, in the field's units.

    Attributes
    ----------
    name : {"beta", "modulus"}
    mean, variance : (ny, nx) float
        Posterior mean (NaN without pokes) and variance, computed on first use; under an
        appearance prior (:meth:`with_prior`; ``None``: blind), the average over its weights.
    """

    name: ClassVar[FieldName]
    prior: AppearancePrior | None = None

    def __init__(self, pokes: PokeSet, xs: NDArray[np.float64], ys: NDArray[np.float64],
                 config: BetaFieldConfig | ModulusFieldConfig) -> None:
        self.pokes = pokes
        self.xs, self.ys = xs, ys
        self.config = config
        self.gp: GaussianRandomField | None = None
        if len(pokes):
            self.gp = GaussianRandomField(
                length_scale=config.length_scale_m, signal_std=config.signal_std,
                noise_std=float(pokes.noise.min()), method="exact",
            ).fit(pokes.xy, pokes.values, noise_std=pokes.noise)  # fmt: skip

    def with_prior(self, prior: AppearancePrior | None) -> Self:
        """This field under the appearance prior ``prior`` (``None``: blind); call before the
        field is first read. Returns ``self``."""
        self.prior = prior
        self.__dict__.pop("_grid", None)
        self.__dict__.pop("models", None)
        return self

    @cached_property
    def models(self) -> AppearanceModels | None:
        """The field under each weight of the appearance prior and their posterior (``None``
        when blind or without pokes)."""
        if self.prior is None or not len(self.pokes):
            return None
        return AppearanceModels(self.prior, self.pokes.xy, self.pokes.values, self.pokes.noise,
                                signal_std=self.config.signal_std,
                                length_scale=self.config.length_scale_m)  # fmt: skip

    @cached_property
    def _grid(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        shape = (self.ys.size, self.xs.size)
        if self.gp is None:
            return np.full(shape, np.nan), np.full(shape, self.config.signal_std**2)
        if self.models is not None:
            assert self.prior is not None
            mean, var = self.models.predict(self.prior.cells_xy)
            return mean.reshape(shape), var.reshape(shape)
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


class BetaField(PokeField):
    """The β-field ("GPR β-field") over the pokes' βs (:func:`deformap.explore._nugget.beta_pokes`)."""

    name: ClassVar[FieldName] = "beta"

    def __init__(self, pokes: PokeSet, xs: NDArray[np.float64], ys: NDArray[np.float64],
                 config: BetaFieldConfig) -> None:
        super().__init__(pokes, xs, ys, config)
