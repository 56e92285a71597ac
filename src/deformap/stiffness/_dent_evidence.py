"""What the dent's shape in the camera's cloud says about the contact models
(:mod:`deformap.stiffness`, Contact models)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError
from deformap.mechanics import (
    foundation_surface_deflection,
    hertz_surface_at_depth,
    layer_surface_deflection,
)
from deformap.stiffness._tables import BONDED_LAYER, FOUNDATION, ContactTable

__all__ = ["DentSamples", "dent_terms"]

_MAD_TO_STD = 1.4826


@dataclass(frozen=True, kw_only=True)
class DentSamples:
    """The surface's sink about a press, seen by the camera while pressing.

    ``offset_m (m, 2)`` each point's horizontal offset [m] from the contact's centre;
    ``sink_m (m,)`` how far below the surface at rest it lies [m]; ``correlation_length_m`` the
    size of the cells over which the points' errors are tested for correlation (class
    docstring of :func:`dent_terms`).
    """

    offset_m: NDArray[np.float64]
    sink_m: NDArray[np.float64]
    correlation_length_m: float

    @classmethod
    def of(cls, offset_m: Any, sink_m: Any, correlation_length_m: float) -> DentSamples:
        """Checked samples (``InvalidArgumentError`` naming the field)."""
        xy = check_array("offset_m", offset_m, (None, 2), what="metres")
        u = check_array("sink_m", sink_m, (None,), what="metres")
        if u.shape[0] != xy.shape[0]:
            raise InvalidArgumentError(
                f"`sink_m` must have one value per `offset_m` row ({xy.shape[0]}); got {u.size}")
        return cls(offset_m=xy, sink_m=u, correlation_length_m=check_positive(
            "correlation_length_m", correlation_length_m))

    @property
    def radius_m(self) -> NDArray[np.float64]:
        """``(m,)`` each point's distance [m] from the contact's centre."""
        return np.asarray(np.hypot(self.offset_m[:, 0], self.offset_m[:, 1]))


def _correlation_factor(residual: NDArray[np.float64], offset: NDArray[np.float64],
                        cell: float, scatter: float) -> float:
    """How many points count as one: ``τ = mean over cells of nᶜ · (mean residualᶜ)² / σ²``,
    at least 1 (batch means over square cells of side ``cell``; Thiébaux & Zwiers 1984). Errors
    independent between points give ``τ ≈ 1``; errors shared within a cell give its size."""
    keys = np.floor(offset / cell).astype(np.int64)
    _, cell_of, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    cell_of = cell_of.ravel()
    sums = np.bincount(cell_of, weights=residual)
    full = counts >= 2
    if not np.any(full):
        return 1.0
    tau = float(np.mean(sums[full] ** 2 / counts[full])) / scatter**2
    return max(tau, 1.0)


def _predicted(table: ContactTable, model: str, depth: float, radius: float, thickness: float,
               nu: float, r: NDArray[np.float64]) -> NDArray[np.float64]:
    """The model's sink at ``r`` for its depth ``δ_c`` at the commanded force: each model's own
    surface (the foundation's, the bonded layer's of its thickness, Hertz's half-space;
    :mod:`deformap.mechanics`)."""
    if model == FOUNDATION and table.contact_radius is not None:
        a = float(np.interp(np.log(depth), table.log_depth, np.log(table.contact_radius)))
        return foundation_surface_deflection(r, min(float(np.exp(a)), radius), radius, thickness,
                                             nu)
    if model == BONDED_LAYER:
        return layer_surface_deflection(r, depth, radius, thickness, nu)
    return hertz_surface_at_depth(r, depth, radius)


def dent_terms(dent: DentSamples, models: list[tuple[str, ContactTable, float]], radius: float,
               thickness: float, nu: float) -> tuple[NDArray[np.float64], float]:
    """Each model's χ² terms of the sink, ``(models, m)``, and the points' correlation factor ``τ``.

    ``models`` holds ``(name, table, δ_c)``. Each model's sink is compared with a free offset
    (the surface at rest is itself an estimate); the points' scatter ``σ`` is the MAD of the best
    model's residuals, common to all; a term is a point's squared residual over ``σ²``, clipped
    at 5 σ (flying pixels). ``τ`` is the correlation factor of the best model's residuals over
    cells of ``correlation_length_m`` (:func:`_correlation_factor`): ``m / τ`` points count, so
    the dent's χ² is the terms' sum over ``τ``, and what the best model misses counts as
    correlated error too. Fewer than 3 points, or one model, give no terms (``(models, 0)``).
    """
    m = dent.radius_m.size
    if m < 3 or len(models) < 2:
        return np.zeros((len(models), 0)), 1.0
    residuals = []
    for name, table, depth in models:
        res = dent.sink_m - _predicted(table, name, depth, radius, thickness, nu, dent.radius_m)
        residuals.append(res - np.median(res))
    spread = np.array([float(np.median(np.abs(r))) for r in residuals])
    scatter = max(_MAD_TO_STD * float(spread.min()), 1e-6)
    # flying pixels: beyond 5 σ a point is no sample of the sink (its residual is clipped)
    clipped = np.array([np.clip(r, -5.0 * scatter, 5.0 * scatter) for r in residuals])
    tau = _correlation_factor(clipped[int(np.argmin(spread))], dent.offset_m,
                              dent.correlation_length_m, scatter)
    return np.asarray(clipped**2 / scatter**2), tau
