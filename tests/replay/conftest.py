"""Synthetic sessions: a flat foam top at 5 cm with a dent under each poke (no simulator needed)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import ForceTravel, PressObservation, TactileContact, Workspace
from deformap.replay import GroundTruth

TOP_M = 0.05
TIP_M = 0.01


@dataclass
class Synthetic:
    workspace: Workspace
    observation: PointCloud
    presses: list[PressObservation]
    truth: GroundTruth


def _surface(rng: np.random.Generator, n: int, dents: list[tuple[np.ndarray, float]]) -> np.ndarray:
    xy = rng.uniform([0.0, 0.0], [0.6, 0.4], (n, 2))
    z = np.full(n, TOP_M) + rng.normal(0, 5e-4, n)
    for center, depth in dents:
        z -= depth * np.exp(-np.sum((xy - center) ** 2, axis=1) / 0.015**2)
    return np.column_stack([xy, z])


def _robot(tip: np.ndarray) -> np.ndarray:
    """A stick: a square prism from the tip's centre up 25 cm."""
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * 0.006
    low = np.column_stack([tip[:2] + corners, np.full(4, tip[2])])
    high = np.column_stack([tip[:2] + corners, np.full(4, tip[2] + 0.25)])
    return np.vstack([low, high])


def make_synthetic(seed: int = 0, n_pokes: int = 3, n_points: int = 1500) -> Synthetic:
    rng = np.random.default_rng(seed)
    record_rng = np.random.default_rng([seed, 1])
    presses = []
    for i in range(n_pokes):
        target = np.array([0.1 + 0.4 * i / max(n_pokes - 1, 1), 0.2])
        depth = 0.004 + 0.002 * i
        tip = np.array([target[0], target[1], TOP_M - depth + TIP_M])
        cloud = PointCloud(np.vstack([_surface(rng, n_points, [(target, depth)]), _robot(tip)]))
        contact = TactileContact(tip_center=tip, force=np.array([0.0, 0.0, -1.0]),
                                 tip_radius_m=TIP_M)  # fmt: skip
        # a force–travel record on every poke but the second (adapters may lack it), its noise
        # from its own stream so that the clouds stay what they were before records existed
        record = None if i == 1 else ForceTravel(
            travel_m=np.linspace(0.0, depth, 9) + record_rng.normal(0, 5e-5, 9),
            force_n=np.linspace(0.02, 1.0, 9) + record_rng.normal(0, 0.01, 9))
        presses.append(PressObservation(cloud=cloud, contact=contact, robot_points=_robot(tip),
                                        target_xy=target, force_n=1.0,
                                        force_travel=record))  # fmt: skip
    xs, ys = np.linspace(0.0025, 0.5975, 120), np.linspace(0.0025, 0.3975, 80)
    labels = (xs[None, :] > 0.3).astype(np.int64) * np.ones((80, 1), dtype=np.int64)
    hardness = np.where(labels == 1, np.inf, 80.0)
    return Synthetic(Workspace(), PointCloud(_surface(rng, n_points, [])), presses,
                     GroundTruth(xs, ys, labels, hardness))  # fmt: skip


@pytest.fixture(scope="session")
def synthetic() -> Synthetic:
    return make_synthetic()


def write_synthetic(folder: Path, syn: Synthetic, *, sealed: bool = True,
                    **kwargs: object) -> Path:  # fmt: skip
    """``write_session`` of ``syn``; ``sealed=False`` drops ``n_pokes`` and the ``sha256``
    manifest, as for a session whose files a test then edits by hand."""
    import yaml

    from deformap.replay import write_session

    file = write_session(
        folder,
        workspace=syn.workspace,
        observation=syn.observation,
        presses=syn.presses,
        ground_truth=syn.truth,
        **kwargs,
    )  # type: ignore[arg-type]
    if not sealed:
        doc = yaml.safe_load(file.read_text())
        del doc["n_pokes"], doc["sha256"]
        file.write_text(yaml.safe_dump(doc, sort_keys=False))
    return file


@pytest.fixture(name="write_synthetic", scope="session")
def _write_synthetic_fixture():  # type: ignore[no-untyped-def]
    return write_synthetic


@pytest.fixture(name="make_synthetic", scope="session")
def _make_synthetic_fixture():  # type: ignore[no-untyped-def]
    return make_synthetic
