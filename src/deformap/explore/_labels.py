"""The regions of the map field: the pokes' classes (:mod:`deformap.explore._classes`), junctions
merged and classes split by place (:mod:`deformap.explore._places`), classes split where their
presses read different behaviours (:func:`~deformap.explore._classes.split_by_behaviour`), then
each cell labelled (``ExplorationConfig.region_labels``).

- ``isopleth``, the paper's: a cell takes the band of the field's mean it falls in between the
  isopleths midway between neighbouring classes' means, so a region is a level set of the map.
- ``nearest``, the default: a cell takes the class of the poke nearest to it; under an appearance
  prior, of the poke it is most correlated with under the prior's model-averaged kernel. Unlike
  smooth isopleths, which revert to the field's mean away from the pokes, these follow the pokes.
- ``indicator-kriging``: a cell takes its most probable class, each class's probability kriged
  from the pokes' class indicators with the map field's own covariance
  (:mod:`deformap.explore._indicator`).

Under ``isopleth`` a class split by behaviour is no level set: a cell in its band takes the part
of the nearest of the band's pokes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from deformap.explore._classes import RegionMap, poke_classes, split_by_behaviour
from deformap.explore._config import ExplorationConfig, FieldName
from deformap.explore._field import PokeSet, field_settings
from deformap.explore._indicator import indicator_labels
from deformap.explore._places import merge_seam_classes, split_by_place

__all__ = ["map_regions"]


def map_regions(mean: NDArray[np.float64], pokes: PokeSet, cells_xy: NDArray[np.float64],
                config: ExplorationConfig, field: FieldName, *,
                correlation: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None,
                behaviours: Sequence[str | None] | None = None) -> RegionMap:  # fmt: skip
    """The regions of the map field ``field`` of mean ``mean (ny, nx)`` fitted to ``pokes``, as
    the exploration settings ask (module docstring), on the grid's ``cells_xy (ny · nx, 2)``;
    ``correlation`` (``cells (q, 2) -> (q, p)``, an appearance prior's) labels ``nearest`` by the
    most correlated poke instead of the nearest one; ``behaviours (p,)`` each poke's behaviour
    class (``PressBehaviour.behaviour``, ``None`` where none was read), which splits classes
    whose presses read different ones (``None``: values alone)."""
    settings = field_settings(config, field)
    found = poke_classes(mean, pokes, config, field)
    if config.merge_seams and found.n_regions >= 3:
        found = merge_seam_classes(found, mean, pokes.xy, pokes.values, pokes.thickness)
    if config.split_by_place:  # after the junctions: the parts it makes are not junctions
        found = split_by_place(found, mean, pokes.xy, pokes.values,
                               np.maximum(pokes.noise, settings.noise_floor),
                               pokes.thickness, max_regions=config.max_regions)  # fmt: skip
    by_value = found
    if behaviours is not None:
        found = split_by_behaviour(found, mean, pokes.xy, pokes.values, behaviours)
    if config.region_labels == "nearest":
        if correlation is None:
            return found.nearest_poke(pokes.xy, cells_xy)
        closest = np.argmax(correlation(cells_xy), axis=1)  # ties: the earliest poke
        return RegionMap(labels=found.poke_labels[closest].reshape(found.labels.shape),
                         levels=found.levels, class_betas=found.class_betas,
                         poke_labels=found.poke_labels)
    if config.region_labels == "indicator-kriging":
        labels = indicator_labels(pokes.xy, found.poke_labels, pokes.noise, cells_xy,
                                  n_classes=found.n_regions, length_scale=settings.length_scale_m,
                                  signal_std=settings.signal_std)  # fmt: skip
        return RegionMap(labels=labels.reshape(found.labels.shape), levels=found.levels,
                         class_betas=found.class_betas, poke_labels=found.poke_labels)
    if found is not by_value:
        return _bands_by_behaviour(by_value, found, pokes.xy, cells_xy)
    return found


def _bands_by_behaviour(by_value: RegionMap, found: RegionMap, poke_xy: NDArray[np.float64],
                        cells_xy: NDArray[np.float64]) -> RegionMap:
    """``found`` (``by_value``'s classes split by behaviour) with each cell in the band of a
    value class labelled by that class's part its nearest poke of the class is in."""
    bands = by_value.labels.reshape(-1)
    labels = found.labels.reshape(-1).copy()  # every band has pokes: each cell is relabelled
    for c in range(by_value.n_regions):
        cells = np.flatnonzero(bands == c)
        members = np.flatnonzero(by_value.poke_labels == c)
        if not cells.size or not members.size:
            continue
        d2 = np.sum((cells_xy[cells, None, :] - poke_xy[None, members, :]) ** 2, axis=-1)
        labels[cells] = found.poke_labels[members[np.argmin(d2, axis=1)]]
    return RegionMap(labels=labels.reshape(by_value.labels.shape), levels=found.levels,
                     class_betas=found.class_betas, poke_labels=found.poke_labels)
