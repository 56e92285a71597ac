"""Studies on homogeneous simulated foams: β against hardness (the paper's Fig. 5a) and the fit
error against cluster size (its Fig. 5b). Each foam, a block over the whole workspace, is pressed
at a few fixed places; every protocol and cluster size reads the *same* presses.

The behaviour study presses blocks of elastic, viscoelastic, plastic and anisotropic foam with a
hold and an unloading branch and compares the behaviour class each press reads
(:func:`deformap.explore.poke_behaviour`) with the material's own (:func:`behaviour_presses`,
:func:`behaviour_summary`).
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
from deformap.explore import ExplorationConfig, Mapper, PokeRecord, measure_press, poke_behaviour
from deformap.msm import ShapeMatchingConfig
from deformap.world import (
    Block,
    Orthotropic,
    Plastic,
    Scenario,
    SimulatedWorld,
    Viscoelastic,
    WorldConfig,
)

__all__ = [
    "BEHAVIOUR_READS", "BEHAVIOUR_TRUTHS", "DEFAULT_HARDNESSES", "DEFAULT_POSITIONS",
    "DEFAULT_PROTOCOL", "FULL_BEHAVIOUR_MATERIALS", "PAPER_PROTOCOL", "PROTOCOLS",
    "QUICK_BEHAVIOUR_MATERIALS", "STUDY_PROTOCOLS", "BehaviourMaterial", "FoamPresses",
    "behaviour_presses", "behaviour_summary", "block_scenario", "cluster_size_study",
    "collect_presses", "hardness_study", "hardness_summary", "material_scenario",
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
        "modulus_within_2sigma": _fraction(covered, n_presses),
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
        "modulus_within_2sigma": _fraction(sum(s["_covered"] for s in mine), n_presses),
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


def _fraction(part: int, whole: int) -> float | None:
    return part / whole if whole else None


def _mean(values: list[Any]) -> float | None:
    kept = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(kept)) if kept else None


# --- what a press reveals beyond its stiffness, against the world's truth ---------------------

BEHAVIOUR_TRUTHS: tuple[str, ...] = ("elastic", "viscoelastic", "plastic")
"""The behaviour classes a simulated material has (an anisotropic foam is elastic)."""

BEHAVIOUR_READS: tuple[str, ...] = ("elastic", "viscoelastic", "plastic", "unknown")
"""What a press can read (:class:`deformap.stiffness.PressBehaviour`'s classes)."""


@dataclass(frozen=True)
class BehaviourMaterial:
    """One material of the behaviour study: a foam of ``hardness_n`` newtons (its instantaneous
    modulus when viscoelastic), elastic unless it relaxes, yields or is anisotropic."""

    name: str
    hardness_n: float
    viscoelastic: Viscoelastic | None = None
    plastic: Plastic | None = None
    anisotropy: Orthotropic | None = None

    @property
    def truth(self) -> str:
        """The behaviour class the press should read."""
        if self.viscoelastic is not None and self.viscoelastic.relaxed_ratio < 1.0:
            return "viscoelastic"
        return "plastic" if self.plastic is not None else "elastic"

    @property
    def kind(self) -> str:
        """Its truth class, or ``"anisotropic"`` for an anisotropic foam."""
        return "anisotropic" if self.anisotropy is not None else self.truth


def _elastic(hardness_n: float) -> BehaviourMaterial:
    return BehaviourMaterial(f"elastic {hardness_n:g} N", hardness_n)


def _memory(relaxed_ratio: float, tau_s: float) -> BehaviourMaterial:
    return BehaviourMaterial(f"viscoelastic g∞ {relaxed_ratio:g} τ {tau_s:g} s", 60.0,
                             viscoelastic=Viscoelastic(relaxed_ratio=relaxed_ratio,
                                                       times_s=(tau_s,)))


def _clay(yield_pa: float) -> BehaviourMaterial:
    return BehaviourMaterial(f"plastic yield {yield_pa:g} Pa", 60.0,
                             plastic=Plastic(yield_stress_pa=yield_pa, hardening_pa=2000.0))


def _ribbed(ratio: float) -> BehaviourMaterial:
    return BehaviourMaterial(f"anisotropic {ratio:g}", 60.0,
                             anisotropy=Orthotropic(ratio=ratio, axis_deg=30.0))


QUICK_BEHAVIOUR_MATERIALS: tuple[BehaviourMaterial, ...] = (
    _elastic(60.0), _memory(0.5, 1.0), _clay(1000.0), _ribbed(3.0))
"""The quick study's materials: one of each kind, 60 N."""

FULL_BEHAVIOUR_MATERIALS: tuple[BehaviourMaterial, ...] = (
    *(_elastic(h) for h in (30.0, 60.0, 110.0, 150.0, 250.0)),
    *(_memory(g, tau) for g in (0.5, 0.8) for tau in (0.5, 2.0)),
    *(_clay(y) for y in (1000.0, 3000.0)),
    *(_ribbed(r) for r in (1.5, 3.0)))
"""The full study's materials: elastic foams 30–250 N; viscoelastic at relaxed/instantaneous
ratios 0.5 and 0.8 and relaxation times 0.5 and 2 s; plastic at yield stresses 1 and 3 kPa
(hardening 2 kPa); anisotropic at ratios 1.5 and 3 (stiff axis 30° from x); all but the
elastic ones 60 N."""


def material_scenario(material: BehaviourMaterial, workspace: Workspace,
                      thickness_m: float = 0.05) -> Scenario:
    """One block of ``material`` over ``workspace``, ``thickness_m`` thick."""
    (x0, y0), (x1, y1) = workspace.lower, workspace.upper
    polygon = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    block = Block(name=material.name, polygon=polygon, hardness_n=material.hardness_n,
                  thickness_m=thickness_m, viscoelastic=material.viscoelastic,
                  plastic=material.plastic, anisotropy=material.anisotropy)
    return Scenario(name=f"behaviour-{material.name}", blocks=(block,), workspace=workspace)


def _truth_at(world: SimulatedWorld, xy: tuple[float, float]) -> dict[str, Any]:
    """The world's own material parameters under a press (``None`` where it has none)."""
    xs, ys = np.array([xy[0]]), np.array([xy[1]])

    def value(grid: Any) -> float | None:
        v = float(np.asarray(grid)[0, 0])
        return v if math.isfinite(v) else None

    return {"relaxation_fraction": value(world.ground_truth_relaxation_fraction(xs, ys)),
            "relaxation_time_s": value(world.ground_truth_relaxation_time(xs, ys)),
            "anisotropy_ratio": value(world.ground_truth_anisotropy_ratio(xs, ys)),
            "anisotropy_axis_deg": value(world.ground_truth_anisotropy_axis(xs, ys)),
            "yield_stress_pa": value(world.ground_truth_yield_stress(xs, ys)),
            "modulus_pa": value(world.ground_truth_modulus(xs, ys))}


def behaviour_presses(material: BehaviourMaterial, *, world_config: WorldConfig,
                      force_n: float, rng: np.random.Generator, thickness_m: float = 0.05,
                      positions: Sequence[tuple[float, float]] = DEFAULT_POSITIONS
                      ) -> list[dict[str, Any]]:
    """Press one block of ``material`` at ``positions`` with ``force_n`` under ``world_config``
    (its hold and unloading) and read each press's behaviour
    (:func:`deformap.explore.poke_behaviour`): one row a press with the material and its
    ``kind`` (:attr:`BehaviourMaterial.kind`), the truth class
    ``truth``, the class read ``read``, its ``evidence``, every quantity of
    :class:`~deformap.stiffness.PressBehaviour` under ``quantities`` and the world's own
    parameters under ``true``."""
    world = SimulatedWorld(material_scenario(material, Workspace(), thickness_m),
                           config=world_config, rng=rng)
    rows = []
    for xy in positions:
        read = poke_behaviour(world.press(np.asarray(xy, dtype=float), force_n))
        world.release()
        quantities = {k: v for k, v in read.to_dict().items() if k not in ("behaviour", "evidence")}
        rows.append({"material": material.name, "kind": material.kind,
                     "hardness_n": material.hardness_n,
                     "xy_m": [float(xy[0]), float(xy[1])], "truth": material.truth,
                     "read": read.behaviour, "evidence": read.evidence,
                     "quantities": quantities, "true": _truth_at(world, xy)})
    return rows


def behaviour_summary(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """What a behaviour study's press rows say: ``confusion`` (``{truth: {read: count}}`` over
    :data:`BEHAVIOUR_TRUTHS` × :data:`BEHAVIOUR_READS`), ``n_presses``, ``right`` (the fraction
    read as their truth), ``elastic_flagged`` (of the elastic presses, the fraction read
    viscoelastic or plastic), ``unknown`` (the fraction read unknown), and ``by_condition`` and
    ``by_material`` (the same counts per ``camera``/``thickness_m`` and per material)."""
    def counts(group: Sequence[dict[str, Any]]) -> dict[str, Any]:
        confusion = {t: dict.fromkeys(BEHAVIOUR_READS, 0) for t in BEHAVIOUR_TRUTHS}
        for row in group:
            confusion[row["truth"]][row["read"]] += 1
        elastic = sum(confusion["elastic"].values())
        n = len(group)
        return {"n_presses": n, "confusion": confusion,
                "right": _fraction(sum(confusion[t][t] for t in BEHAVIOUR_TRUTHS), n),
                "elastic_flagged": _fraction(confusion["elastic"]["viscoelastic"]
                                             + confusion["elastic"]["plastic"], elastic),
                "unknown": _fraction(sum(c["unknown"] for c in confusion.values()), n)}

    by_condition: dict[tuple[Any, Any], list[dict[str, Any]]] = {}
    by_material: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        by_condition.setdefault((row.get("camera"), row.get("thickness_m")), []).append(row)
        by_material.setdefault(row["material"], []).append(row)
    return {**counts(rows),
            "by_condition": [{"camera": c, "thickness_m": h, **counts(g)}
                             for (c, h), g in by_condition.items()],
            "by_material": [{"material": m, "truth": g[0]["truth"], **counts(g)}
                            for m, g in by_material.items()]}
