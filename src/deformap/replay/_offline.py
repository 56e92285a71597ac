"""Recorded pokes fed to the mapper the live loop uses: a whole session, or one poke on its own.

A session's pokes are taken, in order, by the step of the live loop
(:class:`~deformap.explore.MappingRun`), so a poke gives the same β whichever way it arrives.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_instance, check_points, check_positive, check_vector
from deformap.cloud import PointCloud
from deformap.environment import ForceTravel, PressObservation, TactileContact, Workspace
from deformap.errors import DeformapError
from deformap.explore import ExplorationConfig, ExplorationResult, Mapper, MappingRun, PokeResult
from deformap.replay._session import DEFAULT_CONTACT_GAP_M, RecordedSession, check_contact_gap

__all__ = ["ReplayResult", "estimate_poke", "map_session", "tip_sphere_points"]

logger = logging.getLogger(__name__)


@dataclass
class ReplayResult:
    """What :func:`map_session` produced: the ``result`` of every usable poke (``stop_reason``
    ``"end-of-session"``), ``skipped``, ``{"index": i, "error": message}`` per unusable poke, and
    ``notes``, ``{"index": i, "warning": message}`` per poke used with a warning (a raw bag's
    record and camera that disagree)."""

    result: ExplorationResult
    skipped: list[dict[str, Any]] = field(default_factory=list)
    notes: list[dict[str, Any]] = field(default_factory=list)

    @property
    def warnings(self) -> list[str]:
        """One line per skipped poke or warning, numbered from 1 as the console and figures
        are."""
        return [*(f"poke {s['index'] + 1} skipped: {s['error']}" for s in self.skipped),
                *(f"poke {n['index'] + 1}: {n['warning']}" for n in self.notes)]


def map_session(session: RecordedSession, config: ExplorationConfig, *, rng: np.random.Generator,
                on_poke: Callable[[PokeResult], None] | None = None) -> ReplayResult:
    """Feed a session's pokes, in order, to a fresh mapper.

    ``config``'s ``max_pokes``, ``threshold``, ``strategy`` and ``boundary_pokes`` do not apply:
    every recorded poke is used where it was made. ``rng`` is split as the live loop splits it, so the
    live run's generator gives its surface model. A poke that cannot be read, processed or added
    (any DeformapError) is logged and listed in ``skipped``. ``on_poke`` is called after each poke.
    """
    check_instance("session", session, RecordedSession)
    check_instance("config", config, ExplorationConfig)
    # explore() spawns max_pokes + 1 streams and fits the surface with the first; a spawned
    # child depends only on its position, so spawning one gives that same stream.
    run = MappingRun(session.workspace, config, session.observation, rng.spawn(1)[0])
    skipped: list[dict[str, Any]] = []
    notes: list[dict[str, Any]] = []
    unread: dict[int, str] = {}
    for index in range(len(session)):
        try:
            # reading the session stands in for the environment of the live loop
            poke = run.step(index, partial(session.press_observation, index))
        except DeformapError as exc:
            logger.warning("poke %d skipped: %s", index + 1, exc)
            skipped.append({"index": index, "error": str(exc)})
            continue
        found = session.poke_notes(index)
        if "disagreement" in found:
            notes.append({"index": index, "warning": found["disagreement"]})
        if "force_travel" in found and poke.record.stiffness_error is None:
            unread[index] = found["force_travel"]
        if on_poke is not None:
            on_poke(poke)
    result = run.result("end-of-session")
    if unread:  # the poke's own entry says why it has no modulus
        pokes = tuple(replace(p, record=replace(p.record, stiffness_error=unread[p.record.index]))
                      if p.record.index in unread else p for p in result.pokes)  # fmt: skip
        result = replace(result, pokes=pokes)
    return ReplayResult(result=result, skipped=skipped, notes=notes)


def tip_sphere_points(tip_center: Any, tip_radius_m: float) -> NDArray[np.float64]:
    """``(6, 3)`` vertices of the octahedron inscribed in the tip's sphere: robot points known
    without a hull file."""
    center = check_vector("tip_center", tip_center, 3, what="metres")
    radius = check_positive("tip_radius_m", tip_radius_m)
    return center + radius * np.vstack([np.eye(3), -np.eye(3)])


def estimate_poke(before: PointCloud, after: PointCloud, contact: TactileContact,
                  config: ExplorationConfig, *, rng: np.random.Generator, robot_points: Any = None,
                  force_travel: ForceTravel | None = None, released: PointCloud | None = None,
                  contact_gap_m: float = DEFAULT_CONTACT_GAP_M) -> PokeResult:
    """β of one poke from the world-frame clouds ``before`` and ``after`` (while pressing), and with
    the press's ``force_travel`` record its stiffness and E, read as the mapper reads a press
    (``released``: the surface once the tip has left, for the dent it kept).

    The surface, touch and shape-matching settings of ``config`` apply, over a workspace of three ROIs
    square centred on the contact. ``robot_points`` default to the tip's sphere
    (:func:`tip_sphere_points`); ``contact_gap_m`` as for :func:`~deformap.replay.load_session`.
    """
    for name, cloud in (("before", before), ("after", after)):
        check_instance(name, cloud, PointCloud)
    check_instance("contact", contact, TactileContact)
    robot = (tip_sphere_points(contact.tip_center, contact.tip_radius_m) if robot_points is None
             else check_points("robot_points", robot_points, min_rows=4))  # fmt: skip
    xy = contact.contact_point[:2]
    half = 1.5 * config.touch.roi_size_m
    workspace = Workspace(lower=tuple(xy - half), upper=tuple(xy + half))
    obs = PressObservation(cloud=after, contact=contact, robot_points=robot, target_xy=xy,
                           force_n=contact.force_n, force_travel=force_travel,
                           released=released)  # fmt: skip
    check_contact_gap(obs, check_positive("contact_gap_m", contact_gap_m), "`after` and `contact`")
    mapper = Mapper(workspace, config)
    mapper.initialise(before, rng)
    return mapper.process_press(obs, 0)
