"""What an exploration (or a replayed session) produced, as values, not the live mapper."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from deformap.environment import Workspace
from deformap.explore._appearance import AppearanceImage
from deformap.explore._appearance_prior import AppearancePrior
from deformap.explore._classes import RegionMap
from deformap.explore._config import ExplorationConfig, FieldName
from deformap.explore._field import BetaField, PokeField
from deformap.explore._grid import MapGrid
from deformap.explore._modulus import ModulusField
from deformap.explore._nugget import beta_pokes
from deformap.explore._records import PokeResult
from deformap.explore._surface import SurfaceModel

__all__ = ["AppearanceOutcome", "ExplorationResult", "StopReason"]

StopReason = Literal["threshold", "max_pokes", "end-of-session"]
"""``threshold``: the variance fell under ``T_h`` and no boundary poke was owed; ``max_pokes``:
the poke limit came first; ``end-of-session``: a replayed session's pokes ran out."""


@dataclass(frozen=True, kw_only=True, eq=False)
class AppearanceOutcome:
    """What the appearance prior did in a run (:mod:`deformap.explore._appearance_prior`).

    Attributes
    ----------
    used : bool
    reason : str or None
        Why the prior was not used.
    weights, weight_posterior : tuple of float
        The grid of the look's weight ``w`` and its posterior after the last poke (empty when
        not used or without pokes).
    weight, look_scale : float or None
        The posterior mean of ``w``; the most probable ``ℓ_a`` (standardised feature units).
    n_segments : int
    image : AppearanceImage or None
    """

    used: bool
    reason: str | None = None
    weights: tuple[float, ...] = ()
    weight_posterior: tuple[float, ...] = ()
    weight: float | None = None
    look_scale: float | None = None
    n_segments: int = 0
    image: AppearanceImage | None = None

    @classmethod
    def of(cls, prior: AppearancePrior | None, reason: str | None,
           field: PokeField) -> AppearanceOutcome:
        """The outcome of a run whose map field is ``field`` under ``prior`` (or ``reason``)."""
        if prior is None:
            return cls(used=False, reason=reason)
        models = field.models
        if models is None:
            return cls(used=True, n_segments=prior.image.n_segments, image=prior.image)
        values, probability = models.posterior.weight_distribution()
        return cls(used=True, weights=tuple(float(v) for v in values),
                   weight_posterior=tuple(float(p) for p in probability),
                   weight=models.posterior.mean_weight, look_scale=models.posterior.look_scale,
                   n_segments=prior.image.n_segments, image=prior.image)  # fmt: skip

    def to_dict(self) -> dict[str, object]:
        """The JSON form (no arrays): ``used``, ``reason``, ``weight``, ``weights``,
        ``weight_posterior``, ``look_scale``, ``n_segments``."""
        return {"used": self.used, "reason": self.reason, "weight": self.weight,
                "weights": list(self.weights), "weight_posterior": list(self.weight_posterior),
                "look_scale": self.look_scale, "n_segments": self.n_segments}  # fmt: skip


@dataclass(frozen=True, kw_only=True, eq=False)
class ExplorationResult:
    """What one exploration produced.

    Attributes
    ----------
    config : ExplorationConfig
    workspace : Workspace
    grid : MapGrid
        The map's cells; every map below is on it.
    surface : SurfaceModel or None
    pokes : tuple of PokeResult
    beta_field, modulus_field : BetaField, ModulusField
        The fields after the last poke (the modulus field is its prior when no poke has a modulus).
    regions : RegionMap or None
        The regions of ``map_field`` (``None`` without pokes).
    max_variance : float
        What the stopping rule compared with ``T_h``, in the map field's units.
    stop_reason : str
        A :data:`StopReason`.
    timings : mapping of str to float
        ``total_s``, ``observe_s``, ``surface_gp_s``, ``environment_s``.
    map_field_name : {"beta", "modulus"}
        The field the regions, targets and stop ran on at the end: ``config.field``, or ``"beta"``
        where the run fell back (``field_fallback`` says why).
    field_fallback : str or None
    unread_places : tuple of (x, y)
        Presses [m] whose modulus could not be read twice, their discs taken out of the targets
        and the stop cells.
    stop_mask : (ny * nx,) bool or None
        The stop cells without those discs (``None``: ``grid.stop_mask``).
    appearance : AppearanceOutcome
    prior : AppearancePrior or None
        The appearance prior the fields used (``None``: blind).
    """

    config: ExplorationConfig
    workspace: Workspace
    grid: MapGrid
    surface: SurfaceModel | None
    pokes: tuple[PokeResult, ...]
    beta_field: BetaField
    modulus_field: ModulusField
    regions: RegionMap | None
    max_variance: float
    stop_reason: str
    timings: Mapping[str, float]
    map_field_name: FieldName
    field_fallback: str | None = None
    unread_places: tuple[tuple[float, float], ...] = ()
    stop_mask: NDArray[np.bool_] | None = None
    appearance: AppearanceOutcome = AppearanceOutcome(used=False)
    prior: AppearancePrior | None = None

    @property
    def stop_cells(self) -> NDArray[np.bool_]:
        """The cells whose variance the stopping rule read (``stop_mask``, else the grid's)."""
        return self.grid.stop_mask if self.stop_mask is None else self.stop_mask

    @property
    def xs(self) -> NDArray[np.float64]:
        return self.grid.xs

    @property
    def ys(self) -> NDArray[np.float64]:
        return self.grid.ys

    @property
    def map_field(self) -> PokeField:
        """The field the regions and the stopping rule ran on (:attr:`map_field_name`)."""
        return self.modulus_field if self.map_field_name == "modulus" else self.beta_field

    @property
    def has_modulus(self) -> bool:
        """Whether at least one poke has a modulus (the modulus field is more than its prior)."""
        return len(self.modulus_field.pokes) > 0

    def beta_field_after(self, n_pokes: int) -> BetaField:
        """The β-field as it was after the first ``n_pokes`` pokes (recordings, figures)."""
        if n_pokes == len(self.pokes):
            return self.beta_field
        return BetaField(beta_pokes([p.record for p in self.pokes[:n_pokes]], self.config),
                         self.grid.xs, self.grid.ys, self.config.beta_field
                         ).with_prior(self.prior)  # fmt: skip

    def modulus_field_after(self, n_pokes: int) -> ModulusField:
        """The modulus field as it was after the first ``n_pokes`` pokes."""
        if n_pokes == len(self.pokes):
            return self.modulus_field
        return ModulusField.of_records([p.record for p in self.pokes[:n_pokes]], self.grid.xs,
                                       self.grid.ys, self.config.modulus_field,
                                       self.config.stiffness.poisson_ratio,
                                       ).with_prior(self.prior)  # fmt: skip
