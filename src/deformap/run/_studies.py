"""The studies on homogeneous simulated foams (the paper's Fig. 5), each into its own folder:
``hardness.json`` and ``.png`` (β against hardness per contact protocol),
``cluster-size.json`` and ``.png`` (fit error against cluster size), or ``behaviour.json`` and
``.png`` (the behaviour class each press reads against the material's, a confusion matrix). The
numbers come from :mod:`deformap.eval`; this module builds the worlds, writes the files and
reports progress.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from deformap._validation import SettingError, check_positive
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.eval import (
    DEFAULT_HARDNESSES,
    FULL_BEHAVIOUR_MATERIALS,
    PROTOCOLS,
    QUICK_BEHAVIOUR_MATERIALS,
    STUDY_PROTOCOLS,
    FoamPresses,
    behaviour_presses,
    behaviour_summary,
    block_scenario,
    cluster_size_study,
    collect_presses,
    hardness_study,
    hardness_summary,
    material_scenario,
)
from deformap.explore import ExplorationConfig
from deformap.run._folder import claim_run_folder, default_run_folder, write_json
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.world import (
    MIN_RECORD_FORCE_N,
    PHYSICS,
    Physics,
    WorldConfig,
    camera_preset,
    check_world_budget,
)

__all__ = [
    "BEHAVIOUR_FULL_THICKNESSES_M", "BEHAVIOUR_HOLD_S", "BEHAVIOUR_KINDS", "BEHAVIOUR_THICKNESS_M",
    "CLUSTER_SIZE_FOAMS",
    "FULL_CAMERAS", "FULL_ELEMENT_SIZE_M", "FULL_PHYSICS", "FULL_THICKNESSES_M", "StudyOutput",
    "run_behaviour_study", "run_cluster_size_study", "run_hardness_study",
]

CLUSTER_SIZE_FOAMS: tuple[float, ...] = (60.0, 110.0, 150.0)
"""Foams of the cluster-size study in newtons (the rigid board is added)."""

FULL_CAMERAS: tuple[str, ...] = ("primesense", "kinect-v1", "realsense-d435")
FULL_THICKNESSES_M: tuple[float, ...] = (0.03, 0.05, 0.10)
FULL_PHYSICS: tuple[str, ...] = PHYSICS
"""The matrix of ``study hardness --full``: camera presets × thicknesses (metres) × physics."""

FULL_ELEMENT_SIZE_M = 0.00375
"""The world's in-plane element size for ``--full``, metres: the stiffest press's contact patch
(5–6 mm radius) is smaller than the default 7.5 mm element, which would then press too stiff."""


@dataclass(frozen=True, kw_only=True)
class StudyOutput:
    """What a study wrote: ``study`` (the content of its JSON file), ``folder`` and ``files``."""

    study: dict[str, Any]
    folder: Path
    files: list[Path]


def _foams(foams: Sequence[float | None], *, seed: int, coarse: bool, hooks: RunHooks,
           camera: str | None = None, thickness_m: float = 0.05, force_n: float | None = None,
           physics: Physics = "linear-fem", element_size_m: float | None = None,
           ) -> list[FoamPresses]:
    world = _study_world(physics, coarse=coarse, element_size_m=element_size_m)
    if camera is not None:
        world = dataclasses.replace(world, camera=camera_preset(camera))
    explore = ExplorationConfig() if force_n is None else ExplorationConfig(force_n=force_n)
    return collect_presses(foams, world_config=world, config=explore, thickness_m=thickness_m,
                           rng=np.random.default_rng(seed), progress=hooks.step)  # fmt: skip


def _study_world(physics: Physics, *, coarse: bool, element_size_m: float | None) -> WorldConfig:
    """The default (or coarse) world, with ``element_size_m`` elements and top layers no thicker."""
    world = WorldConfig.coarse(physics=physics) if coarse else WorldConfig(physics=physics)
    if element_size_m is None:
        return world
    return dataclasses.replace(world, element_size_m=element_size_m,
                               top_layer_m=min(world.top_layer_m, element_size_m))


def _check_study_mesh(element_size_m: float, thicknesses_m: Sequence[float],
                     physics_names: Sequence[str]) -> None:
    """Refuse (:class:`SettingError` naming ``element_size_m``, the block and the limit) an element
    size whose study blocks would exceed :func:`deformap.world.check_world_budget`."""
    for physics_name in physics_names:
        world = _study_world(WorldConfig(physics=physics_name).physics,  # type: ignore[arg-type]
                             coarse=False, element_size_m=element_size_m)
        for thickness in thicknesses_m:
            try:
                check_world_budget(world, block_scenario(None, Workspace(), thickness))
            except SettingError as exc:
                if exc.field != "element_size_m":
                    raise
                raise SettingError("element_size_m", f"{element_size_m} m is too fine for the "
                                   f"{thickness:g} m study block ({physics_name}): "
                                   f"{exc.detail}") from None


def _write(folder: Path, stem: str, study: dict[str, Any], plot: Any) -> list[Path]:
    json_file = write_json(folder / f"{stem}.json", study)
    plot(study, path=folder / f"{stem}.png")  # written atomically by viz
    return [json_file, folder / f"{stem}.png"]


def run_hardness_study(
    out: Path | None = None, *, seed: int = 0, hardness: Sequence[float] | None = None,
    coarse: bool = False, camera: str | None = None, thickness_m: float = 0.05,
    force_n: float | None = None, physics: str = "linear-fem", full: bool = False,
    cameras: Sequence[str] | None = None, thicknesses_m: Sequence[float] | None = None,
    physics_names: Sequence[str] | None = None, protocols: Sequence[str] | None = None,
    element_size_m: float | None = None, hooks: RunHooks = NO_HOOKS,
) -> StudyOutput:  # fmt: skip
    """β (each contact protocol) and the force–travel reading (stiffness, Young's modulus)
    against hardness (:func:`deformap.eval.hardness_study`) into ``out`` (new or empty; default
    stem ``hardness``), on the foams ``hardness`` in newtons and the rigid board (default
    :data:`~deformap.eval.DEFAULT_HARDNESSES`), each world's noise from ``seed``.

    One condition is a ``camera`` preset (default primesense), a block ``thickness_m`` in metres
    and a world ``physics``; ``full`` presses every condition of :data:`FULL_CAMERAS` ×
    :data:`FULL_THICKNESSES_M` × :data:`FULL_PHYSICS`, or of ``cameras``, ``thicknesses_m`` and
    ``physics_names`` where given. ``force_n`` defaults to the exploration's, ``protocols`` to
    :data:`~deformap.eval.STUDY_PROTOCOLS`; ``element_size_m`` (not with ``coarse``) sets the
    world's in-plane FEM elements, :data:`FULL_ELEMENT_SIZE_M` by default with ``full``.

    The study's JSON has ``rows`` (each naming its ``camera``, ``thickness_m``, ``physics`` and
    ``force_n``) and :func:`deformap.eval.hardness_summary`'s ``summary`` and ``overall``; a
    single-condition study also its condition and monotone flags, a full one its ``matrix``.
    """
    from deformap.viz import plot_hardness_study  # matplotlib: only when a study is drawn

    if full:
        conditions = list(itertools.product(
            cameras or FULL_CAMERAS, thicknesses_m or FULL_THICKNESSES_M,
            physics_names or FULL_PHYSICS))  # fmt: skip
    else:
        conditions = [(camera or "primesense", thickness_m, physics)]
    chosen = _protocols(protocols)
    if element_size_m is not None and coarse:
        raise SettingError("element_size_m", f"sets the mesh, as the coarse world does: give one "
                           f"of them; got {element_size_m} and coarse")
    if full and not coarse and element_size_m is None:
        element_size_m = FULL_ELEMENT_SIZE_M
    foams = DEFAULT_HARDNESSES if not hardness else (*hardness, None)
    _check_press(foams, force_n)
    checked = _checked(conditions)
    if element_size_m is not None:  # nor a mesh it would refuse
        _check_study_mesh(element_size_m, sorted({c[1] for c in checked}),
                         list(dict.fromkeys(c[2] for c in checked)))
    folder = out or default_run_folder("hardness", "study", seed)
    with claim_run_folder(folder, what="study"):
        hooks.start(RunStart(kind="study", title=f"hardness study, seed {seed}", folder=folder,
                             total=len(foams) * len(checked)))  # fmt: skip
        by_condition: dict[tuple[str, float, str], list[dict[str, Any]]] = {}
        single: dict[str, Any] = {}
        # the element size the worlds have (the same under every physics)
        mesh_m = _study_world("linear-fem", coarse=coarse, element_size_m=element_size_m
                              ).element_size_m
        # thickness first: the FEM's factorisation depends on the block's mesh only (one per
        # thickness, shared by the cameras and the two FEM physics, deformap.world._fem); the rows
        # are written in the matrix's own order below, whatever order they were pressed in
        for name, thickness, physics_name in sorted(checked, key=lambda c: c[1]):
            hooks.stage(f"pressing the foams: {name}, {thickness:g} m, {physics_name}")
            presses = _foams(foams, seed=seed, coarse=coarse, hooks=hooks, camera=name,
                             thickness_m=thickness, force_n=force_n, physics=physics_name,
                             element_size_m=element_size_m)  # fmt: skip
            hooks.stage(f"estimating β per protocol: {name}, {thickness:g} m, {physics_name}")
            pressed = [f.presses[0].force_n for f in presses if f.presses]
            condition = {"camera": name, "thickness_m": thickness,
                         "force_n": pressed[0] if pressed else _force(force_n),
                         "physics": physics_name}  # fmt: skip
            single = {**condition, "element_size_m": mesh_m,
                      **hardness_study(presses, protocols=chosen)}
            by_condition[(name, thickness, physics_name)] = [{**row, **condition}
                                                             for row in single["rows"]]
        rows = [row for condition in checked for row in by_condition[condition]]
        study = {**(single if not full else {"matrix": {
            "cameras": list(dict.fromkeys(c[0] for c in checked)),
            "thicknesses_m": sorted({c[1] for c in checked}),
            "physics": list(dict.fromkeys(c[2] for c in checked)),
            "force_n": _force(force_n), "seed": seed, "coarse": coarse,
            "element_size_m": mesh_m}}),
            "rows": rows, **hardness_summary(rows)}  # fmt: skip
        return StudyOutput(study=study, folder=folder,
                           files=_write(folder, "hardness", study, plot_hardness_study))  # fmt: skip


def _checked(conditions: Sequence[tuple[str, float, str]]) -> list[tuple[str, float, Physics]]:
    """The conditions checked before any folder or world (names, thickness, the block), each
    once."""
    checked = []
    for name, thickness, physics_name in conditions:
        camera_preset(name)
        check_positive("thickness_m", thickness)
        checked.append((name, float(thickness),
                        WorldConfig(physics=physics_name).physics))  # type: ignore[arg-type]
    checked = list(dict.fromkeys(checked))
    for _, thickness, _ in checked:
        block_scenario(None, Workspace(), thickness)
    return checked


def _check_press(foams: Sequence[float | None], force_n: float | None) -> None:
    """Each foam a block the world can build, a force that gives a force–travel record."""
    for value in foams:
        if value is not None:
            block_scenario(value, Workspace())
    if force_n is not None:
        force = check_positive("force_n", force_n)
        if not force >= MIN_RECORD_FORCE_N:
            raise InvalidArgumentError(f"`force_n` must be at least {MIN_RECORD_FORCE_N:g} N, a "
                                       f"press the world gives a force–travel record of; got "
                                       f"{force:g}")


def _protocols(names: Sequence[str] | None) -> dict[str, dict[str, Any]]:
    """The protocols by name, checked before any world is built."""
    names = list(STUDY_PROTOCOLS if names is None else names)
    unknown = [n for n in names if n not in PROTOCOLS]
    if not names or unknown:
        raise InvalidArgumentError(
            f"protocols: expected one or more of {', '.join(PROTOCOLS)}, got "
            f"{', '.join(map(repr, unknown)) if unknown else 'none'}")
    return {name: PROTOCOLS[name] for name in dict.fromkeys(names)}


def _force(force_n: float | None) -> float:
    return ExplorationConfig().force_n if force_n is None else float(force_n)


def run_cluster_size_study(out: Path | None = None, *, seed: int = 0, coarse: bool = False,
                           hooks: RunHooks = NO_HOOKS) -> StudyOutput:
    """Fit error and β against cluster size 2×2 … 6×6 (:func:`deformap.eval.cluster_size_study`)
    on the foams :data:`CLUSTER_SIZE_FOAMS` and the rigid board.

    Parameters are those of :func:`run_hardness_study` (default stem ``cluster-size``).
    """
    from deformap.viz import plot_cluster_size_study  # matplotlib: only when a study is drawn

    folder = out or default_run_folder("cluster-size", "study", seed)
    with claim_run_folder(folder, what="study"):
        foams = (*CLUSTER_SIZE_FOAMS, None)
        hooks.start(RunStart(kind="study", title=f"cluster-size study, seed {seed}", folder=folder,
                             total=len(foams)))  # fmt: skip
        hooks.stage("pressing the foams")
        presses = _foams(foams, seed=seed, coarse=coarse, hooks=hooks)
        hooks.stage("estimating β per cluster size")
        study = cluster_size_study(presses)
        files = _write(folder, "cluster-size", study, plot_cluster_size_study)
        return StudyOutput(study=study, folder=folder, files=files)


BEHAVIOUR_HOLD_S = 3.0 * max(max(m.viscoelastic.times_s) / m.viscoelastic.relaxed_ratio
                             for m in FULL_BEHAVIOUR_MATERIALS if m.viscoelastic is not None)
"""How long each press of the behaviour study holds its force, seconds: three creep times of the
slowest memory foam of :data:`~deformap.eval.FULL_BEHAVIOUR_MATERIALS` (a standard linear solid
creeps under a held force with ``τ / g∞``), so that its time constant is read, not only its
creep."""

BEHAVIOUR_THICKNESS_M = 0.03
"""The quick behaviour study's foam thickness, metres (the thinner of
:data:`BEHAVIOUR_FULL_THICKNESSES_M`: the quicker FEM)."""

BEHAVIOUR_FULL_THICKNESSES_M: tuple[float, ...] = (0.03, 0.10)
"""The thicknesses of ``study behaviour --full``, metres."""

BEHAVIOUR_KINDS: tuple[str, ...] = ("elastic", "viscoelastic", "plastic", "anisotropic")
"""The kinds of material a behaviour study can be limited to."""


def run_behaviour_study(
    out: Path | None = None, *, seed: int = 0, full: bool = False,
    cameras: Sequence[str] | None = None, thicknesses_m: Sequence[float] | None = None,
    kinds: Sequence[str] | None = None, force_n: float | None = None, coarse: bool = False,
    hooks: RunHooks = NO_HOOKS,
) -> StudyOutput:  # fmt: skip
    """The behaviour class each press reads against its material's
    (:func:`deformap.eval.behaviour_presses`, :func:`~deformap.eval.behaviour_summary`) into
    ``out`` (new or empty; default stem ``behaviour``): ``behaviour.json`` and the confusion
    matrix ``behaviour.png``.

    Every material (:data:`~deformap.eval.QUICK_BEHAVIOUR_MATERIALS`, or with ``full``
    :data:`~deformap.eval.FULL_BEHAVIOUR_MATERIALS`; only those of ``kinds``, of
    :data:`BEHAVIOUR_KINDS`, where given) is a block over the workspace pressed at three places,
    each press held :data:`BEHAVIOUR_HOLD_S` and unloaded, under every camera preset ``cameras``
    (default primesense; with ``full`` every preset) and thickness ``thicknesses_m`` (default
    :data:`BEHAVIOUR_THICKNESS_M`; with ``full`` :data:`BEHAVIOUR_FULL_THICKNESSES_M`), each
    world's noise from ``seed``. ``force_n`` defaults to the exploration's.

    The JSON has ``matrix`` (the conditions, materials, hold and force), ``rows`` (one a press:
    ``camera``, ``thickness_m``, ``material``, ``truth``, ``read``, ``evidence``, ``quantities``
    and the world's ``true`` parameters) and the summary's ``confusion``, ``right``,
    ``elastic_flagged``, ``unknown``, ``by_condition`` and ``by_material``.
    """
    from deformap.viz import plot_behaviour_study  # matplotlib: only when a study is drawn

    chosen_cameras = list(cameras or (FULL_CAMERAS if full else ("primesense",)))
    chosen_thicknesses = [float(h) for h in (
        thicknesses_m or (BEHAVIOUR_FULL_THICKNESSES_M if full else (BEHAVIOUR_THICKNESS_M,)))]
    unknown = [k for k in (kinds or ()) if k not in BEHAVIOUR_KINDS]
    if unknown or (kinds is not None and not kinds):
        raise InvalidArgumentError(
            f"kinds: expected one or more of {', '.join(BEHAVIOUR_KINDS)}, got "
            f"{', '.join(map(repr, unknown)) if unknown else 'none'}")
    materials = [m for m in (FULL_BEHAVIOUR_MATERIALS if full else QUICK_BEHAVIOUR_MATERIALS)
                 if kinds is None or m.kind in kinds]
    checked = _checked([(c, h, "linear-fem") for c in chosen_cameras for h in chosen_thicknesses])
    for _, thickness, _ in checked:
        for material in materials:
            material_scenario(material, Workspace(), thickness)
    _check_press((), force_n)
    force = _force(force_n)
    folder = out or default_run_folder("behaviour", "study", seed)
    with claim_run_folder(folder, what="study"):
        hooks.start(RunStart(kind="study", title=f"behaviour study, seed {seed}", folder=folder,
                             total=len(materials) * len(checked)))  # fmt: skip
        streams = dict(zip(checked, np.random.default_rng(seed).spawn(len(checked)), strict=True))
        by_condition: dict[tuple[str, float, str], list[dict[str, Any]]] = {}
        # thickness first: the FEM's factorisation depends on the block's mesh only, shared by
        # the cameras (deformap.world._fem); the rows are written in the matrix's own order
        for condition in sorted(checked, key=lambda c: c[1]):
            name, thickness, _ = condition
            hooks.stage(f"pressing the materials: {name}, {thickness:g} m")
            world = _study_world("linear-fem", coarse=coarse, element_size_m=None)
            world = dataclasses.replace(world, camera=camera_preset(name),
                                        hold_s=BEHAVIOUR_HOLD_S, unload=True)
            rows = []
            for material, rng in zip(materials, streams[condition].spawn(len(materials)),
                                     strict=True):
                rows += [{"camera": name, "thickness_m": thickness, **row}
                         for row in behaviour_presses(material, world_config=world,
                                                      force_n=force, rng=rng,
                                                      thickness_m=thickness)]
                hooks.step(f"pressed {material.name}")
            by_condition[condition] = rows
        rows = [row for condition in checked for row in by_condition[condition]]
        study = {"matrix": {"cameras": list(dict.fromkeys(c[0] for c in checked)),
                            "thicknesses_m": sorted({c[1] for c in checked}),
                            "materials": [{"name": m.name, "truth": m.truth, "kind": m.kind}
                                          for m in materials],
                            "hold_s": BEHAVIOUR_HOLD_S, "force_n": force, "seed": seed,
                            "coarse": coarse},
                 "rows": rows, **behaviour_summary(rows)}  # fmt: skip
        return StudyOutput(study=study, folder=folder,
                           files=_write(folder, "behaviour", study, plot_behaviour_study))
