"""The map's grid: every cell of the workspace, where a poke may go, where the variance must fall.
Targets keep half a ROI inside the workspace, so each ROI lies on the surveyed surface.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.explore._config import PLAN_GRID_M, ExplorationConfig

__all__ = ["MapGrid"]


def _strided(nx: int, ny: int, step_m: float, spacing_m: float,
             within: NDArray[np.bool_] | None = None) -> NDArray[np.int64]:
    """Flat indices of the ``(ny, nx)`` grid's cells about ``step_m`` apart, first and last rows
    and columns included, within the non-empty rectangle ``within``."""
    inside = np.ones(ny * nx, dtype=bool) if within is None else within
    rows, cols = np.nonzero(inside.reshape(ny, nx))
    stride = max(1, round(step_m / spacing_m))

    def keep(lo: int, hi: int) -> NDArray[np.int64]:
        return np.unique(np.append(np.arange(lo, hi + 1, stride), hi))

    ys, xs = keep(rows.min(), rows.max()), keep(cols.min(), cols.max())
    flat = (ys[:, None] * nx + xs[None, :]).ravel()
    return flat[inside[flat]]


@dataclass(frozen=True, eq=False)
class MapGrid:
    """Cells of the workspace at the surface grid's spacing, and the masks over them.

    ``xs (nx,)``, ``ys (ny,)`` [m] the cell centres (every map is ``(ny, nx)``); ``cells_xy
    (ny * nx, 2)`` row-major; ``target_mask``, ``stop_mask`` the cells a poke may be centred on and
    whose variance must fall under ``T_h``; ``plan_domain (d, 2)``, ``plan_candidates (c, 2)`` the
    planner's lattices of them.
    """

    xs: NDArray[np.float64]
    ys: NDArray[np.float64]
    cells_xy: NDArray[np.float64]
    target_mask: NDArray[np.bool_]
    stop_mask: NDArray[np.bool_]
    plan_domain: NDArray[np.float64]
    plan_candidates: NDArray[np.float64]

    @classmethod
    def build(cls, workspace: Workspace, config: ExplorationConfig) -> MapGrid:
        """The grid of ``workspace`` at ``config.surface.grid_spacing_m``."""
        spacing = config.surface.grid_spacing_m
        xs, ys = workspace.grid(spacing)
        gx, gy = np.meshgrid(xs, ys)
        cells = np.column_stack([gx.ravel(), gy.ravel()])
        margin = min(config.touch.roi_size_m / 2, 0.25 * min(workspace.size))
        lo, hi = np.asarray(workspace.lower) + margin, np.asarray(workspace.upper) - margin
        target = np.all((cells >= lo) & (cells <= hi), axis=1)
        stop = target if config.stop_region == "targets" else np.ones(len(cells), dtype=bool)
        domain = cells[_strided(xs.size, ys.size, PLAN_GRID_M, spacing, within=stop)]
        candidates = cells[_strided(xs.size, ys.size, PLAN_GRID_M, spacing, within=target)]
        return cls(xs, ys, cells, target, stop, domain, candidates)

    def without(self, centres: NDArray[np.float64], radius_m: float) -> MapGrid | None:
        """This grid with discs of ``radius_m`` around ``centres (n, 2)`` taken out of its targets
        and stop cells; ``None`` when none is left. Raises :class:`InvalidArgumentError`."""
        centres = np.asarray(centres, dtype=float)
        if centres.ndim != 2 or centres.shape[1] != 2 or not np.isfinite(centres).all():
            raise InvalidArgumentError(f"`centres` must be an (n, 2) array of finite metres; got "
                                       f"shape {centres.shape}")
        if not (np.isfinite(radius_m) and radius_m > 0):
            raise InvalidArgumentError(f"`radius_m` must be a positive number of metres; got "
                                       f"{radius_m!r}")
        near = np.zeros(len(self.cells_xy), dtype=bool)
        for centre in centres:
            near |= np.hypot(*(self.cells_xy - centre).T) <= radius_m
        target, stop = self.target_mask & ~near, self.stop_mask & ~near
        if not target.any() or not stop.any():
            return None

        def lattice(points: NDArray[np.float64]) -> NDArray[np.float64]:
            gone = (np.hypot(points[:, None, 0] - centres[None, :, 0],
                             points[:, None, 1] - centres[None, :, 1]) <= radius_m).any(axis=1)
            return points[~gone]

        domain, candidates = lattice(self.plan_domain), lattice(self.plan_candidates)
        if not len(domain) or not len(candidates):
            return None
        return MapGrid(self.xs, self.ys, self.cells_xy, target, stop, domain, candidates)

    @property
    def shape(self) -> tuple[int, int]:
        """``(ny, nx)``."""
        return (self.ys.size, self.xs.size)
