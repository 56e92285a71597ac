"""What one benchmark world gave (:class:`WorldResult`) and its one plain-data form.

A world's result is written to ``worlds/world-NNNNN.json`` and crosses process boundaries as the
plain data of :meth:`WorldResult.to_dict`; :meth:`WorldResult.from_dict` reads it back and refuses,
in one line, data of another :data:`POKES_FORMAT` or data that is damaged.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, cast

import numpy as np

from deformap.errors import InvalidArgumentError
from deformap.explore import PokeSet

__all__ = ["POKES_FORMAT", "TIME_COLUMNS", "WorldResult", "poke_data", "row_values"]

#: Version of a stored world's pokes: each mapping's (:meth:`WorldResult.run_key`) map-field
#: columns ``x``, ``y``, ``value``, ``noise``, ``index`` and ``thickness`` (:func:`poke_data`),
#: the β pokes of a modulus run that fell back (``fallback_pokes``), and rows that name their
#: ``appearance`` family and ``prior``. A reader refuses any other version rather than guess
#: what its columns mean.
POKES_FORMAT = 4
#: Columns of a row that hold wall times (the only ones two runs of one world may differ in).
TIME_COLUMNS = ("poke_s", "elapsed_s")
_POKE_COLUMNS = ("x", "y", "value", "noise", "index", "thickness")

PokeData = dict[str, list[Any]]


def poke_data(pokes: PokeSet, thickness: Sequence[float | None]) -> PokeData:
    """A map field's pokes as plain data: ``x``, ``y`` [m], ``value`` (β, or ln E [ln Pa]),
    ``noise`` (its uncertainty with the field's floor; the β-field's before the map's nugget,
    which depends on the pokes so far and is estimated again when they are rescored),
    ``index`` (the poke's number in its run, from 0) and ``thickness`` (the layer's at each poke
    [m], ``None`` where a poke had none: ``PokeRecord.layer_thickness_m``), in the field's order.
    Floats keep every bit through JSON (``repr``)."""
    return {"x": [float(v) for v in pokes.xy[:, 0]], "y": [float(v) for v in pokes.xy[:, 1]],
            "value": [float(v) for v in pokes.values], "noise": [float(v) for v in pokes.noise],
            "index": [int(v) for v in np.asarray(pokes.index)],
            "thickness": [None if t is None else float(t) for t in thickness]}


def row_values(row: Mapping[str, Any]) -> dict[str, Any]:
    """A row without its wall times (what two runs of one world must agree on)."""
    return {k: v for k, v in row.items() if k not in TIME_COLUMNS}


@dataclass(frozen=True, kw_only=True)
class WorldResult:
    """One benchmark world mapped with every strategy × field (:func:`deformap.eval.run_world`).

    Attributes
    ----------
    world : dict
        :meth:`deformap.eval.WorldDraw.summary` (a failed draw: ``index`` and ``family`` only).
    rows : tuple of dict
        One per arm × strategy × field × cut × poke, each naming them (``runs.csv``'s row
        columns).
    pokes : dict
        Each mapping's map field's pokes (:func:`poke_data`) under its :meth:`run_key`: what
        :func:`deformap.eval.rescore_world` scores other cuts on.
    fallback_pokes : dict
        The β pokes of each modulus mapping whose map field was β at some poke (a row's
        ``map_field`` says at which).
    seconds : float or None
        The world's wall time, building included (``None`` for a failed world).
    status : {"ok", "failed"}
    error : str or None
        A failed world's error, one line.
    """

    world: dict[str, Any]
    rows: tuple[dict[str, Any], ...] = ()
    pokes: dict[str, PokeData] = field(default_factory=dict)
    fallback_pokes: dict[str, PokeData] = field(default_factory=dict)
    seconds: float | None = None
    status: Literal["ok", "failed"] = "ok"
    error: str | None = None

    @staticmethod
    def run_key(appearance: str, prior: str, strategy: str, field: str) -> str:
        """``appearance/prior/strategy/field``: one mapping of a world, the key of its stored
        pokes."""
        return f"{appearance}/{prior}/{strategy}/{field}"

    @property
    def index(self) -> int:
        return int(self.world["index"])

    def to_dict(self) -> dict[str, Any]:
        """The plain data of the world's file (a failed world: no pokes)."""
        if self.status != "ok":
            return {"world": self.world, "rows": list(self.rows), "seconds": self.seconds,
                    "status": self.status, "error": self.error}
        return {"world": self.world, "rows": list(self.rows), "pokes": self.pokes,
                "fallback_pokes": self.fallback_pokes, "pokes_format": POKES_FORMAT,
                "seconds": self.seconds, "status": self.status, "error": self.error}

    @classmethod
    def from_dict(cls, data: Any) -> WorldResult:
        """Read :meth:`to_dict`'s data back.

        Raises
        ------
        InvalidArgumentError
            One line saying what is wrong: not a world, another ``pokes_format``, a finished
            world without its pokes, columns missing or of different lengths.
        """
        if not isinstance(data, dict) or not isinstance(data.get("world"), dict):
            raise InvalidArgumentError("expected an object with a `world` object")
        index = data["world"].get("index")
        if isinstance(index, bool) or not isinstance(index, int) or index < 0:
            raise InvalidArgumentError(f"`world.index` must be an integer >= 0; got {index!r}")
        rows = data.get("rows")
        if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
            raise InvalidArgumentError("`rows` must be a list of objects")
        if data.get("status") != "ok":
            return cls(world=data["world"], rows=tuple(rows), seconds=None, status="failed",
                       error=str(data.get("error")))
        version = data.get("pokes_format")
        if type(version) is not int or version != POKES_FORMAT:
            raise InvalidArgumentError(
                f"`pokes_format` is {version!r}; this version of deformap reads "
                f"{POKES_FORMAT} only")
        pokes, fallback = data.get("pokes"), data.get("fallback_pokes")
        for name, stored in (("pokes", pokes), ("fallback_pokes", fallback)):
            if not isinstance(stored, dict):
                raise InvalidArgumentError(f"`{name}` must be an object; got "
                                           f"{type(stored).__name__}")
            for combo, columns in stored.items():
                _check_pokes(columns, f"{name} of {combo!r}")
        seconds = data.get("seconds")
        return cls(world=data["world"], rows=tuple(rows), pokes=cast(dict[str, PokeData], pokes),
                   fallback_pokes=cast(dict[str, PokeData], fallback),
                   seconds=None if seconds is None else float(seconds), status="ok", error=None)


def _check_pokes(data: Any, what: str) -> None:
    """Refuse stored pokes that are not :func:`poke_data`'s columns of numbers."""
    if not isinstance(data, dict) or not all(isinstance(data.get(k), list)
                                             for k in _POKE_COLUMNS):
        raise InvalidArgumentError(f"the {what} must have lists {list(_POKE_COLUMNS)}")
    if len({len(data[k]) for k in _POKE_COLUMNS}) != 1:
        raise InvalidArgumentError(f"the {what} have columns of different lengths")
    numbers = [v for k in _POKE_COLUMNS for v in data[k] if not (k == "thickness" and v is None)]
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in numbers):
        raise InvalidArgumentError(f"the {what} must be numbers")
