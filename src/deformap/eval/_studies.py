"""Studies on homogeneous simulated foams: β against hardness (the paper's Fig. 5a) and the fit error
against cluster size (its Fig. 5b).

Each foam is a homogeneous block over the whole workspace, pressed at a few fixed places with the
same force; every protocol and cluster size is evaluated on the *same* presses, so differences come
from the estimator alone.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from deformap.environment import PressObservation, Workspace
from deformap.explore import ExplorationConfig, Mapper, PokeRecord, measure_press
from deformap.msm import ShapeMatchingConfig
from deformap.world import Block, Scenario, SimulatedWorld, WorldConfig

__all__ = [
    "DEFAULT_HARDNESSES",
    "DEFAULT_POSITIONS",
    "PROTOCOLS",
    "FoamPresses",
    "cluster_size_study",
    "collect_presses",
    "hardness_study",
]

logger = logging.getLogger(__name__)

DEFAULT_HARDNESSES: tuple[float | None, ...] = (30.0, 60.0, 110.0, 150.0, 250.0, None)
"""Foams of the study in newtons (ISO 2439); ``None`` is the rigid board."""

DEFAULT_POSITIONS: tuple[tuple[float, float], ...] = ((0.30, 0.20), (0.18, 0.12), (0.42, 0.28))
"""Where each foam is pressed: the centre and two places well inside the block."""

PROTOCOLS: dict[str, dict[str, Any]] = {
    "force/quadratic": {"contact": "force", "mode": "quadratic"},
    "force/linear": {"contact": "force", "mode": "linear"},
    "pinned/quadratic": {"contact": "pinned", "mode": "quadratic"},
    "pinned/linear": {"contact": "pinned", "mode": "linear"},
}
"""The contact protocols compared (see :mod:`deformap.msm`)."""


@dataclass
class FoamPresses:
    """One homogeneous foam: the mapper with its surface model and the presses made on it."""

    hardness_n: float | None
    mapper: Mapper
    presses: list[PressObservation]
    true_modulus_pa: float | None = None  # the world's own, at the presses (None: rigid)


def _block_scenario(hardness_n: float | None, workspace: Workspace,
                    thickness_m: float = 0.05) -> Scenario:
    (x0, y0), (x1, y1) = workspace.lower, workspace.upper
    polygon = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    if hardness_n is None:
        block = Block(name="rigid", polygon=polygon, rigid=True, thickness_m=thickness_m)
        name = "homogeneous-rigid"
    else:
        block = Block(name=f"{hardness_n:g} N foam", polygon=polygon, hardness_n=hardness_n,
                      thickness_m=thickness_m)
        name = f"homogeneous-{hardness_n:g}"
    return Scenario(name=name, blocks=(block,), workspace=workspace)


def collect_presses(
    hardnesses: Sequence[float | None] = DEFAULT_HARDNESSES,
    *,
    world_config: WorldConfig | None = None,
    config: ExplorationConfig | None = None,
    positions: Sequence[tuple[float, float]] = DEFAULT_POSITIONS,
    rng: np.random.Generator,
    progress: Callable[[str], None] | None = None,
    thickness_m: float = 0.05,
) -> list[FoamPresses]:
    """Build one world per foam (a block ``thickness_m`` thick over the workspace), observe it,
    and press it at ``positions`` with the configuration's ``force_n``."""
    world_config = world_config or WorldConfig()
    config = config or ExplorationConfig()
    streams = rng.spawn(len(hardnesses))
    out = []
    for hardness, stream in zip(hardnesses, streams, strict=True):
        world_rng, fit_rng = stream.spawn(2)
        world = SimulatedWorld(
            _block_scenario(hardness, Workspace(), thickness_m), config=world_config,
            rng=world_rng,
        )
        mapper = Mapper(world.workspace, config)
        mapper.initialise(world.observe(), fit_rng)
        presses = []
        for xy in positions:
            presses.append(world.press(np.asarray(xy), config.force_n))
            world.release()
        x, y = positions[0]
        true = float(world.ground_truth_modulus(np.array([x]), np.array([y]))[0, 0])
        out.append(FoamPresses(hardness, mapper, presses, true if math.isfinite(true) else None))
        if progress is not None:
            progress(f"pressed {'rigid' if hardness is None else f'{hardness:g} N'} foam")
    return out


def _betas(foam: FoamPresses, shape_matching: ShapeMatchingConfig) -> list[PokeRecord]:
    base = foam.mapper
    assert base.surface is not None  # collect_presses fitted it
    config = dataclasses.replace(base.config, shape_matching=shape_matching)
    return [measure_press(obs, i, base.surface, config).record
            for i, obs in enumerate(foam.presses)]


def _summary(records: list[PokeRecord]) -> dict[str, float]:
    betas = np.array([r.beta for r in records])
    return {
        "beta": float(betas.mean()),
        "beta_std": float(betas.std(ddof=1)) if betas.size > 1 else float("nan"),
        "beta_estimate_std": float(np.mean([r.beta_std for r in records])),
        "fit_error_m": float(np.mean([min(r.errors) for r in records])),
        "iterations": int(max(r.iterations for r in records)),
        "converged": bool(all(r.converged for r in records)),
    }


def _stiffness_summary(records: list[PokeRecord], true_modulus_pa: float | None
                       ) -> dict[str, Any]:
    """What the presses' force–travel records read: the mean stiffness and Young's modulus over
    the presses that gave one, the mean claimed σ of E, its spread between places, the world's
    true modulus and E's relative error; ``rigid`` when every press was read rigid, ``n_rigid``
    how many were (a foam some of whose presses read rigid is not averaged over silently)."""
    estimates = [r.stiffness for r in records]
    read = [s for s in estimates if s is not None and not s.rigid and s.modulus_pa is not None]
    moduli = np.array([s.modulus_pa for s in read], dtype=float)
    out: dict[str, Any] = {
        "rigid": bool(estimates) and all(s is not None and s.rigid for s in estimates),
        "n_rigid": sum(s is not None and s.rigid for s in estimates),
        "stiffness_n_per_m": float(np.mean([s.stiffness_n_per_m for s in read])) if read else None,
        "modulus_pa": float(moduli.mean()) if read else None,
        "modulus_std_pa": float(np.mean([s.modulus_std_pa for s in read])) if read else None,
        "modulus_spread_pa": float(moduli.std(ddof=1)) if moduli.size > 1 else None,
        "true_modulus_pa": true_modulus_pa,
        "modulus_rel_error": None,
    }
    if read and true_modulus_pa:
        out["modulus_rel_error"] = float((moduli.mean() - true_modulus_pa) / true_modulus_pa)
    return out


def hardness_study(
    foams: list[FoamPresses],
    *,
    base: ShapeMatchingConfig | None = None,
    protocols: dict[str, dict[str, Any]] = PROTOCOLS,
) -> dict[str, Any]:
    """β against hardness for each protocol: ``{"rows": [...], "monotone": {protocol: bool}}``.

    A protocol is *monotone* when β strictly rises as hardness falls over the foams, with the rigid
    board (if present) below every foam.
    """
    base = base or ShapeMatchingConfig()
    rows = []
    monotone = {}
    for name, settings in protocols.items():
        cfg = dataclasses.replace(base, **settings)
        proto_rows = []
        for foam in foams:
            records = _betas(foam, cfg)
            row = {"protocol": name, "hardness_n": foam.hardness_n, **_summary(records),
                   **_stiffness_summary(records, foam.true_modulus_pa)}  # fmt: skip
            proto_rows.append(row)
        rows.extend(proto_rows)
        ordered = sorted(
            proto_rows, key=lambda r: math.inf if r["hardness_n"] is None else r["hardness_n"]
        )
        monotone[name] = bool(np.all(np.diff([r["beta"] for r in ordered]) < 0))
    return {"rows": rows, "monotone": monotone, "modulus_monotone": _modulus_monotone(rows)}


def _modulus_monotone(rows: list[dict[str, Any]]) -> bool | None:
    """Whether the force–travel records order the foams: E strictly rises with hardness and a
    rigid board is read rigid (``None`` when the presses had no records)."""
    first = rows[0]["protocol"] if rows else None
    own = sorted((r for r in rows if r["protocol"] == first),
                 key=lambda r: math.inf if r["hardness_n"] is None else r["hardness_n"])
    if not own or all(r["modulus_pa"] is None and not r["rigid"] for r in own):
        return None
    foams = [r for r in own if r["hardness_n"] is not None]
    moduli = [r["modulus_pa"] for r in foams]
    if any(m is None for m in moduli) or any(r["rigid"] for r in foams):
        return False
    rigid_ok = all(r["rigid"] for r in own if r["hardness_n"] is None)
    return bool(np.all(np.diff(moduli) > 0) and rigid_ok)


def cluster_size_study(
    foams: list[FoamPresses],
    *,
    sizes: Sequence[int] = (2, 3, 4, 5, 6),
    base: ShapeMatchingConfig | None = None,
) -> dict[str, Any]:
    """Fit error min E(β) and β against the cluster size k×k (default protocol), per foam."""
    base = base or ShapeMatchingConfig()
    rows = []
    for k in sizes:
        cfg = dataclasses.replace(base, cluster_size=k)
        for foam in foams:
            rows.append(
                {"cluster_size": k, "hardness_n": foam.hardness_n, **_summary(_betas(foam, cfg))}
            )
    return {"rows": rows}
