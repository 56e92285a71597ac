"""Which field a run maps on, poke after poke. Under ``field: modulus`` the run maps on the
modulus field once a poke has a modulus, on the β-field before. A place whose modulus could not
be read twice (two unread presses within :func:`unread_radius_m`) leaves the targets and the
stopping rule; when no target would be left the run maps on the β-field for good.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from deformap.explore._config import ExplorationConfig, FieldName
from deformap.explore._grid import MapGrid
from deformap.explore._modulus import ModulusField
from deformap.explore._records import PokeRecord
from deformap.explore._targets import BOUNDARY_SPACING_ROI

__all__ = ["FieldChoice", "choose_map_field", "unread_radius_m"]


def unread_radius_m(config: ExplorationConfig) -> float:
    """Radius [m] of one place, ``BOUNDARY_SPACING_ROI`` ROIs (a dent spreads a few centimetres)."""
    return float(BOUNDARY_SPACING_ROI * config.touch.roi_size_m)


@dataclass(frozen=True, eq=False)
class FieldChoice:
    """The field a run maps on after its latest poke, and why.

    ``name`` is ``"beta"`` or ``"modulus"``; ``grid`` the map's grid without the discs of the
    ``unread_places``, the presses [m] where the modulus could not be read twice; ``fallback`` why
    the run maps on β although it asked for the modulus field; ``given_up`` why it does for good.
    """

    name: FieldName
    grid: MapGrid
    fallback: str | None = None
    unread_places: tuple[tuple[float, float], ...] = ()
    given_up: str | None = None


def _unread_here(previous: FieldChoice, records: Sequence[PokeRecord], modulus: ModulusField,
                 grid: MapGrid, radius: float) -> FieldChoice:
    """``previous`` with the latest poke's place taken out when its modulus was not read there
    twice; unchanged otherwise (also while no poke has a modulus)."""
    reading = modulus.readings[-1]
    if previous.given_up is not None or reading.excluded is None or len(records) < 2:
        return previous
    latest = records[-1]
    here = np.asarray(latest.contact_xy, dtype=float)
    unread = {r.index for r in modulus.readings[:-1] if r.excluded is not None}
    before = [np.asarray(r.contact_xy, dtype=float) for r in records[:-1]
              if r.index in unread and np.hypot(*(np.asarray(r.contact_xy) - here)) <= radius]
    if not before or not len(modulus.pokes):
        return previous
    # the disc about every unread press of the place, not only the last
    places = (*previous.unread_places, *((float(x), float(y)) for x, y in (*before, here)))
    left = grid.without(np.array(places), radius)
    if left is not None:
        return FieldChoice(name=previous.name, grid=left, unread_places=places)
    return FieldChoice(name=previous.name, grid=grid, unread_places=previous.unread_places,
                       given_up=(f"poke {latest.index + 1}: the modulus could not be read twice "
                                 f"at one place ({reading.excluded}); no target would be left "
                                 "without it"))


def choose_map_field(previous: FieldChoice, requested: FieldName, records: Sequence[PokeRecord],
                     modulus: ModulusField, grid: MapGrid, radius: float) -> FieldChoice:
    """The field to map on after the latest of ``records``, given the ``previous`` choice (before
    any poke ``FieldChoice(requested, grid)``), the ``requested`` ``ExplorationConfig.field``, the
    ``modulus`` field over ``records``, the map's ``grid`` and :func:`unread_radius_m`."""
    if requested == "beta" or not records:
        return FieldChoice(name="beta" if requested == "beta" else previous.name, grid=grid)
    choice = _unread_here(previous, records, modulus, grid, radius)
    why = choice.given_up
    if why is None and not len(modulus.pokes):
        why = f"poke {records[-1].index + 1} gave no modulus ({modulus.readings[-1].excluded})"
    # the fall-back names its first reason while it lasts (the same reason at a later poke is
    # not news)
    fallback = (None if why is None else previous.fallback
                or f"`exploration.field` 'modulus' fell back to 'beta': {why}")
    return FieldChoice(name="modulus" if fallback is None else "beta", grid=choice.grid,
                       fallback=fallback, unread_places=choice.unread_places,
                       given_up=choice.given_up)
