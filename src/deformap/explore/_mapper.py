"""The mapper: the state of one exploration, updated one poke at a time.

It orchestrates the concepts of the paper's process flow, each in its own module: the surface
model (:mod:`._surface`), the dent and its β (:mod:`._dent`), the β-field (:mod:`._field`), the
choice of the next target (:mod:`._targets`) and the regions (:mod:`._regions`). The live loop
(:func:`deformap.explore.explore`) and a recorded session (:mod:`deformap.replay`) both feed it
through :func:`deformap.explore.poke_step`, so a poke gives the same β whichever way it arrives.

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
from deformap.explore._classes import RegionMap
from deformap.explore._config import ExplorationConfig, FieldName, check_exploration_budget
from deformap.explore._dent import measure_press
from deformap.explore._field import BetaField, PokeField, field_settings
from deformap.explore._grid import MapGrid
from deformap.explore._labels import map_regions
from deformap.explore._modulus import ModulusField
from deformap.explore._nugget import beta_pokes
from deformap.explore._records import PokeResult, Target
from deformap.explore._result import ExplorationResult
from deformap.explore._surface import SurfaceModel, fit_surface
from deformap.explore._targets import BOUNDARY_SPACING_ROI, choose_next

__all__ = ["Mapper", "unread_radius_m"]

logger = logging.getLogger(__name__)


def unread_radius_m(config: ExplorationConfig) -> float:
    """Radius [m] of one place: two presses this close are at one place, and an unread place's
    disc of it leaves the targets and the stopping rule (``BOUNDARY_SPACING_ROI`` ROIs: a dent
    spreads a few centimetres)."""
    return float(BOUNDARY_SPACING_ROI * config.touch.roi_size_m)


class Mapper:
    """State of one exploration: the surface model, the pokes and the β-field over them.

    Parameters
    ----------
    workspace : Workspace
        The rectangle to map; the surface grid's spacing gives every map's cells.
    config : ExplorationConfig
        Settings of every stage.
    """

    def __init__(self, workspace: Workspace, config: ExplorationConfig) -> None:
        check_exploration_budget(config, workspace)
        self.workspace = workspace
        self.config = config
        self.grid = MapGrid.build(workspace, config)
        self.surface: SurfaceModel | None = None
        self._pokes: list[PokeResult] = []
        self._beta_field: BetaField | None = None  # fitted when first asked for (`beta_field`)
        self._modulus = self._fit_modulus([])
        self.threshold = field_settings(config).threshold
        #: Why the run maps on β although ``config.field`` asked for the modulus (else None).
        self.field_fallback: str | None = None
        self._requested_field = config.field
        self._given_up: str | None = None
        #: places the modulus could not be read twice at, and the grid
        #: the targets and the stopping rule use: ``grid`` without them
        self.unread_places: list[tuple[float, float]] = []
        self._choice_grid = self.grid

    @property
    def pokes(self) -> tuple[PokeResult, ...]:
        """The pokes in the β-field, in order."""
        return tuple(self._pokes)

    @property
    def beta_field(self) -> BetaField:
        """The current β-field, fitted on first use after a poke: under ``field: modulus`` the
        loop does not need it, and its nugget costs a region test per poke."""
        if self._beta_field is None:
            self._beta_field = self._fit_beta(self._pokes)
        return self._beta_field

    @property
    def modulus_field(self) -> ModulusField:
        """The current modulus field (the prior while no poke has a modulus)."""
        return self._modulus

    @property
    def map_field(self) -> PokeField:
        """The field the regions, the next target and the stopping rule run on
        (``config.field``); ``threshold`` is its ``T_h``."""
        return self._modulus if self.config.field == "modulus" else self.beta_field

    def _fit_beta(self, pokes: list[PokeResult]) -> BetaField:
        return BetaField(beta_pokes([p.record for p in pokes], self.config), self.grid.xs,
                         self.grid.ys, self.config.beta_field)

    def _fit_modulus(self, pokes: list[PokeResult]) -> ModulusField:
        return ModulusField.of_records([p.record for p in pokes], self.grid.xs, self.grid.ys,
                                       self.config.modulus_field,
                                       self.config.stiffness.poisson_ratio)  # fmt: skip

    def initialise(self, cloud: PointCloud, rng: np.random.Generator) -> SurfaceModel:
        """Fit the surface model to the first observation (:func:`fit_surface`)."""
        self.surface = fit_surface(cloud, self.workspace, self.grid.xs, self.grid.ys,
                                   self.config.surface, rng)  # fmt: skip
        return self.surface

    def process_press(self, obs: PressObservation, index: int) -> PokeResult:
        """Reconstruct the dent of one press and estimate its β; the β-field is not touched."""
        if self.surface is None:
            raise EnvironmentStateError("the mapper needs `initialise(cloud)` before a poke")
        return measure_press(obs, index, self.surface, self.config)

    def add(self, poke: PokeResult, *, target: Target | None = None,
            timings: Mapping[str, float] | None = None) -> PokeResult:
        """Add a processed (or journalled) poke to the β-field; return it as recorded there.

        ``target`` (the live loop's) gives the record its purpose and plan; ``timings`` adds
        stage times measured outside the mapper (``target_s``, ``environment_s``).
        """
        t0 = time.perf_counter()
        pokes = [*self._pokes, poke]
        modulus = self._fit_modulus(pokes)
        if self._requested_field == "modulus":
            self._choose_field(poke, modulus)
        # the β-field is fitted now only when it is the map field; otherwise on first use
        field = None if self.config.field == "modulus" else self._fit_beta(pokes)
        active = modulus if field is None else field
        record = poke.record
        if target is not None:
            record = dataclasses.replace(record, purpose=target.purpose,
                                         planned_after=target.planned_after)  # fmt: skip
        record = dataclasses.replace(
            record, max_variance_after=active.max_variance(self._choice_grid.stop_mask),
            timings=dataclasses.replace(record.timings, field_s=time.perf_counter() - t0,
                                        **dict(timings or {})),
        )  # fmt: skip
        added = dataclasses.replace(poke, record=record)
        self._pokes.append(added)
        # a lazily fitted β-field holds the pokes' records, and ``added`` differs from ``poke``
        # only in what the field does not read (purpose, plan, variance after, timings)
        self._beta_field, self._modulus = field, modulus
        return added

    def _choose_field(self, poke: PokeResult, modulus: ModulusField) -> None:
        """Under ``field: modulus``, the field to map on after ``poke``: the modulus field once a
        poke has a modulus; the β-field while none has (a camera-only robot or session). Once the
        modulus could not be read twice at one place (a further press there would read nothing
        again, and the modulus field's variance there would never fall): the modulus field still,
        with that place taken out of the targets and the stopping rule (the β-field for good only
        when nothing would be left)."""
        reading = modulus.readings[-1]
        if self._given_up is None and reading.excluded is not None and self._pokes:
            here = np.asarray(poke.record.contact_xy, dtype=float)
            radius = unread_radius_m(self.config)
            unread = {r.index for r in modulus.readings[:-1] if r.excluded is not None}
            before = [np.asarray(p.record.contact_xy, dtype=float) for p in self._pokes
                      if p.record.index in unread
                      and np.hypot(*(np.asarray(p.record.contact_xy) - here)) <= radius]
            # while no poke has a modulus the run maps on β, which reads the place: nothing to
            # avoid yet (a later unread press there, once a modulus is read, is caught again)
            if before and len(modulus.pokes):
                # the disc about every unread press of the place, not only the last
                places = [*self.unread_places,
                          *((float(x), float(y)) for x, y in (*before, here))]
                left = self.grid.without(np.array(places), radius)
                if left is not None:
                    self.unread_places, self._choice_grid = places, left
                    logger.warning("poke %d: the modulus could not be read twice at (%.3f, %.3f) "
                                   "m (%s); that place is left out of the targets and the "
                                   "stopping rule", poke.record.index + 1, here[0], here[1],
                                   reading.excluded)  # fmt: skip
                else:  # β reads every place: its targets and stopping rule are the whole grid's
                    self._choice_grid = self.grid
                    self._given_up = (f"poke {poke.record.index + 1}: the modulus could not be "
                                      f"read twice at one place ({reading.excluded}); no target "
                                      "would be left without it")
        if self._given_up is not None:
            why = self._given_up
        elif not len(modulus.pokes):
            why = f"poke {poke.record.index + 1} gave no modulus ({reading.excluded})"
        else:
            why = None
        fallback = None if why is None else f"`exploration.field` 'modulus' fell back to 'beta': {why}"
        if fallback is not None and fallback != self.field_fallback:
            logger.warning("%s", fallback)
        self.field_fallback = fallback
        field: FieldName = "modulus" if fallback is None else "beta"
        if field != self.config.field:
            self.config = dataclasses.replace(self.config, field=field)
            self.threshold = field_settings(self.config).threshold

    def max_variance(self) -> float:
        """The map field's largest variance where it must fall below ``threshold``
        (``stop_region``)."""
        return self.map_field.max_variance(self._choice_grid.stop_mask)

    def boundary_owed(self) -> int:
        """Boundary pokes still to make (``boundary_pokes`` less those made)."""
        made = sum(p.record.purpose == "boundary" for p in self._pokes)
        return max(0, self.config.boundary_pokes - made)

    def next_target(self, rng: np.random.Generator) -> Target | None:
        """The next target (:func:`deformap.explore._targets.choose_next`), or ``None`` when the
        map is done."""
        return choose_next(self._choice_grid, self.map_field, self.config, rng,
                           boundary_owed=self.boundary_owed(),
                           n_made=len(self._pokes))  # fmt: skip

    def regions(self) -> RegionMap:
        """Cut the current map field into regions (:func:`map_regions`)."""
        if not self._pokes:
            raise EnvironmentStateError("no poke yet: the field has no regions")
        field = self.map_field
        return map_regions(field.mean, field.pokes, self.grid.cells_xy, self.config)

    def result(self, stop_reason: str, timings: Mapping[str, float]) -> ExplorationResult:
        """What the exploration produced, with the β-field and regions read once."""
        return ExplorationResult(
            config=self.config, workspace=self.workspace, grid=self.grid, surface=self.surface,
            pokes=self.pokes, beta_field=self.beta_field, modulus_field=self._modulus,
            regions=self.regions() if self._pokes else None,
            max_variance=self.max_variance(), stop_reason=stop_reason, timings=dict(timings),
            field_fallback=self.field_fallback, unread_places=tuple(self.unread_places),
            stop_mask=self._choice_grid.stop_mask,
        )  # fmt: skip
