"""Estimate β of one poke from two cloud files and the tactile contact (world frame, SI units),
and write ``estimate.json``, ``beta-curve.png`` and ``poke.png``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from deformap.cloud.io import read_cloud
from deformap.environment import TactileContact
from deformap.errors import InvalidArgumentError
from deformap.replay import estimate_poke
from deformap.run._config import RunConfig
from deformap.run._figures import write_estimate_figures
from deformap.run._folder import create_run_folder, write_json
from deformap.run._report import estimate_report

__all__ = ["EstimateOutput", "estimate_one_poke"]


@dataclass(frozen=True, kw_only=True)
class EstimateOutput:
    """What :func:`estimate_one_poke` found (``report``: the content of ``estimate.json``) and the
    folder it wrote (``None`` when none)."""

    report: dict[str, Any]
    folder: Path | None


def estimate_one_poke(
    *, before: Path, after: Path, tip_center: Sequence[float], force: Sequence[float],
    tip_radius_m: float, config: RunConfig, robot_hull: Path | None = None, units: str = "m",
    seed: int = 0, out: Path | None = None,
) -> EstimateOutput:  # fmt: skip
    """β of one poke (:func:`deformap.replay.estimate_poke`) from the clouds ``before`` and
    ``after`` (PCD, PLY, NPZ in ``units`` m or mm), the tip's centre ``tip_center`` (3,) [m] and
    ``force`` (3,) [N] at the press, with ``config.exploration`` and the surface fit's ``seed``.

    ``robot_hull`` is a cloud whose hull covers stick and hand (default: the tip's sphere); ``out``
    a new or empty folder for ``estimate.json`` and the figures, created before the work. A bad
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
    if out is not None:
        create_run_folder(out, what="result")
    poke = estimate_poke(*clouds, contact, config.exploration, rng=np.random.default_rng(seed),
                         robot_points=hull)  # fmt: skip
    report = estimate_report(before, after, contact, poke)
    if out is not None:
        write_json(out / "estimate.json", report)
        write_estimate_figures(out, poke)
    return EstimateOutput(report=report, folder=out)
