"""The ``stiffening-foam`` physics: each foam block a stiffening two-parameter foundation
(:mod:`deformap.world._foundation`) behind the FEM's interface
(:class:`~deformap.world._foam.FoamModel`), a physics of another kind than the estimator's.

Grid: spacing ``a / 6`` over a core of ±2 ``a`` around the target (``a`` the expected contact
radius; re-gridded when the solved disc spans fewer than 4 or more than 9 cells), cells growing by
1.2 outside it out to 8 ``ℓ`` beyond the core, cut at the block's edge; only the block under the
target is loaded. The press settles the grid, the mode shape's ``γ`` (to 1 %) and the contact
together, a few Newton steps a round, then solves in full. The camera's mesh is displaced by
``u_z = −w φ(z)``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import RegularGridInterpolator
from scipy.special import k0, k1

from deformap.world._foam import Dent, FoamMesh
from deformap.world._foundation import (
    MAX_NEWTON_STEPS,
    FoundationGrid,
    FoundationLayer,
    solve_press,
)
from deformap.world._scenario import Scenario

__all__ = ["StiffeningFoam", "graded_axis", "max_grid_nodes"]

log = logging.getLogger(__name__)

_CORE_CELLS_PER_RADIUS = 6  # grid spacing a / 6 over the contact disc
_CORE_RADII = 2.0  # the uniform core spans ±2 a
_GROWTH = 1.2  # cell growth outside the core
_REACH_LENGTHS = 8.0  # the grid reaches 8 ℓ beyond the core (the dent decays as exp(−r / ℓ))
_MAX_ROUNDS = 12  # solves a press may take to settle its grid and its mode shape
_DECAY_TOLERANCE = 0.01
_SETTLING_STEPS = 3


def graded_axis(center: float, lo: float, hi: float, *, step: float, core: float,
                reach: float) -> NDArray[np.float64]:
    """One axis's nodes: ``step`` apart near ``center``, then growing, cut to ``[lo, hi]``."""
    offsets = list(np.arange(0.0, core + 0.5 * step, step))
    cell = step
    while offsets[-1] < core + reach:
        cell *= _GROWTH
        offsets.append(offsets[-1] + cell)
    half = np.asarray(offsets)
    axis = np.concatenate([center - half[:0:-1], center + half])
    body = axis[(axis > lo) & (axis < hi)]
    # a node closer to a cut end than a third of the cell before it would make a sliver
    if axis[0] <= lo and body.size > 1 and body[0] - lo < (body[1] - body[0]) / 3 \
            and body[0] != center:
        body = body[1:]
    if axis[-1] >= hi and body.size > 1 and hi - body[-1] < (body[-1] - body[-2]) / 3 \
            and body[-1] != center:
        body = body[:-1]
    return np.concatenate([[lo] if axis[0] <= lo else [], body, [hi] if axis[-1] >= hi else []])


def max_grid_nodes(extent_m: NDArray[np.float64], tip_radius_m: float) -> int:
    """Most nodes of a press grid over a block of ``(2,)`` in-plane ``extent_m``: per axis the
    core (``a ≤ sqrt(2) R``) and the graded cells from the finest spacing ``R / 200`` out to the
    block's extent."""
    finest = tip_radius_m / 200
    core = math.ceil(_CORE_RADII * math.sqrt(2.0) * _CORE_CELLS_PER_RADIUS)
    count = 1
    for extent in np.asarray(extent_m, dtype=float):
        rings = math.ceil(math.log1p(extent * (_GROWTH - 1) / finest) / math.log(_GROWTH))
        count *= 2 * (core + rings) + 3
    return count


def _depth_guess(layer: FoundationLayer, force_n: float, tip_radius_m: float) -> float:
    """A first sink: a flat punch of radius ``sqrt(2 R δ)`` on the linear Pasternak layer."""
    k, gp, ell = layer.spring_pa_per_m, layer.shear_n_per_m, layer.influence_length_m
    depth = math.sqrt(force_n / (math.pi * k * tip_radius_m))
    for _ in range(30):  # a damped fixed point: K rises with δ
        a = math.sqrt(2 * tip_radius_m * min(depth, tip_radius_m))
        stiffness = math.pi * a * a * k
        if gp > 0.0:
            stiffness += 2 * math.pi * a * math.sqrt(k * gp) * float(k1(a / ell) / k0(a / ell))
        depth = math.sqrt(depth * 2 * force_n / stiffness)
    return depth


class StiffeningFoam(FoamMesh):
    """All foam blocks of a scenario as stiffening foundations (module docstring) on the display
    mesh of :class:`~deformap.world._foam.FoamMesh`; ``shear`` False: Winkler foundations."""

    def __init__(self, scenario: Scenario, *, element_size_m: float, top_layer_m: float,
                 layer_growth: float, poisson_ratio: float, densification_strain: float,
                 stiffening_exponent: float, shear: bool = True) -> None:
        super().__init__(scenario, element_size_m=element_size_m, top_layer_m=top_layer_m,
                         layer_growth=layer_growth)
        self.layers = {index: FoundationLayer(
            modulus_pa=scenario.blocks[index].modulus_pa, poisson_ratio=poisson_ratio,
            thickness_m=scenario.blocks[index].thickness_m,
            densification_strain=densification_strain,
            stiffening_exponent=stiffening_exponent, shear=shear) for index in self.foam_blocks}
        self.shear = shear

    @property
    def n_dofs(self) -> int:
        """Top nodes of the foam blocks' display meshes (one deflection each)."""
        return sum((self.grids[i].nx + 1) * (self.grids[i].ny + 1) for i in self.layers)

    def forget(self) -> None:
        """Nothing to drop: each press is solved from its own first guess."""

    def dent(self, target_xy: NDArray[np.float64], force_n: float, *, tip_radius_m: float,
             initial_radius_m: float | None = None, max_radius_m: float | None = None) -> Dent:
        """Solve the press of ``force_n`` newtons at ``target_xy`` (module docstring), the first
        grid and mode shape set by ``initial_radius_m`` (default ``sqrt(R δ)`` of
        :func:`_depth_guess`); ``max_radius_m``, the FEM's bracket, is not needed here."""
        del max_radius_m
        target = np.asarray(target_xy, dtype=float).reshape(2)
        index = self.block_at(target)
        if index is None:
            return Dent(displacement=self.zero_displacement(), depth_m=0.0,
                        contact_radius_m=0.0, iterations=0)
        block = self.scenario.blocks[index]
        layer = replace(self.layers[index], decay=1.0) if self.shear else self.layers[index]
        depth = _depth_guess(layer, force_n, tip_radius_m)
        # the contact disc of a dragged surface is smaller than the cap's sqrt(2 R δ)
        radius = (initial_radius_m if initial_radius_m else
                  math.sqrt(tip_radius_m * min(depth, tip_radius_m)))
        if self.shear:
            # a first mode shape: the influence length of a thick layer, H sqrt(G / 2M) / γ, is
            # about the contact radius (as the solved presses find)
            decay = layer.thickness_m * math.sqrt(
                layer.shear_modulus_pa / (2 * layer.constrained_modulus_pa)) / radius
            layer = replace(layer, decay=max(decay, 0.1))
            depth = _depth_guess(layer, force_n, tip_radius_m)
        lo, hi = block.polygon.min(axis=0), block.polygon.max(axis=0)
        finest, coarsest = tip_radius_m / 200, tip_radius_m / _CORE_CELLS_PER_RADIUS
        iterations, field, grid, reach, grid_step = 0, None, None, 0.0, 0.0
        precise = False  # full Newton solves from here on
        for _round in range(_MAX_ROUNDS):
            step = min(max(radius / _CORE_CELLS_PER_RADIUS, finest), coarsest)
            if grid is None or not math.isclose(step, grid_step) or \
                    layer.influence_length_m * _REACH_LENGTHS > reach:
                grid_step = step
                reach = 1.5 * _REACH_LENGTHS * layer.influence_length_m + 2 * step
                axes = [graded_axis(float(target[d]), float(lo[d]), float(hi[d]), step=step,
                                    core=_CORE_RADII * radius, reach=reach) for d in (0, 1)]
                grid = FoundationGrid.build(block, *axes)
            start = (np.zeros(len(grid.xy)) if field is None else field(grid.xy[:, ::-1]),
                     np.sum((grid.xy - target) ** 2, axis=1) <= radius**2)
            # while the grid and the mode shape settle, a few Newton steps a round; then in full
            result = solve_press(layer, grid, target, force_n, tip_radius_m, depth, start,
                                 max_steps=MAX_NEWTON_STEPS if precise else _SETTLING_STEPS)
            iterations += result.iterations
            depth = result.depth_m
            solved = math.sqrt(float(grid.area[result.active].sum()) / math.pi)
            field = self._field(grid, result.w)
            fits = (4 * step <= solved <= 9 * step or (step == finest and solved < 4 * step)
                    or (step == coarsest and solved > 9 * step))
            decay = layer.decay_for(result.w, grid) if self.shear else 0.0
            change = abs(decay - layer.decay) / max(layer.decay, 1.0)
            log.debug("foundation press: a=%.5f m, δ=%.5f m, γ=%.3f", solved, depth, decay)
            # done when a converged solve on a fitting grid asks for the mode shape it had
            if fits and change <= _DECAY_TOLERANCE and result.converged:
                break
            precise = precise or (fits and change <= 10 * _DECAY_TOLERANCE)
            if not fits:
                radius = solved
            layer = replace(layer, decay=decay)
        else:
            log.warning("foundation press at %s, %.3g N: the grid or the mode shape did not "
                        "settle in %d solves", target, force_n, _MAX_ROUNDS)
        assert grid is not None  # _MAX_ROUNDS ≥ 1
        return Dent(displacement=self._displace(layer, index, result.w, grid),
                    depth_m=result.depth_m, contact_radius_m=min(solved, tip_radius_m),
                    iterations=iterations)

    @staticmethod
    def _field(grid: FoundationGrid, w: NDArray[np.float64]) -> RegularGridInterpolator:
        """The deflection as a function of ``(n, 2)`` points ``(y, x)`` (0 off the grid)."""
        full = np.zeros(grid.x.size * grid.y.size)
        full[grid.used] = w
        return RegularGridInterpolator((grid.y, grid.x), full.reshape(grid.y.size, grid.x.size),
                                       bounds_error=False, fill_value=0.0)

    def _displace(self, layer: FoundationLayer, index: int, w: NDArray[np.float64],
                  grid: FoundationGrid) -> NDArray[np.float64]:
        """The display mesh's displacement: ``u_z = −w φ(z)`` in the pressed block."""
        field = self._field(grid, w)
        u = self.zero_displacement()
        off, hex_grid = self.offsets[index], self.grids[index]
        xyz = self.rest_nodes[off:off + hex_grid.n_nodes]
        u[off:off + hex_grid.n_nodes, 2] = -field(xyz[:, [1, 0]]) * layer.mode(xyz[:, 2])[0]
        return u
