"""The behaviour study: blocks of elastic, viscoelastic, plastic and anisotropic foam pressed
with a hold and an unloading branch, the behaviour class each press reads
(:func:`deformap.explore.poke_behaviour`) against the world's own (:func:`behaviour_presses`,
:func:`behaviour_summary`).

The truth of a press is what the world's material did under that press: viscoelastic for a block
that relaxes; plastic for a block that yields when the dent the press leaves exceeds the
record's resolvable floor (:func:`deformap.stiffness.record_dent_floor`), else elastic (the press
did not yield beyond it, and behaved elastically); elastic otherwise (an anisotropic foam too).
The dent a press leaves is how far below the top the tip's sphere, lowered at the press point,
rests on the surface the world keeps after release (``tip_rest_dent_m``; the deepest point of
that surface is ``kept_dent_m``). The quantities read are set against the world's: the hold's
creep fraction against that of the world's noise-free record of the same press
(``1 − δ(hold's start)/δ(hold's end)``), the time constant against the standard linear solid's
creep time under a held force ``τ/g∞`` (one relaxation time), the residual dent against the
dent the press leaves (elastic and plastic blocks: a viscoelastic dent recovers in time)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import LinearNDInterpolator

from deformap.environment import Workspace
from deformap.eval._studies import DEFAULT_POSITIONS, fraction
from deformap.explore import poke_behaviour
from deformap.stiffness import record_dent_floor
from deformap.world import (
    Block,
    Orthotropic,
    Plastic,
    Scenario,
    SimulatedWorld,
    Viscoelastic,
    WorldConfig,
)

__all__ = ["BEHAVIOUR_READS", "BEHAVIOUR_TOLERANCES", "BEHAVIOUR_TRUTHS",
           "FULL_BEHAVIOUR_MATERIALS", "QUICK_BEHAVIOUR_MATERIALS", "BehaviourMaterial",
           "behaviour_presses", "behaviour_summary", "material_scenario"]


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


def _tip_rest_dent(world: SimulatedWorld, xy: tuple[float, float], u: Any, radius_m: float,
                   thickness_m: float) -> float:
    """How far below the block's top the tip's sphere (``radius_m``), lowered at ``xy`` onto the
    top surface displaced by ``u`` ``(n_nodes, 3)``, rests with no force: the lowest sphere that
    no point of the surface (linear between its nodes, read every 0.25 mm) enters."""
    nodes = world.foam.rest_nodes
    top = nodes[:, 2] >= thickness_m - 1e-9
    near = top & (np.hypot(nodes[:, 0] - xy[0], nodes[:, 1] - xy[1]) <= 2.0 * radius_m)
    surface = LinearNDInterpolator((nodes + u)[near, :2], (nodes + u)[near, 2])
    g = np.arange(-radius_m, radius_m + 1e-9, 2.5e-4)
    dx, dy = (a.ravel() for a in np.meshgrid(g, g))
    r2 = dx**2 + dy**2
    inside = r2 < radius_m**2
    z = surface(xy[0] + dx[inside], xy[1] + dy[inside])
    bottom = np.nanmax(z - radius_m + np.sqrt(radius_m**2 - r2[inside]))
    return max(0.0, thickness_m - float(bottom))


def behaviour_presses(material: BehaviourMaterial, *, world_config: WorldConfig,
                      force_n: float, rng: np.random.Generator, thickness_m: float = 0.05,
                      positions: Sequence[tuple[float, float]] = DEFAULT_POSITIONS
                      ) -> list[dict[str, Any]]:
    """Press one block of ``material`` at ``positions`` with ``force_n`` under ``world_config``
    (its hold and unloading) and read each press's behaviour
    (:func:`deformap.explore.poke_behaviour`): one row a press with the material and its
    ``kind`` (:attr:`BehaviourMaterial.kind`), the press's truth class ``truth`` (module
    docstring), the class read ``read``, its ``evidence``, every quantity of
    :class:`~deformap.stiffness.PressBehaviour` under ``quantities`` and the world's own
    parameters under ``true`` (with ``creep_fraction``, ``creep_time_s`` and ``kept_dent_m``)."""
    world = SimulatedWorld(material_scenario(material, Workspace(), thickness_m),
                           config=world_config, rng=rng)
    rows = []
    for xy in positions:
        obs = world.press(np.asarray(xy, dtype=float), force_n)
        read = poke_behaviour(obs)
        creep: float | None = 0.0  # the world's elastic and plastic blocks are rate-independent
        if material.viscoelastic is not None:  # its solved history is kept: no second solve
            exact = world.force_travel(obs.target_xy, force_n, exact=True)
            creep = None if exact is None or exact.hold is None else (
                1.0 - float(exact.travel_m[-1]) / float(exact.hold.travel_m[-1]))
        world.release()
        u = world.released_displacement(0.0)
        kept = max(0.0, -float(np.min(u[:, 2])))
        rest = _tip_rest_dent(world, xy, u, obs.contact.tip_radius_m, thickness_m) if kept else 0.0
        truth = material.truth
        if truth == "plastic" and (obs.force_travel is None
                                   or rest <= record_dent_floor(obs.force_travel)):
            truth = "elastic"  # it did not yield beyond what the record resolves
        quantities = {k: v for k, v in read.to_dict().items() if k not in ("behaviour", "evidence")}
        true = _truth_at(world, xy)
        visco = material.viscoelastic
        true.update(creep_fraction=creep, kept_dent_m=kept, tip_rest_dent_m=rest, creep_time_s=(
            None if visco is None or len(visco.times_s) != 1
            else float(visco.times_s[0]) / visco.relaxed_ratio))
        rows.append({"material": material.name, "kind": material.kind,
                     "hardness_n": material.hardness_n,
                     "xy_m": [float(xy[0]), float(xy[1])], "truth": truth,
                     "read": read.behaviour, "evidence": read.evidence,
                     "quantities": quantities, "true": true})
    return rows


#: The issue's tolerances on what a press reads: relaxation (creep) fraction, absolute; time
#: constant, relative; residual dent [m], absolute.
BEHAVIOUR_TOLERANCES: dict[str, float] = {"relaxation": 0.05, "tau": 0.20, "residual_dent": 3e-4}


def _errors(group: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Each quantity's error against the world's (module docstring) over the presses that read
    it: ``n``, ``median`` and ``largest`` absolute error, ``within`` its ``tolerance`` (the
    issue's, :data:`BEHAVIOUR_TOLERANCES`)."""
    pairs: dict[str, list[float]] = {k: [] for k in BEHAVIOUR_TOLERANCES}
    for row in group:
        q, true = row.get("quantities", {}), row.get("true", {})
        if q.get("relaxation") is not None and true.get("creep_fraction") is not None:
            pairs["relaxation"].append(q["relaxation"] - true["creep_fraction"])
        if q.get("tau_s") is not None and true.get("creep_time_s"):
            pairs["tau"].append(q["tau_s"] / true["creep_time_s"] - 1.0)
        # a viscoelastic dent recovers in time: no residual dent to set the reading against
        if (q.get("residual_dent_m") is not None and true.get("tip_rest_dent_m") is not None
                and row.get("kind") != "viscoelastic"):
            pairs["residual_dent"].append(q["residual_dent_m"] - true["tip_rest_dent_m"])
    out: dict[str, Any] = {}
    for name, errors in pairs.items():
        err = np.abs(np.array(errors))
        out[name] = {"n": int(err.size), "tolerance": BEHAVIOUR_TOLERANCES[name],
                     "median": float(np.median(err)) if err.size else None,
                     "largest": float(np.max(err)) if err.size else None,
                     "within": int(np.sum(err <= BEHAVIOUR_TOLERANCES[name]))}
    return out


def behaviour_summary(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """What a behaviour study's press rows say: ``confusion`` (``{truth: {read: count}}`` over
    :data:`BEHAVIOUR_TRUTHS` × :data:`BEHAVIOUR_READS`), ``n_presses``, ``right`` (the fraction
    read as their truth), ``elastic_flagged`` (of the elastic presses, the fraction read
    viscoelastic or plastic), ``unknown`` (the fraction read unknown), ``errors`` (each
    quantity's error against the world's, :data:`BEHAVIOUR_TOLERANCES`), and ``by_condition`` and
    ``by_material`` (the same counts per ``camera``/``thickness_m`` and per material, the latter
    with its ``errors``)."""
    def counts(group: Sequence[dict[str, Any]]) -> dict[str, Any]:
        confusion = {t: dict.fromkeys(BEHAVIOUR_READS, 0) for t in BEHAVIOUR_TRUTHS}
        for row in group:
            confusion[row["truth"]][row["read"]] += 1
        elastic = sum(confusion["elastic"].values())
        n = len(group)
        return {"n_presses": n, "confusion": confusion,
                "right": fraction(sum(confusion[t][t] for t in BEHAVIOUR_TRUTHS), n),
                "elastic_flagged": fraction(confusion["elastic"]["viscoelastic"]
                                             + confusion["elastic"]["plastic"], elastic),
                "unknown": fraction(sum(c["unknown"] for c in confusion.values()), n)}

    by_condition: dict[tuple[Any, Any], list[dict[str, Any]]] = {}
    by_material: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        by_condition.setdefault((row.get("camera"), row.get("thickness_m")), []).append(row)
        by_material.setdefault(row["material"], []).append(row)
    return {**counts(rows), "errors": _errors(rows),
            "by_condition": [{"camera": c, "thickness_m": h, **counts(g)}
                             for (c, h), g in by_condition.items()],
            "by_material": [{"material": m, "truth": g[0]["truth"], **counts(g),
                             "errors": _errors(g)} for m, g in by_material.items()]}
