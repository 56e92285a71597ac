"""Typed records of an exploration: what one poke gave, and why a place was chosen.

A record becomes plain data only at the journal and report boundary (:meth:`PokeRecord.to_dict`)
and comes back through :meth:`PokeRecord.from_dict`, which refuses a line that is not a poke.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import points_in_hull
from deformap.environment import ForceTravel, PressObservation, TactileContact
from deformap.errors import FileFormatError, InvalidArgumentError
from deformap.explore._planning import PokePlan
from deformap.msm import BetaEstimate
from deformap.stiffness import (
    ANISOTROPY_WINDOW_RADII,
    BEHAVIOURS,
    LAYER_MODEL,
    ContactModelFit,
    PressBehaviour,
    StiffnessEstimate,
    dent_anisotropy,
    press_behaviour,
    released_dent,
)

__all__ = ["PURPOSES", "ContactRecord", "Dent", "PokeRecord", "PokeResult", "PokeTimings", "Purpose",
           "Target", "poke_behaviour"]

#: Margin [m] around the probe's hull and tip ball within which cloud points are the probe's.
_PROBE_MARGIN_M = 0.003

#: Why a place was poked: the first poke, the strategy's (until the variance is under ``T_h``), a
#: look the appearance prior asks to test, or a boundary poke after it.
Purpose = Literal["first", "variance", "boundary", "appearance"]
PURPOSES: tuple[str, ...] = get_args(Purpose)


def _floats(value: Any, n: int | None, where: str) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or (n is not None and len(value) != n):
        size = "a list" if n is None else f"a list of {n} numbers"
        raise FileFormatError(f"`{where}` must be {size}; got {value!r}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise FileFormatError(f"`{where}` must hold finite numbers; got {v!r}")
        out.append(float(v))
    return tuple(out)


def _number(data: Mapping[str, Any], key: str, where: str, *, kind: type = float,
            optional: bool = False) -> Any:
    value = data.get(key)
    if value is None and optional:
        return None
    if key not in data:
        raise FileFormatError(f"`{where}` has no `{key}`")
    if kind is bool:
        if not isinstance(value, bool):
            raise FileFormatError(f"`{where}.{key}` must be true or false; got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FileFormatError(f"`{where}.{key}` must be a number; got {value!r}")
    if kind is int:
        if float(value) != int(value):
            raise FileFormatError(f"`{where}.{key}` must be an integer; got {value!r}")
        return int(value)
    if not math.isfinite(value):
        raise FileFormatError(f"`{where}.{key}` must be finite; got {value!r}")
    return float(value)


def _text(data: Mapping[str, Any], key: str, where: str) -> str | None:
    value = data.get(key)
    if value is not None and not isinstance(value, str):
        raise FileFormatError(f"`{where}.{key}` must be text; got {value!r}")
    return value


def _mapping(data: Any, where: str, cls: type | None = None, *, also: frozenset[str] = frozenset()
             ) -> Mapping[str, Any]:
    """``data`` if it is a mapping holding no key but ``cls``'s fields (and ``also``)."""
    if not isinstance(data, Mapping):
        raise FileFormatError(f"`{where}` must be a mapping; got {data!r}")
    unknown = [] if cls is None else sorted(set(data) - {f.name for f in fields(cls)} - also)
    if unknown:
        raise FileFormatError(f"`{where}` has unknown key(s) {unknown}")
    return data


def _stiffness_from_dict(data: Any, where: str) -> StiffnessEstimate | None:
    if data is None:
        return None
    data = _mapping(data, where, StiffnessEstimate)
    names = {f.name for f in fields(StiffnessEstimate)}
    numbers = {n: _number(data, n, where, optional=True)
               for n in names - {"rigid", "n_samples", "model", "depth_m", "model_fits"}}  # fmt: skip
    model = _text(data, "model", where)
    listed = data.get("model_fits") or []
    if not isinstance(listed, list):
        raise FileFormatError(f"`{where}.model_fits` must be a list; got {listed!r}")
    try:
        fits = []
        for i, item in enumerate(listed):
            at = f"{where}.model_fits[{i}]"
            item = _mapping(item, at, ContactModelFit)
            fits.append(ContactModelFit(name=_text(item, "name", at) or "", **{
                n: _number(item, n, at) for n in
                ("modulus_pa", "modulus_std_pa", "reduced_chi2", "p_value", "weight")}))
        return StiffnessEstimate(
            **numbers, depth_m=_number(data, "depth_m", where),
            rigid=_number(data, "rigid", where, kind=bool),
            n_samples=_number(data, "n_samples", where, kind=int),
            model=LAYER_MODEL if model is None else model, model_fits=tuple(fits))
    except InvalidArgumentError as exc:
        raise FileFormatError(f"`{where}`: {exc}") from None


@dataclass(frozen=True, kw_only=True)
class ContactRecord:
    """The tactile contact of a poke as plain numbers (world frame, SI units)."""

    tip_center: tuple[float, float, float]
    force: tuple[float, float, float]
    tip_radius_m: float

    @classmethod
    def of(cls, contact: TactileContact) -> ContactRecord:
        c, f = contact.tip_center, contact.force
        return cls(tip_center=(float(c[0]), float(c[1]), float(c[2])),
                   force=(float(f[0]), float(f[1]), float(f[2])),
                   tip_radius_m=float(contact.tip_radius_m))  # fmt: skip

    def to_dict(self) -> dict[str, Any]:
        return {"tip_center": list(self.tip_center), "force": list(self.force),
                "tip_radius_m": self.tip_radius_m}  # fmt: skip

    @classmethod
    def from_dict(cls, data: Any, where: str) -> ContactRecord:
        data = _mapping(data, where)
        center = _floats(data.get("tip_center"), 3, f"{where}.tip_center")
        force = _floats(data.get("force"), 3, f"{where}.force")
        return cls(tip_center=(center[0], center[1], center[2]),
                   force=(force[0], force[1], force[2]),
                   tip_radius_m=_number(data, "tip_radius_m", where))  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class PokeTimings:
    """Seconds spent on one poke, by stage (``None``: not passed through): crop and filter, the
    dent's reconstruction, β, the force–travel fit, the field update, choosing the place, and the
    world, robot or recording."""

    filter_s: float
    touch_gp_s: float
    beta_s: float
    stiffness_s: float | None = None
    field_s: float | None = None
    target_s: float | None = None
    environment_s: float | None = None

    @property
    def compute_s(self) -> float:
        """Everything but the environment's own time."""
        return sum(getattr(self, f.name) or 0.0 for f in fields(self)
                   if f.name != "environment_s")  # fmt: skip

    def to_dict(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}  # fmt: skip

    @classmethod
    def from_dict(cls, data: Any, where: str) -> PokeTimings:
        data = _mapping(data, where, cls)
        names = [f.name for f in fields(cls)]
        required = ("filter_s", "touch_gp_s", "beta_s")
        return cls(**{n: _number(data, n, where, optional=n not in required) for n in names})


@dataclass(frozen=True, kw_only=True)
class PokeRecord:
    """What one poke gave: where, the contact, β with its uncertainty and E(β), and timings.

    ``index`` from 0 in its run; ``target_xy``, ``contact_xy`` [m] where it was aimed and touched;
    ``beta``, ``beta_std`` β̂ and its σ (before the field's floor); ``betas``, ``errors`` the
    compared β and E(β) [m]; ``iterations``, ``residual``, ``converged`` the solver's worst.
    Optional (``None``: not applicable): the record's ``stiffness``, the ``layer_thickness_m`` it
    was read with or ``stiffness_error``; the ``indentation_m`` of the tactile points and whether
    it came from the record (``depth_anchored``); ``dent_visible``; ``purpose``;
    ``planned_after``; the stop cells' largest variance after this poke (``max_variance_after``);
    what the press reveals beyond its stiffness (``behaviour``, :func:`~deformap.stiffness.
    press_behaviour`: ``"unknown"`` with the reason for a record of the ramp alone).
    """

    index: int
    target_xy: tuple[float, float]
    contact_xy: tuple[float, float]
    contact: ContactRecord
    force_n: float
    beta: float
    beta_std: float
    betas: tuple[float, ...]
    errors: tuple[float, ...]
    iterations: int
    residual: float
    converged: bool
    n_roi_points: int
    camera_noise_m: float | None
    timings: PokeTimings
    stiffness: StiffnessEstimate | None = None
    layer_thickness_m: float | None = None
    stiffness_error: str | None = None
    indentation_m: float | None = None
    depth_anchored: bool | None = None
    dent_visible: bool | None = None
    purpose: Purpose | None = None
    planned_after: int | None = None
    max_variance_after: float | None = None
    behaviour: PressBehaviour | None = None

    @property
    def xy(self) -> NDArray[np.float64]:
        """``contact_xy`` as an array."""
        return np.asarray(self.contact_xy, dtype=float)

    def to_dict(self) -> dict[str, Any]:
        """Plain data for the journal and ``report.json`` (unset optional fields left out)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, (ContactRecord, PokeTimings)):
                value = value.to_dict()
            elif isinstance(value, StiffnessEstimate):
                value = {g.name: getattr(value, g.name) for g in fields(value)}
                value["model_fits"] = [dataclasses.asdict(m) for m in value["model_fits"]]
            elif isinstance(value, PressBehaviour):
                value = value.to_dict()
            if value is not None or f.name == "camera_noise_m":
                out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, data: Any, *, where: str = "poke") -> PokeRecord:
        """The record a journal line holds; :class:`FileFormatError` naming a field that is
        missing, of the wrong type or unknown."""
        data = _mapping(data, where, cls, also=frozenset({"kind"}))
        purpose = data.get("purpose")
        if purpose is not None and purpose not in PURPOSES:
            raise FileFormatError(f"`{where}.purpose` must be one of {list(PURPOSES)}; "
                                  f"got {purpose!r}")  # fmt: skip
        target = _floats(data.get("target_xy"), 2, f"{where}.target_xy")
        contact_xy = _floats(data.get("contact_xy"), 2, f"{where}.contact_xy")

        def num(key: str, kind: type = float, optional: bool = False) -> Any:
            return _number(data, key, where, kind=kind, optional=optional)

        return cls(
            index=num("index", int), target_xy=(target[0], target[1]),
            contact_xy=(contact_xy[0], contact_xy[1]),
            contact=ContactRecord.from_dict(data.get("contact"), f"{where}.contact"),
            force_n=num("force_n"), beta=num("beta"), beta_std=num("beta_std"),
            betas=_floats(data.get("betas"), None, f"{where}.betas"),
            errors=_floats(data.get("errors"), None, f"{where}.errors"),
            iterations=num("iterations", int), residual=num("residual"),
            converged=num("converged", bool), n_roi_points=num("n_roi_points", int),
            camera_noise_m=num("camera_noise_m", optional=True),
            timings=PokeTimings.from_dict(data.get("timings"), f"{where}.timings"),
            stiffness=_stiffness_from_dict(data.get("stiffness"), f"{where}.stiffness"),
            layer_thickness_m=num("layer_thickness_m", optional=True),
            stiffness_error=_text(data, "stiffness_error", where),
            indentation_m=num("indentation_m", optional=True),
            depth_anchored=num("depth_anchored", bool, True),
            dent_visible=num("dent_visible", bool, True), purpose=purpose,
            planned_after=num("planned_after", int, True),
            max_variance_after=num("max_variance_after", optional=True),
            behaviour=_behaviour_from_dict(data.get("behaviour"), f"{where}.behaviour"))


def poke_behaviour(obs: PressObservation, stiffness: StiffnessEstimate | None = None
                   ) -> PressBehaviour:
    """:func:`~deformap.stiffness.press_behaviour` of a press: its record and, when it has one,
    the dent its cloud after release keeps at the tip (:func:`~deformap.stiffness.released_dent`;
    why none could be had joins the evidence); the anisotropy its cloud during the press shows,
    the probe's own points (its hull and tip ball with 3 mm) left out; with ``stiffness`` (the
    record's estimate, not rigid) its modulus as the instantaneous one."""
    modulus = None
    if (stiffness is not None and not stiffness.rigid and stiffness.modulus_pa is not None
            and stiffness.modulus_pa > 0.0):
        modulus = (float(stiffness.modulus_pa), float(stiffness.modulus_std_pa or 0.0))
    contact = obs.contact
    pts = obs.cloud.points
    # the window the dent's shape is read in (the probe's points tested only there)
    near = (np.linalg.norm(pts[:, :2] - contact.tip_center[:2], axis=1)
            <= ANISOTROPY_WINDOW_RADII * contact.tip_radius_m)
    pts = pts[near]
    probe = points_in_hull(pts, obs.robot_points, tolerance_m=_PROBE_MARGIN_M)
    probe |= np.linalg.norm(pts - contact.tip_center, axis=1) < contact.tip_radius_m + _PROBE_MARGIN_M
    shape = dent_anisotropy(pts[~probe], contact.tip_center, contact.tip_radius_m)
    if obs.released is None:
        return press_behaviour(obs.force_travel, modulus=modulus, anisotropy=shape)
    dent = released_dent(obs.released.points, contact.tip_center, contact.tip_radius_m)
    if isinstance(dent, str):
        got = press_behaviour(obs.force_travel, modulus=modulus, anisotropy=shape)
        return dataclasses.replace(got, evidence=f"{got.evidence}; {dent}")
    return press_behaviour(obs.force_travel, released=dent, modulus=modulus, anisotropy=shape)


def _behaviour_from_dict(data: Any, where: str) -> PressBehaviour | None:
    """A poke's ``behaviour`` entry (absent in journals written before it existed)."""
    if data is None:
        return None
    data = _mapping(data, where, PressBehaviour)
    kind, mode = data.get("behaviour"), data.get("relaxation_mode")
    isotropy = data.get("isotropy")
    if isotropy not in (None, "isotropic", "anisotropic", "unknown"):
        raise FileFormatError(f"`{where}.isotropy` must be 'isotropic', 'anisotropic', 'unknown' "
                              f"or null; got {isotropy!r}")  # fmt: skip
    if kind not in BEHAVIOURS:
        raise FileFormatError(f"`{where}.behaviour` must be one of {list(BEHAVIOURS)}; "
                              f"got {kind!r}")  # fmt: skip
    if mode not in (None, "force", "travel"):
        raise FileFormatError(f"`{where}.relaxation_mode` must be 'force', 'travel' or null; "
                              f"got {mode!r}")  # fmt: skip
    evidence = _text(data, "evidence", where)
    if evidence is None:
        raise FileFormatError(f"`{where}` has no `evidence`")
    numbers = {f.name: _number(data, f.name, where, optional=True) for f in fields(PressBehaviour)
               if f.name not in ("behaviour", "evidence", "relaxation_mode", "isotropy")}
    return PressBehaviour(behaviour=kind, evidence=evidence, relaxation_mode=mode,
                          isotropy=isotropy, **numbers)


@dataclass(frozen=True, eq=False)
class Dent:
    """A poke's reconstructed dent for figures and recordings: the ROI grid ``roi_xs (nx,)``,
    ``roi_ys (ny,)``; heights ``rest_z``, ``deformed_z (ny, nx)`` before and while pressing;
    ``roi_points (m, 3)`` and ``tactile (k, 3)``, metres; the press's ``force_travel`` record and
    ``force_fit (2, m)``, travel [m] and force [N] of the fitted model (``None`` without)."""

    roi_xs: NDArray[np.float64]
    roi_ys: NDArray[np.float64]
    rest_z: NDArray[np.float64]
    deformed_z: NDArray[np.float64]
    roi_points: NDArray[np.float64]
    tactile: NDArray[np.float64]
    force_travel: ForceTravel | None = None
    force_fit: NDArray[np.float64] | None = None


@dataclass(frozen=True, eq=False)
class PokeResult:
    """One processed poke: its record, and (unless resumed from a journal) its dent and estimate."""

    record: PokeRecord
    dent: Dent | None = None
    estimate: BetaEstimate | None = None

    @property
    def xy(self) -> NDArray[np.float64]:
        """Where the tip touched, ``(2,)`` metres."""
        return self.record.xy


@dataclass(frozen=True, eq=False)
class Target:
    """The next place to poke, ``xy (2,)`` metres, why, and the plan it came from (or ``None``)."""

    xy: NDArray[np.float64]
    purpose: Purpose
    plan: PokePlan | None = None

    @property
    def planned_after(self) -> int | None:
        """How many more pokes a plan that reaches ``T_h`` foresees after this one."""
        if self.plan is None or not self.plan.reaches:
            return None
        return len(self.plan.targets) - 1
