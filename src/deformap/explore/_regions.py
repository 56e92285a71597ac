"""Cut the β-field into regions along isopleths.

How the contour levels are chosen
---------------------------------
The paper draws "the best isopleth" of the β-field without saying how. We choose the levels from
the data the field is trained on, the pokes' own estimates (the field's posterior at a poke is
smoothed toward its neighbours, which fills the very gaps that separate classes): the βs, sorted,
are split wherever two neighbours differ by more than they can be told apart —
``z · sqrt(σ_i² + σ_j²)`` with σ each estimate's uncertainty (at least the β-field's noise floor)
and ``z`` the separation in standard deviations (default 2: the difference is real at about
95 %), and never by less than ``min_step`` (default 0.05 in β). Each group
of pokes is one deformability class; the isopleth between two neighbouring classes lies half-way
between the largest β of the softer-looking group's lower neighbour and the smallest of the next
(the midpoint of the gap). Cells are labelled by the band of the β-field's mean they fall in, so a
region is a level set of the map, and ``n_regions`` is the number of classes found.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive

__all__ = ["RegionMap", "segment_regions"]


@dataclass(frozen=True)
class RegionMap:
    """Regions of a β-field on a grid.

    Attributes
    ----------
    labels : (ny, nx) int
        Region of each cell, 0 for the lowest β band (the stiffest class) upwards.
    levels : (n_regions - 1,) float
        The isopleths between bands, increasing.
    class_betas : (n_regions,) float
        Mean posterior β of the pokes in each class.
    """

    labels: NDArray[np.int64]
    levels: NDArray[np.float64]
    class_betas: NDArray[np.float64]

    @property
    def n_regions(self) -> int:
        return int(self.class_betas.size)


def segment_regions(
    beta_grid: NDArray[np.float64],
    poke_beta: NDArray[np.float64],
    poke_std: NDArray[np.float64],
    *,
    z: float = 2.0,
    min_step: float = 0.05,
) -> RegionMap:
    """Label the cells of ``beta_grid`` by isopleths chosen from the pokes' posterior β.

    Parameters
    ----------
    beta_grid : (ny, nx) float
        Posterior mean of the β-field on the grid.
    poke_beta, poke_std : (k,) float
        The k pokes' β estimates and their uncertainties.
    z : float
        Separation, in combined standard deviations, needed to call two pokes different.
    min_step : float
        Smallest β gap that can separate two classes, whatever the uncertainties say.
    """
    grid = check_array("beta_grid", beta_grid, (None, None))
    betas = check_array("poke_beta", poke_beta, (None,), min_rows=1)
    stds = check_array("poke_std", poke_std, (betas.size,), what="standard deviations")
    check_positive("z", z)
    check_positive("min_step", min_step, allow_zero=True)
    order = np.argsort(betas, kind="stable")
    b, s = betas[order], stds[order]
    gaps = np.diff(b)
    needed = np.maximum(z * np.hypot(s[:-1], s[1:]), min_step)
    cuts = np.flatnonzero(gaps > needed)
    groups = np.split(np.arange(b.size), cuts + 1)
    class_betas = np.array([b[g].mean() for g in groups])
    levels = np.array([(b[cut] + b[cut + 1]) / 2 for cut in cuts], dtype=float)
    labels = np.searchsorted(levels, grid, side="right").astype(np.int64)
    return RegionMap(labels=labels, levels=levels, class_betas=class_betas)
