"""Active exploration: the mapper, the loop that drives an ``Environment`` with it, acquisition
strategies, region segmentation and the session journal."""

from __future__ import annotations

from deformap.explore._acquisition import STRATEGIES, choose_target
from deformap.explore._config import (
    BetaFieldConfig,
    ExplorationConfig,
    SurfaceGPConfig,
    TouchGPConfig,
)
from deformap.explore._journal import (
    JOURNAL_NAME,
    Journal,
    JournalContents,
    read_journal,
    replace_durably,
)
from deformap.explore._loop import ExplorationResult, explore
from deformap.explore._mapper import Mapper, PokeResult, SurfaceModel
from deformap.explore._regions import RegionMap, segment_regions

__all__ = [
    "JOURNAL_NAME",
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
    "choose_target",
    "explore",
    "read_journal",
    "replace_durably",
    "segment_regions",
]
