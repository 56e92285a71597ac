"""Estimate β of one poke from two cloud files and the tactile contact (world frame, SI units),
with a force–travel record also its stiffness and E, and write ``estimate.json``,
``beta-curve.png`` and ``poke.png``.
"""

from __future__ import annotations

import contextlib
import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from deformap.cloud.io import read_cloud
from deformap.environment import ForceTravel, TactileContact
from deformap.errors import DeformapError, FileFormatError, InvalidArgumentError
from deformap.replay import estimate_poke
from deformap.run._config import RunConfig
from deformap.run._figures import write_estimate_figures
from deformap.run._folder import claim_run_folder, write_json
from deformap.run._report import estimate_report

__all__ = ["EstimateOutput", "estimate_one_poke", "read_force_travel_csv"]

# a column's name gives its unit: metres to the unit named
_TRAVEL_UNITS = {"travel_m": 1.0, "travel_mm": 1e-3}
_MAX_RECORD_BYTES = 64 * 2**20  # a press sampled at 10 kHz for a minute is about 20 MB of text


@dataclass(frozen=True, kw_only=True)
class EstimateOutput:
    """What :func:`estimate_one_poke` found (``report``: the content of ``estimate.json``) and the
    folder it wrote (``None`` when none)."""

    report: dict[str, Any]
    folder: Path | None


def read_force_travel_csv(path: Path) -> ForceTravel:
    """A press's force–travel record from a CSV file with a header row naming a travel column
    (``travel_m`` or ``travel_mm``, since first contact) and ``force_n`` (the normal force on the
    surface); other columns (e.g. ``time_s``) are ignored. Rows in time order, from first contact
    to the commanded force. Anything else is a :class:`~deformap.errors.FileFormatError` naming
    the file, and the row where it applies."""
    try:
        if path.stat().st_size > _MAX_RECORD_BYTES:
            raise FileFormatError(f"{path}: larger than {_MAX_RECORD_BYTES // 2**20} MiB; a "
                                  "force–travel record of one press is far smaller")
        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except FileNotFoundError:
        raise FileFormatError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise FileFormatError(f"{path}: cannot read this force–travel record: {exc}") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    header = [c.strip() for c in rows[0]] if rows else []
    travel_names = [n for n in header if n in _TRAVEL_UNITS]
    if len(travel_names) != 1 or header.count("force_n") != 1:
        raise FileFormatError(
            f"{path}: the first row must name one travel column (travel_m or travel_mm) and "
            f"force_n; got {', '.join(header) or 'an empty file'}")
    columns = header.index(travel_names[0]), header.index("force_n")
    values = []
    for number, row in enumerate(rows[1:], start=2):
        try:
            pair = [float(row[c]) for c in columns]
        except (IndexError, ValueError):
            raise FileFormatError(f"{path}: row {number} must hold a number under "
                                  f"{travel_names[0]} and force_n; got {row}") from None
        if not all(math.isfinite(v) for v in pair):
            raise FileFormatError(f"{path}: row {number} holds a NaN or infinite value: {row}")
        values.append(pair)
    if not values:
        raise FileFormatError(f"{path}: no samples below the header")
    data = np.array(values)
    try:
        return ForceTravel(travel_m=data[:, 0] * _TRAVEL_UNITS[travel_names[0]], force_n=data[:, 1])
    except DeformapError as exc:
        raise FileFormatError(f"{path}: {exc}") from None


def estimate_one_poke(
    *, before: Path, after: Path, tip_center: Sequence[float], force: Sequence[float],
    tip_radius_m: float, config: RunConfig, robot_hull: Path | None = None,
    record: Path | None = None, units: str = "m", seed: int = 0, out: Path | None = None,
) -> EstimateOutput:  # fmt: skip
    """β of one poke (:func:`deformap.replay.estimate_poke`) from the clouds ``before`` and
    ``after`` (PCD, PLY, NPZ in ``units`` m or mm), the tip's centre ``tip_center`` (3,) [m] and
    ``force`` (3,) [N] at the press, with ``config.exploration`` and the surface fit's ``seed``.

    ``record`` is the press's force–travel record (:func:`read_force_travel_csv`; it must end at
    ``force``'s magnitude): with it the dent is anchored to the record and the stiffness and E
    are read as the mapper reads a press, the layer's thickness taken from ``before`` under the
    contact. ``robot_hull`` is a cloud whose hull covers stick and hand (default: the tip's
    sphere); ``out`` a new or empty folder for ``estimate.json`` and the figures, created before
    the work. A bad
    contact (named ``--contact/--force/--tip-radius``), an unreadable cloud, a contact far from
    the surface or a bad ``out`` raise a :class:`~deformap.errors.DeformapError`.
    """
    try:
        contact = TactileContact(tip_center=np.array(tip_center), force=np.array(force),
                                 tip_radius_m=tip_radius_m)  # fmt: skip
    except InvalidArgumentError as exc:
        raise InvalidArgumentError(f"--contact/--force/--tip-radius: {exc}") from None
    hull = None if robot_hull is None else read_cloud(robot_hull, units=units).points
    clouds = read_cloud(before, units=units), read_cloud(after, units=units)
    force_travel = None if record is None else read_force_travel_csv(record)
    with contextlib.ExitStack() as held:
        if out is not None:  # held until the result is written
            held.enter_context(claim_run_folder(out, what="result"))
        try:
            poke = estimate_poke(*clouds, contact, config.exploration,
                                 rng=np.random.default_rng(seed), robot_points=hull,
                                 force_travel=force_travel)  # fmt: skip
        except InvalidArgumentError as exc:
            if "`force_travel`" in str(exc):  # the record and --force are not one press
                raise InvalidArgumentError(f"--record/--force: {exc}") from None
            raise
        report = estimate_report(before, after, contact, poke)
        if out is not None:
            write_json(out / "estimate.json", report)
            write_estimate_figures(out, poke)
        return EstimateOutput(report=report, folder=out)
