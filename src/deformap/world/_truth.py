"""What a simulated world is, for scoring the estimator against: each block's label, hardness,
modulus and material parameters on a grid, and the surface's height (:class:`SimulatedWorld`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array
from deformap.world._foam import FoamMesh
from deformap.world._scenario import Block, Scenario

__all__ = ["WorldTruth"]


class WorldTruth:
    """The ground truth of :class:`SimulatedWorld`, which gives its ``scenario`` and ``foam``."""

    scenario: Scenario
    foam: FoamMesh

    @property
    def regions(self) -> tuple[Block, ...]:
        """The blocks, in label order (``.name``, ``.hardness``, ``.modulus_pa``, ``.rigid``)."""
        return self.scenario.blocks

    def ground_truth_labels(self, xs: Any, ys: Any) -> NDArray[np.int64]:
        """``(ny, nx)`` block index at ``(xs[j], ys[i])``; ``-1`` on the bare table."""
        return self.scenario.labels(xs, ys)

    def ground_truth_hardness(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` hardness in N; ``inf`` on rigid blocks and the bare table."""
        return self.scenario.per_block(xs, ys, [b.hardness for b in self.regions])

    def ground_truth_modulus(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` Young's modulus in Pa; ``inf`` on rigid blocks and the bare table."""
        return self.scenario.per_block(xs, ys, [b.modulus_pa for b in self.regions])

    def ground_truth_relaxation_fraction(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` share ``1 − g∞`` of the instantaneous modulus that relaxes: 0 on elastic
        and rigid blocks, NaN on the bare table."""
        return self.scenario.per_block(xs, ys, [
            0.0 if b.viscoelastic is None else b.viscoelastic.relaxation_fraction
            for b in self.regions], table=np.nan)

    def ground_truth_relaxation_time(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` relaxation time in seconds (the arms' times weighted by their moduli);
        NaN where nothing relaxes."""
        return self.scenario.per_block(xs, ys, [
            np.nan if b.viscoelastic is None or b.viscoelastic.relaxation_fraction == 0.0
            else b.viscoelastic.time_constant_s for b in self.regions], table=np.nan)

    def ground_truth_anisotropy_ratio(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` in-plane stiff over soft modulus: 1 on isotropic and rigid blocks, NaN on
        the bare table."""
        return self.scenario.per_block(xs, ys, [
            1.0 if b.anisotropy is None else b.anisotropy.ratio for b in self.regions],
            table=np.nan)

    def ground_truth_anisotropy_axis(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` angle of the stiff in-plane axis from x in degrees, in ``(−90, 90]``;
        NaN where the foam is isotropic."""
        def axis(b: Block) -> float:
            if b.anisotropy is None or b.anisotropy.ratio == 1.0:
                return np.nan
            return float(90.0 - (90.0 - b.anisotropy.axis_deg) % 180.0)
        return self.scenario.per_block(xs, ys, [axis(b) for b in self.regions], table=np.nan)

    def ground_truth_yield_stress(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` initial yield stress in Pa: ``inf`` where nothing yields (elastic and
        rigid blocks, the bare table)."""
        return self.scenario.per_block(xs, ys, [
            np.inf if b.plastic is None else b.plastic.yield_stress_pa for b in self.regions])

    def surface_height(self, xs: Any, ys: Any, displacement: Any = None) -> NDArray[np.float64]:
        """``(ny, nx)`` height of the top surface in metres, deformed vertically by
        ``displacement`` (``Dent.displacement``, ``(n_nodes, 3)``; None: the rest shape)."""
        labels = self.ground_truth_labels(xs, ys)
        thickness = np.array([b.thickness_m for b in self.regions] + [0.0])
        height = thickness[labels]  # label -1 picks the table's 0
        if displacement is not None:
            u = check_array("displacement", displacement, (self.foam.n_nodes, 3), what="metres")
            gx, gy = np.meshgrid(np.asarray(xs, float), np.asarray(ys, float))
            uz = self.foam.top_displacement(np.column_stack([gx.ravel(), gy.ravel()]), u)[:, 2]
            height = height + uz.reshape(height.shape) * (labels >= 0)
        return np.asarray(height)
