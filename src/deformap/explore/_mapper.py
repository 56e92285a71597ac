"""The mapper: the state of one exploration, updated one poke at a time, in the paper's process
flow (surface, dent and β, fields, next target, regions). The live loop and a recorded session
(:mod:`deformap.replay`) both feed it through :func:`deformap.explore.poke_step`.

References
----------
Caccamo et al. (2016), Sec. III-D (the process flow this class follows).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping

import numpy as np

from deformap.cloud import PointCloud
from deformap.environment import PressObservation, Workspace
from deformap.errors import EnvironmentStateError
from deformap.explore._appearance import build_appearance
from deformap.explore._appearance_prior import AppearancePrior
from deformap.explore._choice import FieldChoice, choose_map_field, unread_radius_m
from deformap.explore._classes import RegionMap
from deformap.explore._config import ExplorationConfig, FieldName, check_exploration_budget
from deformap.explore._dent import measure_press
from deformap.explore._field import BetaField, PokeField, field_settings
from deformap.explore._grid import MapGrid
from deformap.explore._labels import map_regions
from deformap.explore._modulus import ModulusField
from deformap.explore._nugget import beta_pokes
from deformap.explore._records import PokeRecord, PokeResult, Target
from deformap.explore._result import AppearanceOutcome, ExplorationResult
from deformap.explore._surface import SurfaceModel, fit_surface
from deformap.explore._targets import BOUNDARY_SPACING_ROI, choose_next, segment_interior

__all__ = ["Mapper"]

logger = logging.getLogger(__name__)


class Mapper:
    """State of one exploration of ``workspace``: the surface model, the pokes and the fields."""

    def __init__(self, workspace: Workspace, config: ExplorationConfig) -> None:
        check_exploration_budget(config, workspace)
        self.workspace = workspace
        self.config = config
        self.grid = MapGrid.build(workspace, config)
        self.surface: SurfaceModel | None = None
        self.appearance: AppearancePrior | None = None
        self.appearance_reason: str | None = "no observation yet"
        self._pokes: list[PokeResult] = []
        self._beta_field: BetaField | None = None  # fitted when first asked for (`beta_field`)
        self._modulus = self._fit_modulus([])
        self._choice = FieldChoice(name=config.field, grid=self.grid)

    @property
    def pokes(self) -> tuple[PokeResult, ...]:
        return tuple(self._pokes)

    @property
    def map_field_name(self) -> FieldName:
        """``config.field``, or ``"beta"`` where a run that asked for the modulus falls back."""
        return self._choice.name

    @property
    def field_fallback(self) -> str | None:
        return self._choice.fallback

    @property
    def unread_places(self) -> list[tuple[float, float]]:
        """The presses [m] where the modulus could not be read twice (out of the targets)."""
        return list(self._choice.unread_places)

    @property
    def choice_grid(self) -> MapGrid:
        """The grid the targets and the stopping rule use: ``grid`` without the unread places."""
        return self._choice.grid

    @property
    def threshold(self) -> float:
        """``T_h`` of the map field."""
        return field_settings(self.config, self.map_field_name).threshold

    @property
    def beta_field(self) -> BetaField:
        """The current β-field, fitted on first use (under ``field: modulus`` the loop does not
        need it, and its nugget costs a region test per poke)."""
        if self._beta_field is None:
            self._beta_field = self._fit_beta(self._pokes)
        return self._beta_field

    @property
    def modulus_field(self) -> ModulusField:
        return self._modulus

    @property
    def map_field(self) -> PokeField:
        """The field the regions, the next target and the stopping rule run on."""
        return self._modulus if self.map_field_name == "modulus" else self.beta_field

    def _fit_beta(self, pokes: list[PokeResult]) -> BetaField:
        return BetaField(beta_pokes([p.record for p in pokes], self.config), self.grid.xs,
                         self.grid.ys, self.config.beta_field).with_prior(self.appearance)

    def _fit_modulus(self, pokes: list[PokeResult]) -> ModulusField:
        return ModulusField.of_records([p.record for p in pokes], self.grid.xs, self.grid.ys,
                                       self.config.modulus_field,
                                       self.config.stiffness.poisson_ratio,
                                       ).with_prior(self.appearance)  # fmt: skip

    def initialise(self, cloud: PointCloud, rng: np.random.Generator) -> SurfaceModel:
        """Fit the surface model to the first observation and, under ``appearance: auto``, read
        its colours into the appearance prior (the same cloud gives the same prior)."""
        self.surface = fit_surface(cloud, self.workspace, self.grid.xs, self.grid.ys,
                                   self.config.surface, rng)  # fmt: skip
        if self.config.appearance == "off":
            self.appearance, self.appearance_reason = None, "exploration.appearance is off"
        else:
            footprint_m = BOUNDARY_SPACING_ROI * self.config.touch.roi_size_m
            image = build_appearance(cloud, self.grid.xs, self.grid.ys, self.surface.height,
                                     footprint_m)  # fmt: skip
            if isinstance(image, str):
                self.appearance, self.appearance_reason = None, image
                if cloud.colors is not None:
                    logger.warning("the appearance prior is off: %s; the map is the blind one",
                                   image)  # fmt: skip
            else:
                self.appearance = AppearancePrior(image, self.grid.xs, self.grid.ys)
                self.appearance_reason = None
        self._modulus = self._fit_modulus([])
        return self.surface

    def first_target(self) -> tuple[float, float]:
        """The first poke [m]: ``config.first_target`` if set; else, under the appearance
        prior, the place deepest inside the largest segment; else the workspace's centre."""
        if self.config.first_target is not None:
            return self.config.first_target
        if self.appearance is not None:
            segments = self.appearance.image.segments
            order = np.argsort(-np.bincount(segments[segments >= 0]), kind="stable")
            for s in order:
                found = segment_interior(self.grid, segments, int(s))
                if found is not None:
                    return (float(found[0][0]), float(found[0][1]))
        return self.workspace.center

    def process_press(self, obs: PressObservation, index: int) -> PokeResult:
        """Reconstruct the dent of one press and estimate its β; the β-field is not touched."""
        if self.surface is None:
            raise EnvironmentStateError("the mapper needs `initialise(cloud)` before a poke")
        return measure_press(obs, index, self.surface, self.config)

    def add(self, poke: PokeResult, *, target: Target | None = None,
            timings: Mapping[str, float] | None = None) -> PokeResult:
        """Add a processed (or journalled) poke to the fields; return it as recorded there, with
        ``target``'s purpose and plan and the stage ``timings`` measured outside the mapper."""
        t0 = time.perf_counter()
        pokes = [*self._pokes, poke]
        modulus = self._fit_modulus(pokes)
        self._update_choice([p.record for p in pokes], modulus)
        # the β-field is fitted now only when it is the map field; otherwise on first use
        field = None if self.map_field_name == "modulus" else self._fit_beta(pokes)
        active = modulus if field is None else field
        record = poke.record
        if target is not None:
            record = dataclasses.replace(record, purpose=target.purpose,
                                         planned_after=target.planned_after)  # fmt: skip
        record = dataclasses.replace(
            record, max_variance_after=active.max_variance(self.choice_grid.stop_mask),
            timings=dataclasses.replace(record.timings, field_s=time.perf_counter() - t0,
                                        **dict(timings or {})),
        )  # fmt: skip
        added = dataclasses.replace(poke, record=record)
        self._pokes.append(added)
        # a lazily fitted β-field holds the pokes' records, and ``added`` differs from ``poke``
        # only in what the field does not read (purpose, plan, variance after, timings)
        self._beta_field, self._modulus = field, modulus
        return added

    def _update_choice(self, records: list[PokeRecord], modulus: ModulusField) -> None:
        """The field to map on after the latest of ``records``, warning of each place left out
        and each new reason to fall back to β."""
        before = self._choice
        self._choice = choose_map_field(before, self.config.field, records, modulus, self.grid,
                                        unread_radius_m(self.config))  # fmt: skip
        if len(self._choice.unread_places) > len(before.unread_places):
            x, y = records[-1].contact_xy
            logger.warning("poke %d: the modulus could not be read twice at (%.3f, %.3f) m (%s); "
                           "that place is left out of the targets and the stopping rule",
                           records[-1].index + 1, x, y, modulus.readings[-1].excluded)
        fallback = self._choice.fallback
        if fallback is not None and fallback != before.fallback:
            logger.warning("%s", fallback)

    def max_variance(self) -> float:
        """The map field's largest variance over the stop cells."""
        return self.map_field.max_variance(self.choice_grid.stop_mask)

    def boundary_owed(self) -> int:
        """Boundary pokes still to make."""
        made = sum(p.record.purpose == "boundary" for p in self._pokes)
        return max(0, self.config.boundary_pokes - made)

    def next_target(self, rng: np.random.Generator) -> Target | None:
        """The next target, or ``None`` when the map is done."""
        return choose_next(self.choice_grid, self.map_field, self.config, rng,
                           boundary_owed=self.boundary_owed(),
                           n_made=len(self._pokes))  # fmt: skip

    def regions(self) -> RegionMap:
        """Cut the current map field into regions (:func:`map_regions`, with each poke's
        behaviour class)."""
        if not self._pokes:
            raise EnvironmentStateError("no poke yet: the field has no regions")
        field = self.map_field
        correlation = None if field.models is None else field.models.correlation
        read = {p.record.index: p.record.behaviour for p in self._pokes}
        index = field.pokes.index if field.pokes.index is not None else range(len(field.pokes))
        behaviours = [None if (b := read.get(int(i))) is None else b.behaviour for i in index]
        return map_regions(field.mean, field.pokes, self.grid.cells_xy, self.config,
                           self.map_field_name, correlation=correlation, behaviours=behaviours)

    def result(self, stop_reason: str, timings: Mapping[str, float]) -> ExplorationResult:
        """What the exploration produced, with the β-field and regions read once."""
        return ExplorationResult(
            config=self.config, workspace=self.workspace, grid=self.grid, surface=self.surface,
            pokes=self.pokes, beta_field=self.beta_field, modulus_field=self._modulus,
            regions=self.regions() if self._pokes else None,
            max_variance=self.max_variance(), stop_reason=stop_reason, timings=dict(timings),
            map_field_name=self.map_field_name, field_fallback=self.field_fallback,
            unread_places=self._choice.unread_places, stop_mask=self.choice_grid.stop_mask,
            appearance=AppearanceOutcome.of(self.appearance, self.appearance_reason,
                                            self.map_field),
            prior=self.appearance,
        )  # fmt: skip
