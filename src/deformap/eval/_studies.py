"""Studies on homogeneous simulated foams: β against hardness (the paper's Fig. 5a) and the fit
error against cluster size (its Fig. 5b). Each foam, a block over the whole workspace, is pressed
at a few fixed places; every protocol and cluster size reads the *same* presses.

The behaviour study is :mod:`deformap.eval._behaviour_study`.
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
from deformap.errors import InvalidArgumentError
from deformap.explore import ExplorationConfig, Mapper, PokeRecord, measure_press
from deformap.msm import ShapeMatchingConfig
from deformap.world import (
    Block,
    Scenario,
    SimulatedWorld,
    WorldConfig,
)

__all__ = [
    "DEFAULT_HARDNESSES", "DEFAULT_POSITIONS", "DEFAULT_PROTOCOL", "PAPER_PROTOCOL", "PROTOCOLS",
    "STUDY_PROTOCOLS", "FoamPresses", "block_scenario", "cluster_size_study", "collect_presses",
    "fraction", "hardness_study", "hardness_summary",
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

DEFAULT_PROTOCOL = "force/quadratic"
"""The protocol of :class:`~deformap.msm.ShapeMatchingConfig`'s defaults (the summary's rows)."""

PAPER_PROTOCOL = "pinned/quadratic"
"""The paper's protocol (Caccamo et al.: the particle under the tip pinned at the observed dent)."""

STUDY_PROTOCOLS: tuple[str, ...] = (DEFAULT_PROTOCOL, PAPER_PROTOCOL)
"""The protocols a hardness study runs unless asked for others (each is one β fit per press)."""

CONDITION_KEYS = ("camera", "thickness_m", "physics", "force_n")
"""The keys of a row that name its condition (one combination of a study's matrix)."""


@dataclass
class FoamPresses:
    """One homogeneous foam: the mapper with its surface model and the presses made on it, or
    none and the world's reason it ``refused`` to press the foam."""

    hardness_n: float | None
    mapper: Mapper
    presses: list[PressObservation]
    true_modulus_pa: float | None = None  # the world's own, at the presses (None: rigid)
    refused: str | None = None


def block_scenario(hardness_n: float | None, workspace: Workspace,
                   thickness_m: float = 0.05) -> Scenario:
    """One block over ``workspace``: a foam of ``hardness_n`` newtons, or the rigid board (None);
    the block's own checks refuse a material or thickness the world cannot press."""
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
    hardnesses: Sequence[float | None] = DEFAULT_HARDNESSES, *,
    world_config: WorldConfig | None = None, config: ExplorationConfig | None = None,
    positions: Sequence[tuple[float, float]] = DEFAULT_POSITIONS, rng: np.random.Generator,
    progress: Callable[[str], None] | None = None, thickness_m: float = 0.05,
) -> list[FoamPresses]:  # fmt: skip
    """Build one world per foam (a block ``thickness_m`` thick over the workspace), observe it,
    and press it at ``positions`` with the configuration's ``force_n``. A foam the world refuses
    to press with that force is kept with no presses and the world's reason in ``refused``."""
    world_config = world_config or WorldConfig()
    config = config or ExplorationConfig()
    streams = rng.spawn(len(hardnesses))
    out = []
    for hardness, stream in zip(hardnesses, streams, strict=True):
        world_rng, fit_rng = stream.spawn(2)
        world = SimulatedWorld(block_scenario(hardness, Workspace(), thickness_m),
                               config=world_config, rng=world_rng)
        mapper = Mapper(world.workspace, config)
        mapper.initialise(world.observe(), fit_rng)
        presses: list[PressObservation] = []
        refused = None
        try:
            for xy in positions:
                presses.append(world.press(np.asarray(xy), config.force_n))
                world.release()
        except InvalidArgumentError as error:
            presses, refused = [], str(error)
            logger.warning("foam %s refused: %s", hardness, refused)
        x, y = positions[0]
        true = float(world.ground_truth_modulus(np.array([x]), np.array([y]))[0, 0])
        out.append(FoamPresses(hardness, mapper, presses, true if math.isfinite(true) else None,
                               refused))  # fmt: skip
        if progress is not None:
            name = "rigid" if hardness is None else f"{hardness:g} N"
            progress(f"pressed {name} foam" if refused is None else f"{name} foam refused")
    return out


def _betas(foam: FoamPresses, shape_matching: ShapeMatchingConfig) -> list[PokeRecord]:
    base = foam.mapper
    assert base.surface is not None  # collect_presses fitted it
    config = dataclasses.replace(base.config, shape_matching=shape_matching)
    return [measure_press(obs, i, base.surface, config).record
            for i, obs in enumerate(foam.presses)]


def _summary(records: list[PokeRecord]) -> dict[str, float]:
    betas = np.array([r.beta for r in records])
    return {"beta": float(betas.mean()),
            "beta_std": float(betas.std(ddof=1)) if betas.size > 1 else float("nan"),
            "beta_estimate_std": float(np.mean([r.beta_std for r in records])),
            "fit_error_m": float(np.mean([min(r.errors) for r in records])),
            "iterations": int(max(r.iterations for r in records)),
            "converged": bool(all(r.converged for r in records))}


def _stiffness_summary(records: list[PokeRecord], true_modulus_pa: float | None
                       ) -> dict[str, Any]:
    """The force–travel readings: means over the presses that gave a modulus, their spread, the
    true E and the relative errors; ``rigid`` when every press read rigid, ``n_rigid`` how many
    did; ``moduli_pa``, ``modulus_stds_pa`` and ``modulus_rel_errors`` per press (None: none)."""
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
        "moduli_pa": [_read(s, "modulus_pa") for s in estimates],
        "modulus_stds_pa": [_read(s, "modulus_std_pa") for s in estimates],
        "modulus_rel_errors": [None] * len(estimates),
    }
    if read and true_modulus_pa:
        out["modulus_rel_error"] = float((moduli.mean() - true_modulus_pa) / true_modulus_pa)
        out["modulus_rel_errors"] = [None if e is None else (e - true_modulus_pa) / true_modulus_pa
                                     for e in out["moduli_pa"]]  # fmt: skip
    return out


def _read(estimate: Any, key: str) -> float | None:
    """One press's value of ``key`` (None when the press gave no modulus or read rigid)."""
    if estimate is None or estimate.rigid or estimate.modulus_pa is None:
        return None
    value = getattr(estimate, key)
    return None if value is None else float(value)


def _foam_row(foam: FoamPresses, shape_matching: ShapeMatchingConfig) -> dict[str, Any]:
    """One foam's values under one protocol; a refused foam's row has its reason and none."""
    if foam.refused is None:
        records = _betas(foam, shape_matching)
        return {**_summary(records), **_stiffness_summary(records, foam.true_modulus_pa),
                "refused": None}
    keys = ("beta", "beta_std", "beta_estimate_std", "fit_error_m", "iterations", "converged",
            "stiffness_n_per_m", "modulus_pa", "modulus_std_pa", "modulus_spread_pa",
            "modulus_rel_error", "rigid", "n_rigid")  # fmt: skip
    return {**dict.fromkeys(keys), "true_modulus_pa": foam.true_modulus_pa, "moduli_pa": [],
            "modulus_stds_pa": [], "modulus_rel_errors": [], "refused": foam.refused}


def hardness_study(foams: list[FoamPresses], *,
                   protocols: dict[str, dict[str, Any]] = PROTOCOLS) -> dict[str, Any]:
    """β against hardness for each protocol: ``{"rows": [...], "monotone": {protocol: bool},
    "modulus_monotone": bool | None, "n_refused": int}``.

    A protocol is *monotone* when β strictly rises as hardness falls over the foams, with the rigid
    board (if present) below every foam. A foam the world refused to press has a row with
    ``refused`` (the reason) and null values, and is left out of both monotone checks.
    """
    rows = []
    monotone = {}
    for name, settings in protocols.items():
        cfg = ShapeMatchingConfig(**settings)
        proto_rows = [{"protocol": name, "hardness_n": foam.hardness_n, **_foam_row(foam, cfg)}
                      for foam in foams]
        rows.extend(proto_rows)
        monotone[name] = _beta_monotone(proto_rows)
    return {"rows": rows, "monotone": monotone, "modulus_monotone": _modulus_monotone(rows),
            "n_refused": sum(f.refused is not None for f in foams)}  # fmt: skip


def _by_hardness(rows: Any) -> list[dict[str, Any]]:
    """The rows of the foams the world pressed, by rising hardness, the rigid board last."""
    kept = [r for r in rows if not r.get("refused")]
    return sorted(kept, key=lambda r: math.inf if r["hardness_n"] is None else r["hardness_n"])


def _beta_monotone(rows: list[dict[str, Any]]) -> bool:
    """β strictly falls as hardness rises over one protocol's rows, the rigid board lowest
    (refused foams left out; fewer than two is False)."""
    betas = [r["beta"] for r in _by_hardness(rows)]
    return len(betas) >= 2 and bool(np.all(np.diff(betas) < 0))


def _modulus_monotone(rows: list[dict[str, Any]]) -> bool | None:
    """E strictly rises with hardness and a rigid board reads rigid (refused foams left out);
    ``None`` when the presses had no records."""
    first = rows[0]["protocol"] if rows else None
    own = _by_hardness(r for r in rows if r["protocol"] == first)
    if not own or all(r["modulus_pa"] is None and not r["rigid"] for r in own):
        return None
    foams = [r for r in own if r["hardness_n"] is not None]
    moduli = [r["modulus_pa"] for r in foams]
    if any(m is None for m in moduli) or any(r["rigid"] for r in foams):
        return False
    rigid_ok = all(r["rigid"] for r in own if r["hardness_n"] is None)
    return bool(np.all(np.diff(moduli) > 0) and rigid_ok)


def cluster_size_study(foams: list[FoamPresses], *, sizes: Sequence[int] = (2, 3, 4, 5, 6)
                       ) -> dict[str, Any]:
    """Fit error min E(β) and β against the cluster size k×k (default protocol), per foam."""
    return {"rows": [{"cluster_size": k, "hardness_n": foam.hardness_n,
                      **_summary(_betas(foam, ShapeMatchingConfig(cluster_size=k)))}
                     for k in sizes for foam in foams]}


def hardness_summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """What a hardness study's rows of :data:`DEFAULT_PROTOCOL` (else the first) say, grouped by
    condition (:data:`CONDITION_KEYS`): ``{"summary": [...], "overall": [...]}``, per condition,
    over the foam presses, ``n_presses``, ``n_unread`` (no modulus),
    ``modulus_median_abs_rel_error`` (median |E − E_true| / E_true of the presses read),
    ``modulus_within_2sigma`` (fraction of all presses within 2 claimed σ; unread counts out),
    ``modulus_monotone``, ``beta_monotone``, ``beta_claimed_std`` and ``beta_spread`` (means over
    the foams) and ``n_refused``; per physics the same over its conditions (monotone: in all)."""
    protocols = list(dict.fromkeys(r["protocol"] for r in rows))
    protocol = DEFAULT_PROTOCOL if DEFAULT_PROTOCOL in protocols else protocols[0] if rows else None
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for row in rows:
        if row["protocol"] == protocol:
            groups.setdefault(tuple(row.get(k) for k in CONDITION_KEYS), []).append(row)
    summary = [_condition_summary(condition, group) for condition, group in groups.items()]
    overall = [_physics_summary(physics, [s for s in summary if s["physics"] == physics])
               for physics in dict.fromkeys(s["physics"] for s in summary)]
    for s in summary:
        del s["_errors"], s["_covered"]
    return {"summary": summary, "overall": overall}


def _condition_summary(condition: tuple[Any, ...], group: list[dict[str, Any]]) -> dict[str, Any]:
    errors, covered, n_presses = _press_errors(group)
    foams = [r for r in group if r["hardness_n"] is not None and not r.get("refused")]
    return {
        **dict(zip(CONDITION_KEYS, condition, strict=True)),
        "n_presses": n_presses, "n_unread": n_presses - len(errors),
        "modulus_median_abs_rel_error": _median_abs(errors),
        "modulus_within_2sigma": fraction(covered, n_presses),
        "modulus_monotone": _modulus_monotone(group), "beta_monotone": _beta_monotone(group),
        "beta_claimed_std": _mean([r["beta_estimate_std"] for r in foams]),
        "beta_spread": _mean([r["beta_std"] for r in foams]),
        "n_refused": sum(bool(r.get("refused")) for r in group),
        "_errors": errors, "_covered": covered,
    }  # fmt: skip


def _physics_summary(physics: Any, mine: list[dict[str, Any]]) -> dict[str, Any]:
    n_presses = sum(s["n_presses"] for s in mine)
    return {
        "physics": physics, "n_conditions": len(mine), "n_presses": n_presses,
        "n_unread": sum(s["n_unread"] for s in mine),
        "modulus_median_abs_rel_error": _median_abs([e for s in mine for e in s["_errors"]]),
        "modulus_within_2sigma": fraction(sum(s["_covered"] for s in mine), n_presses),
        "modulus_monotone": all(s["modulus_monotone"] is True for s in mine),
        "beta_monotone": all(s["beta_monotone"] for s in mine),
        "n_refused": sum(s["n_refused"] for s in mine),
    }  # fmt: skip


def _press_errors(rows: list[dict[str, Any]]) -> tuple[list[float], int, int]:
    """Over the foam presses of ``rows``: the relative errors of E (presses read), how many lie
    within twice their claimed σ of the true E, and how many presses there were."""
    errors: list[float] = []
    covered = n_presses = 0
    for row in rows:
        true = row.get("true_modulus_pa")
        if row["hardness_n"] is None or row.get("refused") or not true:
            continue
        moduli, stds = row.get("moduli_pa") or [], row.get("modulus_stds_pa") or []
        n_presses += len(moduli)
        for modulus, std in zip(moduli, stds, strict=True):
            if modulus is None:
                continue
            errors.append((modulus - true) / true)
            covered += std is not None and abs(modulus - true) <= 2.0 * std
    return errors, covered, n_presses


def _median_abs(values: list[float]) -> float | None:
    return float(np.median(np.abs(values))) if values else None


def fraction(part: int, whole: int) -> float | None:
    return part / whole if whole else None


def _mean(values: list[Any]) -> float | None:
    kept = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(kept)) if kept else None
