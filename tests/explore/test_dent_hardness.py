"""β orders the foams by hardness under other cameras and foam thicknesses, with the press's
force–travel record anchoring the dent (issue 13, item 4): one press at the centre of a
homogeneous block per foam, on the coarse test mesh."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.environment import Workspace
from deformap.explore import (
    ExplorationConfig,
    Mapper,
    SurfaceGPConfig,
    TouchGPConfig,
    measure_press,
)
from deformap.msm import ShapeMatchingConfig
from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig, camera_preset

HARDNESSES_N = (30.0, 60.0, 110.0, 150.0, 250.0)
SIDE_M = 0.24
WORKSPACE = Workspace(lower=(0.0, 0.0), upper=(SIDE_M, SIDE_M))
# β̂ alone is compared: no noise draws for its σ, no hyperparameter search on a flat block
CONFIG = ExplorationConfig(
    surface=SurfaceGPConfig(fit_hyperparameters=False),
    touch=TouchGPConfig(noise_samples=0), beta_uncertainty="shape-matching",
    shape_matching=ShapeMatchingConfig(uncertainty="tolerance"),
)


def _beta(hardness_n: float, camera: str, thickness_m: float) -> float:
    polygon = np.array([[0, 0], [SIDE_M, 0], [SIDE_M, SIDE_M], [0, SIDE_M]])
    block = Block(name="foam", polygon=polygon, hardness_n=hardness_n, thickness_m=thickness_m)
    world = SimulatedWorld(Scenario(name="block", blocks=(block,), workspace=WORKSPACE),
                           config=WorldConfig.coarse(camera=camera_preset(camera)),
                           rng=np.random.default_rng(0))
    surface = Mapper(WORKSPACE, CONFIG).initialise(world.observe(), np.random.default_rng(1))
    obs = world.press(np.array([SIDE_M / 2, SIDE_M / 2]), CONFIG.force_n)
    world.release()
    assert obs.force_travel is not None
    record = measure_press(obs, 0, surface, CONFIG).record
    assert record.depth_anchored is True
    return record.beta


@pytest.mark.parametrize("thickness_m", [0.03, 0.05])
@pytest.mark.parametrize("camera", ["primesense", "kinect-v1"])
def test_beta_falls_strictly_as_the_foam_hardens(camera: str, thickness_m: float) -> None:
    betas = [_beta(h, camera, thickness_m) for h in HARDNESSES_N]
    assert np.all(np.diff(betas) < 0), betas
    assert betas[0] > 0.5  # the softest foam is read far from the rigid end
