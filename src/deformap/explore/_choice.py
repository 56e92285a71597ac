"""Which field a run maps on: the policy that, poke after poke, picks the β-field or the modulus
field, never editing the settings (``ExplorationConfig.field`` stays what was asked for).

Under ``field: modulus`` the run maps on the modulus field once a poke has a modulus, and on the
β-field while none has (a camera-only robot or session). A place whose modulus could not be read
twice (two presses within :func:`unread_radius_m` of each other whose records were not read: a
further press there would read nothing again, so the modulus field's variance there would never
fall) leaves the targets and the stopping rule: the choice grid is the map's grid without a disc
about each such press. When no target would be left the run maps on the β-field for good, on the
whole grid. Under ``field: beta`` the run maps on the β-field.
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
    """Radius [m] of one place: two presses this close are at one place, and an unread place's
    disc of it leaves the targets and the stopping rule (``BOUNDARY_SPACING_ROI`` ROIs: a dent
    spreads a few centimetres)."""
    return float(BOUNDARY_SPACING_ROI * config.touch.roi_size_m)


@dataclass(frozen=True, eq=False)
class FieldChoice:
    """The field a run maps on after its latest poke, and why.

    Attributes
    ----------
    name : {"beta", "modulus"}
        The field the regions, the next target and the stopping rule run on.
    grid : MapGrid
        Where targets may go and the variance must fall: the map's grid without the unread
        places' discs.
    fallback : str or None
        Why the run maps on β although it asked for the modulus field (``None`` when it does not).
    unread_places : tuple of (x, y)
        The presses [m] of the places whose modulus could not be read twice, in the order found.
    given_up : str or None
        Why the run maps on β for good (no target would be left without the unread places).
    """

    name: FieldName
    grid: MapGrid
    fallback: str | None = None
    unread_places: tuple[tuple[float, float], ...] = ()
    given_up: str | None = None


def _unread_here(previous: FieldChoice, records: Sequence[PokeRecord], modulus: ModulusField,
                 grid: MapGrid, radius: float) -> FieldChoice:
    """``previous`` with the latest poke's place taken out when its modulus was not read there
    twice (module docstring); unchanged otherwise. While no poke has a modulus the run maps on
    β, which reads the place: nothing to avoid yet (a later unread press there, once a modulus
    is read, is caught again)."""
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
    """The field to map on after the latest of ``records`` (the run's pokes in order), given the
    choice after the poke before it (module docstring).

    Parameters
    ----------
    previous : FieldChoice
        The choice before the latest poke (before any poke: ``FieldChoice(requested, grid)``).
    requested : {"beta", "modulus"}
        ``ExplorationConfig.field``.
    records : sequence of PokeRecord
        Every poke so far, the latest last.
    modulus : ModulusField
        The modulus field over ``records`` (its ``readings`` say which poke has a modulus).
    grid : MapGrid
        The map's grid.
    radius : float
        :func:`unread_radius_m`.
    """
    if requested == "beta" or not records:
        return FieldChoice(name="beta" if requested == "beta" else previous.name, grid=grid)
    choice = _unread_here(previous, records, modulus, grid, radius)
    if choice.given_up is not None:
        why: str | None = choice.given_up
    elif not len(modulus.pokes):
        why = f"poke {records[-1].index + 1} gave no modulus ({modulus.readings[-1].excluded})"
    else:
        why = None
    fallback = None if why is None else f"`exploration.field` 'modulus' fell back to 'beta': {why}"
    return FieldChoice(name="modulus" if fallback is None else "beta", grid=choice.grid,
                       fallback=fallback, unread_places=choice.unread_places,
                       given_up=choice.given_up)
