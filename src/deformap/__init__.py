"""deformap: map how deformable a surface is, region by region, from a few robot pokes.

The method is Caccamo et al., "Active Perception and Modeling of Deformable Surfaces using Gaussian
Processes and Position-based Dynamics", HUMANOIDS 2016: a Gaussian random field models the surface,
meshless shape matching explains each poke's dent with one deformability value β, and a second
Gaussian random field (the β-field) spreads the βs over the surface and chooses the next poke.

The packages (``cloud``, ``gp``, ``msm``, ``stiffness``, ``mechanics``, ``environment``,
``explore``, ``world``, ``replay``, ``eval``, ``viz``, ``run``, ``cli``, ``testing``), what each
owns and may import, are in ``docs/architecture.md`` (a test enforces its import table). The main
entry points are names of ``deformap`` (``__all__``) and the packages its attributes, each
imported on first use, so ``import deformap`` stays cheap.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

from deformap._lazy import lazy_exports
from deformap.errors import DeformapError

if TYPE_CHECKING:  # the names a user imports from deformap; loaded on first use (below)
    from deformap.cloud import PointCloud
    from deformap.environment import (
        Environment,
        ForceTravel,
        PressObservation,
        TactileContact,
        Workspace,
    )
    from deformap.explore import ExplorationConfig, ExplorationResult, PokeRecord
    from deformap.gp import GaussianRandomField
    from deformap.msm import BetaEstimate, ShapeMatchingConfig, estimate_beta
    from deformap.replay import load_session, map_session, write_session
    from deformap.run import RunConfig, explore_scenario
    from deformap.world import SimulatedWorld, WorldConfig, list_scenarios, load_scenario

# the subpackage each main entry point lives in (its public name, imported on first use)
_MODULES = {
    "cloud": ("PointCloud",), "gp": ("GaussianRandomField",),
    "environment": ("Environment", "ForceTravel", "PressObservation", "TactileContact",
                    "Workspace"),
    "explore": ("ExplorationConfig", "ExplorationResult", "PokeRecord"),
    "msm": ("BetaEstimate", "ShapeMatchingConfig", "estimate_beta"),
    "replay": ("load_session", "map_session", "write_session"),
    "run": ("RunConfig", "explore_scenario"),
    "world": ("SimulatedWorld", "WorldConfig", "list_scenarios", "load_scenario"),
}  # fmt: skip

__all__ = ["BetaEstimate", "DeformapError", "Environment", "ExplorationConfig",
           "ExplorationResult", "ForceTravel", "GaussianRandomField", "PointCloud", "PokeRecord",
           "PressObservation", "RunConfig", "ShapeMatchingConfig", "SimulatedWorld",
           "TactileContact", "Workspace", "WorldConfig", "__version__", "estimate_beta",
           "explore_scenario", "list_scenarios", "load_scenario", "load_session", "map_session",
           "write_session"]  # fmt: skip

# the subpackages as attributes, imported on first use; no name above is a subpackage's (as
# ``deformap.explore``, the loop ``explore()`` would hide its package)
_PACKAGES = ("cloud", "environment", "eval", "explore", "gp", "mechanics", "msm", "replay", "run",
             "stiffness", "viz", "world")  # fmt: skip
_names_getattr, __dir__ = lazy_exports(__name__, _MODULES, [*__all__, *_PACKAGES], globals())


def __getattr__(name: str) -> Any:
    if name in _PACKAGES:
        return importlib.import_module(f"{__name__}.{name}")
    return _names_getattr(name)
