"""Active exploration: the mapper and its concepts (surface model, dent and β, β-field, target
choice, regions, the modulus field over the stiffness a force–travel record gives), the loop
that drives an ``Environment`` with it, the typed poke records and the session journal."""

from __future__ import annotations

from deformap.explore._acquisition import STRATEGIES
from deformap.explore._classes import RegionMap, segment_regions
from deformap.explore._config import (
    BetaFieldConfig,
    ExplorationConfig,
    FieldName,
    ModulusFieldConfig,
    RegionLabels,
    SurfaceGPConfig,
    TouchGPConfig,
    check_exploration_budget,
)
from deformap.explore._dent import measure_press
from deformap.explore._field import (
    BetaField,
    FieldSettings,
    PokeField,
    PokeSet,
    beta_noise_floor,
    field_settings,
)
from deformap.explore._grid import MapGrid
from deformap.explore._journal import JOURNAL_NAME, Journal, JournalContents, read_journal
from deformap.explore._labels import map_regions
from deformap.explore._loop import MappingRun, explore, poke_step
from deformap.explore._mapper import Mapper
from deformap.explore._modulus import ModulusField, ModulusReading, rigid_modulus_bound
from deformap.explore._records import (
    PURPOSES,
    ContactRecord,
    Dent,
    PokeRecord,
    PokeResult,
    PokeTimings,
    Purpose,
    Target,
    poke_behaviour,
)
from deformap.explore._result import AppearanceOutcome, ExplorationResult, StopReason
from deformap.explore._surface import SurfaceModel, fit_surface

__all__ = ["JOURNAL_NAME", "PURPOSES", "STRATEGIES", "AppearanceOutcome", "BetaField",
           "BetaFieldConfig", "ContactRecord", "Dent", "ExplorationConfig", "ExplorationResult",
           "FieldName", "FieldSettings", "Journal", "JournalContents", "MapGrid", "Mapper",
           "MappingRun", "ModulusField", "ModulusFieldConfig", "ModulusReading", "PokeField",
           "PokeRecord", "PokeResult", "PokeSet", "PokeTimings", "Purpose", "RegionLabels",
           "RegionMap", "StopReason", "SurfaceGPConfig", "SurfaceModel", "Target", "TouchGPConfig",
           "beta_noise_floor", "check_exploration_budget", "explore", "field_settings",
           "fit_surface", "map_regions", "measure_press", "poke_behaviour", "poke_step", "read_journal",
           "rigid_modulus_bound", "segment_regions"]
