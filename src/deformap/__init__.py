"""deformap: map how deformable a surface is, region by region, from a few robot pokes.

The method is Caccamo et al., "Active Perception and Modeling of Deformable Surfaces using Gaussian
Processes and Position-based Dynamics", HUMANOIDS 2016: a Gaussian random field models the surface,
meshless shape matching explains each poke's dent with one deformability value β, and a second
Gaussian random field (the β-field) spreads the βs over the surface and chooses the next poke.

The packages, what each owns and may import, the data flow and the contracts are in
``docs/architecture.md`` (a test enforces its import table):

- :mod:`deformap.cloud`: point clouds, filters, tactile points, file and ROS 2 bag I/O;
- :mod:`deformap.gp`: the paper's kernel, exact and grid Gaussian random fields, hyperparameters;
- :mod:`deformap.msm`: meshless shape matching and the β estimation;
- :mod:`deformap.stiffness`: stiffness and Young's modulus from a press's force–travel record;
- :mod:`deformap.mechanics`: contact mechanics (tactile contact, Hertz, hardness ↔ modulus);
- :mod:`deformap.environment`: the ``Environment`` protocol a world or a robot implements;
- :mod:`deformap.explore`: the mapper and its concepts, the loop, poke records, the journal;
- :mod:`deformap.world`: the simulated world (scenarios, foam FEM, depth camera, probe);
- :mod:`deformap.replay`: recorded sessions written, read back and fed to the mapper;
- :mod:`deformap.eval`: metrics against ground truth, studies, Table I, benchmarks;
- :mod:`deformap.viz`: figures and 3D recordings (a leaf that nothing in the core imports);
- :mod:`deformap.run`: the application layer (run configuration, folders, reports, workflows);
- :mod:`deformap.cli`: the ``deformap`` command over :mod:`deformap.run`;
- :mod:`deformap.testing`: fixtures and tolerance helpers for tests.

The main entry points are names of ``deformap`` itself (``deformap.SimulatedWorld``,
``deformap.ExplorationConfig``, ``deformap.GaussianRandomField``, …, listed in ``__all__``), and
the packages are its attributes (``deformap.explore.explore``, the loop, whose name is its
package's); each is imported on first use, so ``import deformap`` stays cheap (the command line's
``--help`` loads neither the world nor the estimator).
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
    "cloud": ("PointCloud",),
    "environment": ("Environment", "ForceTravel", "PressObservation", "TactileContact",
                    "Workspace"),
    "explore": ("ExplorationConfig", "ExplorationResult", "PokeRecord"),
    "gp": ("GaussianRandomField",),
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

# a subpackage as an attribute of deformap (``deformap.gp``) without importing it first; no name
# above is a subpackage's (``explore()`` stays ``deformap.explore.explore``: as ``deformap.explore``
# it would hide its package once that is imported)
_PACKAGES = ("cloud", "environment", "eval", "explore", "gp", "mechanics", "msm", "replay", "run",
             "stiffness", "viz", "world")  # fmt: skip
_names_getattr, __dir__ = lazy_exports(__name__, _MODULES, [*__all__, *_PACKAGES], globals())


def __getattr__(name: str) -> Any:
    if name in _PACKAGES:
        return importlib.import_module(f"{__name__}.{name}")
    return _names_getattr(name)
