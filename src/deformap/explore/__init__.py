"""Active exploration: the mapper, the loop that drives an ``Environment`` with it, acquisition
strategies, region segmentation and the session journal."""

from __future__ import annotations

from deformap.explore._acquisition import STRATEGIES, choose_target
from deformap.explore._config import (
    BetaFieldConfig,
    ExplorationConfig,
    SurfaceGPConfig,
    TouchGPConfig,
    check_exploration_budget,
)
from deformap.explore._journal import Journal, JournalContents, read_journal
from deformap.explore._loop import ExplorationResult, explore
from deformap.explore._mapper import Mapper, PokeResult, SurfaceModel
from deformap.explore._regions import RegionMap, segment_regions

__all__ = [
    "STRATEGIES",
    "BetaFieldConfig",
    "ExplorationConfig",
    "ExplorationResult",
    "Journal",
    "JournalContents",
    "Mapper",
    "PokeResult",
    "RegionMap",
    "SurfaceGPConfig",
    "SurfaceModel",
    "TouchGPConfig",
    "check_exploration_budget",
    "choose_target",
    "explore",
    "read_journal",
    "segment_regions",
]
