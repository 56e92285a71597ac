"""The next place to poke: the configured strategy until the map field's variance is under its
``T_h``, then the boundary pokes (strategies and scores in :mod:`deformap.explore._acquisition`).

Under an appearance prior the looks come first: while the variance is above ``T_h``, the interior
(:func:`segment_interior`) of the largest segment of the largest look no poke has read (a look:
the segments within ``ℓ_a`` of it), if that look covers more than one poke does on the blind map
(:func:`covered_area_m2`) and is not yet known; once under ``T_h``, a test of the looks: in the
largest segment with one poke, the place the blind map (``w = 0``) knows least while still above
``T_h``. A test the pokes contradict moves the weight's posterior toward the blind map.

Once under ``T_h``, where the prior holds (the pokes make the looks more probable than the blind
map, the weight's posterior above one half on ``w > 0``), no target's footprint (a dent's, the
segmentation's ``BOUNDARY_SPACING_ROI`` ROIs across) meets a segment of another look (farther
than ``ℓ_a``; :func:`footprint_inside`): the boundary is then the image's, a dent across it reads
between two materials, and the boundary pokes and the tests of the looks poke inside the looks.
Where no such place is left, or the prior does not hold, every reachable place may be poked.
Above ``T_h`` the targets seek the least known places, not edges, and are left as they are.

When only the edge band, where no poke fits, is still above ``T_h``, ``planned`` plans it like
any other place; the other strategies poke the reachable cell of largest variance.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage as ndi
from scipy.spatial import cKDTree

from deformap.explore._acquisition import boundary_score, choose_target
from deformap.explore._appearance_prior import LOOK_SCALES
from deformap.explore._classes import poke_classes
from deformap.explore._config import ExplorationConfig, FieldName
from deformap.explore._field import PokeField, PokeSet, field_settings
from deformap.explore._grid import MapGrid
from deformap.explore._planning import PokePlan, plan_pokes
from deformap.explore._records import Target

__all__ = ["BOUNDARY_SPACING_ROI", "choose_next", "covered_area_m2", "expected_noise",
           "footprint_inside", "segment_interior"]

logger = logging.getLogger(__name__)

BOUNDARY_SPACING_ROI = 0.25
"""Boundary pokes keep this many ROI sizes from every poke: a dent spreads a few centimetres, so
closer pokes would measure much the same foam again."""


def expected_noise(candidates: NDArray[np.float64], pokes: PokeSet, config: ExplorationConfig,
                   field: FieldName) -> NDArray[np.float64]:
    """``(c,)`` the uncertainty a poke at each of ``candidates (c, 2)`` is expected to have: the
    largest of the pokes within ``BOUNDARY_SPACING_ROI`` ROIs of it (a press there measures that
    foam again, no better), else the field's noise floor with ``pokes.nugget`` added in variance."""
    floor = float(np.hypot(field_settings(config, field).noise_floor, pokes.nugget))
    noise = np.full(len(candidates), floor)
    if len(pokes) == 0:
        return noise
    radius = BOUNDARY_SPACING_ROI * config.touch.roi_size_m
    near = cKDTree(pokes.xy).query_ball_point(candidates, r=radius)
    for i, found in enumerate(near):
        if found:
            noise[i] = max(floor, float(pokes.noise[found].max()))
    return noise


def _plan(grid: MapGrid, pokes: PokeSet, config: ExplorationConfig, n_made: int,
          field: PokeField) -> PokePlan:
    """The plan with the fewest further pokes that brings the variance under ``T_h``."""
    cfg = field_settings(config, field.name)
    models = field.models
    return plan_pokes(
        pokes.xy, pokes.noise, grid.plan_candidates, grid.plan_domain,
        signal_std=cfg.signal_std, length_scale=cfg.length_scale_m,
        new_noise=expected_noise(grid.plan_candidates, pokes, config, field.name),
        threshold=cfg.threshold, max_new=max(1, config.max_pokes - n_made),
        covariance=None if models is None else models.covariance_at_mean,
    )  # fmt: skip


def _straddle(grid: MapGrid, field: PokeField, pokes: PokeSet, config: ExplorationConfig
              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """The reachable cells at least ``BOUNDARY_SPACING_ROI`` ROIs from every poke and their
    straddle scores (:func:`boundary_score` against the isopleths of the pokes' classes); ``σ``
    alone before any poke; both empty when no cell is left."""
    allowed = grid.target_mask.copy()
    var = field.variance.ravel()
    if len(pokes) == 0:
        return grid.cells_xy[allowed], np.sqrt(var[allowed])
    spacing = BOUNDARY_SPACING_ROI * config.touch.roi_size_m
    allowed &= cKDTree(pokes.xy).query(grid.cells_xy, k=1)[0] >= spacing
    if not allowed.any():
        return np.empty((0, 2)), np.empty(0)
    mean = field.mean
    classes = poke_classes(mean, pokes, config, field.name)
    score = boundary_score(mean.ravel()[allowed], np.sqrt(var[allowed]), classes.levels)
    return grid.cells_xy[allowed], score


def segment_interior(grid: MapGrid, segments: NDArray[np.int64], segment: int
                     ) -> tuple[NDArray[np.float64], float] | None:  # fmt: skip
    """The reachable cell deepest inside ``segment`` of ``segments (ny, nx)`` (the largest
    distance to its edge, a distance transform) and that distance [m]; ``None`` when none of its
    cells is reachable."""
    inside = segments == segment
    reach = inside & grid.target_mask.reshape(grid.shape)
    if not reach.any():
        return None
    spacing = float(grid.xs[1] - grid.xs[0]) if grid.xs.size > 1 else 1.0
    depth = ndi.distance_transform_edt(np.pad(inside, 1))[1:-1, 1:-1] * spacing
    flat = int(np.argmax(np.where(reach, depth, -1.0)))
    return np.array(grid.cells_xy[flat], dtype=float), float(depth.ravel()[flat])


def footprint_inside(looks: NDArray[np.int64], spacing_m: float, radius_m: float,
                     alike: NDArray[np.bool_] | None = None) -> NDArray[np.bool_]:
    """``(ny, nx)`` whether a disc of ``radius_m`` [m] centred on each cell meets no segment of
    another look: ``looks (ny, nx)`` each cell's segment (none masked), cells ``spacing_m``
    apart, ``alike (n, n)`` which segments share a look (default: each only itself). A cell's
    distance to the nearest cell of a segment unlike its own, less half a cell (the edge lies
    between the two), must be at least ``radius_m``. The workspace's border is no edge."""
    n = int(looks.max()) + 1
    same = np.eye(n, dtype=bool) if alike is None else np.asarray(alike, dtype=bool)
    inside = np.ones(looks.shape, dtype=bool)
    for s in np.unique(looks):
        mine = looks == s
        kin = same[s][looks]
        if kin.all():
            continue
        depth = ndi.distance_transform_edt(kin) * spacing_m - spacing_m / 2
        inside[mine] = depth[mine] >= radius_m
    return inside


def _interior_grid(grid: MapGrid, field: PokeField, config: ExplorationConfig) -> MapGrid:
    """``grid`` with the targets whose footprint meets another look taken out, where the prior
    holds (module docstring); ``grid`` itself where it does not or no place would be left."""
    models = field.models
    if field.prior is None or models is None:
        return grid
    values, probability = models.posterior.weight_distribution()
    if probability[values > 0].sum() <= 0.5:
        return grid
    spacing = float(grid.xs[1] - grid.xs[0]) if grid.xs.size > 1 else 1.0
    radius = BOUNDARY_SPACING_ROI * config.touch.roi_size_m / 2
    d2, alike = _look_distance(field)
    inside = footprint_inside(field.prior.looks, spacing, radius, d2 <= alike).ravel()
    target = grid.target_mask & inside
    candidates = grid.plan_candidates[inside[field.prior.cells_of(grid.plan_candidates)]]
    if not target.any() or not len(candidates):
        return grid
    return replace(grid, target_mask=target, plan_candidates=candidates)


def _poked_segments(field: PokeField, segments: NDArray[np.int64]) -> NDArray[np.int64]:
    """How many pokes each segment holds, ``(n_segments,)``."""
    assert field.prior is not None
    seg = segments.ravel()[field.prior.cells_of(field.pokes.xy)]
    return np.bincount(seg[seg >= 0], minlength=int(segments.max()) + 1)


def _look_distance(field: PokeField) -> tuple[NDArray[np.float64], float]:
    """``(n, n)`` squared distances between the segments' features and the squared ``ℓ_a`` that
    makes two looks alike (the posterior's most probable; before any poke the grid's middle)."""
    assert field.prior is not None
    feats = field.prior.image.features
    d2 = np.sum((feats[:, None, :] - feats[None, :, :]) ** 2, axis=-1)
    models = field.models
    scale = LOOK_SCALES[len(LOOK_SCALES) // 2] if models is None else models.posterior.look_scale
    return d2, scale**2


def covered_area_m2(config: ExplorationConfig, field: FieldName) -> float:
    """The area [m²] one exact poke brings under ``T_h`` on the blind map: the disc where
    ``σ² (1 − k²) ≤ T_h``, radius² ``−σ_w² ln(1 − T_h / σ²) / 2``; a look smaller than this
    gains nothing from a poke placed by its look."""
    cfg = field_settings(config, field)
    ratio = min(cfg.threshold / cfg.signal_std**2, 1.0 - 1e-12)
    return float(np.pi * -(cfg.length_scale_m**2) * np.log(1.0 - ratio) / 2.0)


def _look_target(grid: MapGrid, field: PokeField, config: ExplorationConfig, threshold: float,
                 done: bool) -> NDArray[np.float64] | None:
    """Where the looks say to poke next (module docstring), or ``None`` (the strategy's turn)."""
    assert field.prior is not None
    segments = field.prior.image.segments
    poked = _poked_segments(field, segments)
    area = (np.bincount(segments.ravel()[segments.ravel() >= 0], minlength=poked.size)
            * config.surface.grid_spacing_m**2)  # fmt: skip
    stop = grid.stop_mask.reshape(grid.shape)
    if not done:
        d2, alike = _look_distance(field)
        look_area = (d2 <= alike) @ area  # each segment's look: the area of every alike segment
        read = (poked > 0) | ((d2[:, poked > 0] <= alike).any(axis=1))
        above = (field.variance > threshold) & stop
        open_ = [s for s in np.lexsort((-area, -look_area))
                 if not read[s] and look_area[s] >= covered_area_m2(config, field.name)
                 and above[segments == s].any()]
        for s in open_:
            found = segment_interior(grid, segments, int(s))
            if found is not None and found[1] >= BOUNDARY_SPACING_ROI * config.touch.roi_size_m / 2:
                return found[0]
        return None
    models = field.models
    if models is None:
        return None
    blind = models.blind_variance(grid.cells_xy).reshape(grid.shape)
    for s in np.argsort(-area, kind="stable"):
        if poked[s] != 1:
            continue
        vouched = (segments == s) & stop & (blind > threshold)
        reach = vouched & grid.target_mask.reshape(grid.shape)
        if reach.any():
            flat = int(np.argmax(np.where(reach, blind, -np.inf)))
            return np.array(grid.cells_xy[flat], dtype=float)
    return None


def choose_next(grid: MapGrid, field: PokeField, config: ExplorationConfig,
                rng: np.random.Generator, *, boundary_owed: int,
                n_made: int | None = None) -> Target | None:
    """The next target after the pokes the map ``field`` was fitted to (read with its own
    :func:`deformap.explore.field_settings`), or ``None`` when the variance is under ``T_h`` and
    no boundary poke is owed or none has a place left; ``rng`` is this choice's stream,
    ``n_made`` the pokes made so far (default: the field's, which may leave some out)."""
    pokes = field.pokes
    variance = field.variance.ravel()
    threshold = field_settings(config, field.name).threshold
    done = variance[grid.stop_mask].max() <= threshold
    if done:  # the pokes that seek edges: boundary pokes and the tests of the looks
        grid = _interior_grid(grid, field, config)
    if field.prior is not None:
        look = _look_target(grid, field, config, threshold, done)
        if look is not None:
            return Target(look, "appearance")
    if done:
        if boundary_owed == 0:
            return None
        cells, score = _straddle(grid, field, pokes, config)
        if score.size == 0:
            logger.warning("%d of %d boundary pokes left undone: no reachable place is %.3g m "
                           "from every poke", boundary_owed, config.boundary_pokes,
                           BOUNDARY_SPACING_ROI * config.touch.roi_size_m)  # fmt: skip
            return None
        return Target(np.array(cells[int(np.argmax(score))], dtype=float), "boundary")
    cells, reachable = grid.cells_xy[grid.target_mask], variance[grid.target_mask]
    plans: list[PokePlan] = []

    def planner() -> NDArray[np.float64]:
        made = len(pokes) if n_made is None else n_made  # the field may leave pokes out
        plans.append(_plan(grid, pokes, config, made, field))
        return np.array(plans[-1].targets[0], dtype=float)

    if reachable.max() <= threshold:  # only the edge band is left
        if config.strategy == "planned":
            xy = planner()
        else:
            xy = np.array(cells[int(np.argmax(reachable))], dtype=float)
    else:
        def scorer() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
            found = _straddle(grid, field, pokes, config)
            if found[1].size == 0:  # every reachable cell near a poke: the least known one
                return cells, reachable
            return found

        chosen = choose_target(config.strategy, cells, reachable, threshold, rng,
                               planner=planner, scorer=scorer)  # fmt: skip
        if chosen is None:  # pragma: no cover - reachable.max() > threshold above
            return None
        xy = chosen
    return Target(xy, "variance", plans[-1] if plans else None)
