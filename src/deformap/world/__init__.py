"""The simulated world: foam scenarios, physics ground truth, a depth camera and a probe.

:class:`SimulatedWorld` implements :class:`deformap.environment.Environment` and never imports the
estimator (``msm``, ``gp``, ``explore``), so accuracy figures are never circular; its physics is
chosen by ``WorldConfig.physics``. Every frame carries colour (``cloud.colors``, sRGB): each block
has an :class:`Appearance`, lit by one light and seen through the camera's colour sensor;
``world.rgb_image()`` is the camera's colour image of the scene. Hertz contact and the
hardness–modulus conversion of :mod:`deformap.mechanics` are re-exported here.
"""

from __future__ import annotations

from deformap.mechanics import (
    hardness_to_youngs_modulus,
    hertz_contact_radius,
    hertz_indentation,
    hertz_pressure_samples,
    youngs_modulus_to_hardness,
)
from deformap.world._appearance import Appearance, Split
from deformap.world._camera import CAMERA_PRESETS, CameraConfig, camera_preset
from deformap.world._config import PHYSICS, Physics, WorldConfig, check_world_budget
from deformap.world._foam import Dent
from deformap.world._layouts import LAYOUT_FAMILIES, LayoutFamily
from deformap.world._materials import Orthotropic, Plastic, Viscoelastic
from deformap.world._paint import APPEARANCE_FAMILIES, AppearanceFamily
from deformap.world._probe import ProbeGeometry
from deformap.world._random import random_scenario
from deformap.world._scenario import BARE_TABLE, Block, Scenario
from deformap.world._scenario_io import list_scenarios, load_scenario, save_scenario
from deformap.world._world import MIN_RECORD_FORCE_N, SimulatedWorld

__all__ = [
    "APPEARANCE_FAMILIES", "BARE_TABLE", "CAMERA_PRESETS", "LAYOUT_FAMILIES", "MIN_RECORD_FORCE_N",
    "PHYSICS", "Appearance", "AppearanceFamily", "Block", "CameraConfig", "Dent", "LayoutFamily",
    "Orthotropic", "Physics", "Plastic", "ProbeGeometry", "Scenario", "SimulatedWorld", "Split",
    "Viscoelastic", "WorldConfig",
    "camera_preset", "check_world_budget", "hardness_to_youngs_modulus", "hertz_contact_radius",
    "hertz_indentation", "hertz_pressure_samples", "list_scenarios", "load_scenario",
    "random_scenario", "save_scenario", "youngs_modulus_to_hardness",
]
