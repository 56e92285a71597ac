"""A press's dent read with its force–travel record: the tactile cap from the indentation, the
depth anchored by the record (not by the tip's absolute height), an honest σ(β), and presses
without a record (issue 13, item 4)."""

from __future__ import annotations

import dataclasses
from functools import cache

import numpy as np
import pytest

from deformap.environment import PressObservation, TactileContact, Workspace
from deformap.explore import (
    ExplorationConfig,
    Mapper,
    SurfaceGPConfig,
    TouchGPConfig,
    measure_press,
)
from deformap.explore._dent import UNINFORMED_BETA_STD, dent_visible
from deformap.explore._surface import SurfaceModel
from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig

SIDE_M = 0.24
WORKSPACE = Workspace(lower=(0.0, 0.0), upper=(SIDE_M, SIDE_M))
CENTRE = np.array([SIDE_M / 2, SIDE_M / 2])
# a flat block's surface needs no hyperparameter search (a second of the test, not twenty)
CONFIG = ExplorationConfig(surface=SurfaceGPConfig(fit_hyperparameters=False))
# the paper's fixed cap on the tip where proprioception puts it: what the record replaces
TIP_ONLY = dataclasses.replace(
    CONFIG, touch=dataclasses.replace(CONFIG.touch, tactile_cap="fixed", depth_anchor="tip"))


@cache
def _press(hardness_n: float | None, thickness_m: float = 0.05
           ) -> tuple[PressObservation, SurfaceModel]:
    """One press at the centre of a homogeneous block on the coarse test mesh."""
    polygon = np.array([[0, 0], [SIDE_M, 0], [SIDE_M, SIDE_M], [0, SIDE_M]])
    block = (Block(name="board", polygon=polygon, rigid=True, thickness_m=thickness_m)
             if hardness_n is None else
             Block(name="foam", polygon=polygon, hardness_n=hardness_n, thickness_m=thickness_m))
    world = SimulatedWorld(Scenario(name="block", blocks=(block,), workspace=WORKSPACE),
                           config=WorldConfig.coarse(), rng=np.random.default_rng(0))
    surface = Mapper(WORKSPACE, CONFIG).initialise(world.observe(), np.random.default_rng(1))
    obs = world.press(CENTRE, CONFIG.force_n)
    world.release()
    return obs, surface


def _tip_moved(obs: PressObservation, dz: float) -> PressObservation:
    c = obs.contact
    tip = TactileContact(tip_center=c.tip_center + np.array([0.0, 0.0, dz]), force=c.force,
                         tip_radius_m=c.tip_radius_m)
    return dataclasses.replace(obs, contact=tip)


@pytest.mark.parametrize("hardness_n", [60.0, 150.0])
def test_a_millimetre_of_tip_height_error_moves_beta_little_with_a_record(
        hardness_n: float) -> None:
    obs, surface = _press(hardness_n)
    assert obs.force_travel is not None
    betas = {dz: measure_press(_tip_moved(obs, dz), 0, surface, CONFIG).record.beta
             for dz in (0.0, -0.001, 0.001)}
    assert max(abs(betas[dz] - betas[0.0]) for dz in (-0.001, 0.001)) <= 0.05
    if hardness_n == 150.0:
        # read against the tip, the same millimetre moves the hard foam's β far more: the
        # test can fail
        tip = {dz: measure_press(_tip_moved(obs, dz), 0, surface, TIP_ONLY).record.beta
               for dz in (0.0, -0.001, 0.001)}
        assert max(abs(tip[dz] - tip[0.0]) for dz in (-0.001, 0.001)) > 0.1


def test_the_tactile_points_cover_the_cap_the_measured_indentation_touches() -> None:
    soft, hard, board = (measure_press(*_args(h), CONFIG) for h in (30.0, 250.0, None))
    for poke in (soft, hard, board):
        r, dent = poke.record, poke.dent
        assert r.depth_anchored is True and r.stiffness is not None
        assert r.indentation_m == pytest.approx(0.0 if r.stiffness.rigid else r.stiffness.depth_m)
        # no tactile point lies beyond the tip's contact edge, √(Rδ) from the axis: the cap's
        # rim at θ = asin(√(Rδ)/R) about the measured force, whose sensor noise tilts it by α
        # from the vertical, reaches 2R sin(θ/2) cos(θ/2 − α) from the pole in plan
        # (R sin θ untilted)
        radius = r.contact.tip_radius_m
        offset = np.linalg.norm(dent.tactile[:, :2] - dent.tactile[0, :2], axis=1)
        force = np.asarray(r.contact.force)
        tilt = float(np.arccos(abs(force[2]) / np.linalg.norm(force)))
        half = float(np.arcsin(min(np.sqrt(radius * r.indentation_m) / radius, 1.0)))
        rim = 2.0 * radius * np.sin(half / 2.0) * np.cos(max(half / 2.0 - tilt, 0.0))
        assert offset.max() <= rim + 1e-9
        assert rim <= np.sqrt(radius * r.indentation_m) * 1.01
    assert soft.record.indentation_m > hard.record.indentation_m > 0.0
    assert len(soft.dent.tactile) >= len(hard.dent.tactile) > 1

    def reach(poke: object) -> float:  # how far from the axis the cap reaches
        tactile = poke.dent.tactile  # type: ignore[attr-defined]
        return float(np.linalg.norm(tactile[:, :2] - tactile[0, :2], axis=1).max())

    assert reach(soft) > reach(hard) > 0.0
    # the board is read rigid: the pole alone, on the surface model, and β = 0 is known
    assert board.record.stiffness is not None and board.record.stiffness.rigid
    assert len(board.dent.tactile) == 1 and board.record.beta == 0.0
    obs, surface = _press(None)
    rest = float(np.asarray(surface.gp.predict(obs.contact.contact_point[None, :2]))[0])
    assert board.dent.tactile[0, 2] == pytest.approx(rest, abs=1e-9)
    assert board.record.beta_std < 0.05
    # the paper's cap: ten points on 30° wherever the tip is
    assert len(measure_press(*_args(250.0), TIP_ONLY).dent.tactile) == 10


def _args(hardness_n: float | None) -> tuple[PressObservation, int, SurfaceModel]:
    obs, surface = _press(hardness_n)
    return obs, 0, surface


def test_a_press_without_a_record_reads_the_dent_against_the_tip() -> None:
    obs, surface = _press(60.0)
    bare = dataclasses.replace(obs, force_travel=None)
    poke = measure_press(bare, 0, surface, CONFIG)
    r = poke.record
    assert r.stiffness is None and r.depth_anchored is False
    rest = float(np.asarray(surface.gp.predict(obs.contact.contact_point[None, :2]))[0])
    assert r.indentation_m == pytest.approx(rest - obs.contact.contact_point[2])
    np.testing.assert_allclose(poke.dent.tactile[0], obs.contact.contact_point, atol=1e-12)
    with_record = measure_press(obs, 0, surface, CONFIG).record
    assert 0.3 < r.beta < 1.0 and abs(r.beta - with_record.beta) < 0.1
    # a tip height error now moves the dent, as before the record existed
    moved = measure_press(_tip_moved(bare, 0.001), 0, surface, CONFIG).record
    assert moved.indentation_m == pytest.approx(r.indentation_m - 0.001, abs=1e-9)


def test_a_dent_within_the_cameras_noise_claims_an_uninformed_sigma() -> None:
    # half the indentation against the camera's mean height over n points: 2 σ/√n
    assert dent_visible(0.002, 0.002, 16, 2.0)  # 1 mm edge against 1 mm
    assert not dent_visible(0.0019, 0.002, 16, 2.0)
    assert not dent_visible(0.01, 0.002, 0, 2.0)  # nothing seen around the tip
    assert dent_visible(1e-9, 0.002, 16, 0.0)  # the test switched off
    obs, surface = _press(250.0)
    seen = measure_press(obs, 0, surface, CONFIG).record
    assert seen.dent_visible is True and seen.beta_std < UNINFORMED_BETA_STD
    # the same press where the camera is twice as far from seeing its dent as it must be
    strict = dataclasses.replace(CONFIG, touch=TouchGPConfig(dent_visible_sigmas=1e4))
    unseen = measure_press(obs, 0, surface, strict).record
    assert unseen.dent_visible is False and unseen.beta == seen.beta
    assert unseen.beta_std == pytest.approx(UNINFORMED_BETA_STD)
    # a record that reads the board rigid has measured β = 0: nothing to widen
    board = measure_press(*_args(None), strict).record
    assert board.dent_visible is False and board.beta_std < 0.05
