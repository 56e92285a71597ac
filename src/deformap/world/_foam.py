"""The foam of a whole scenario: one elastic body per foam block, pressed by the probe.

Each foam block is its own :class:`~deformap.world._fem.FoamBody` (neighbouring blocks are not
glued). A press puts the Hertz pressure of the commanded force on the top surface under the tip
(on rigid ground it loads no foam). Inside the contact the surface follows the sphere, so the
pressure-weighted mean FEM displacement ``ū_p`` gives the indentation ``δ = ū_p + 0.2 a² / R``;
after the solve the top nodes inside the contact disc are put on the tip's cap.

The patch radius iterates ``a ← sqrt(a · sqrt(R δ_FEM))`` (a damped fixed point of ``a² = R δ``)
from the Hertz value until it changes by less than 2 %, at most the tip radius (or
``max_radius_m``), bisecting the bracket the solves set where a step would leave it (``δ(a)`` jumps
at a seam). A press's first solve computes the unit responses ``K⁻¹ e_z`` of the top nodes under
the tip in one call; its patch iterations and load levels are sums of them.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap.mechanics import hertz_contact_radius, hertz_pressure_samples
from deformap.world._fem import FoamBody, HexGrid, graded_levels
from deformap.world._scenario import Block, Scenario

__all__ = ["Dent", "FoamMesh", "FoamModel", "block_grid"]

log = logging.getLogger(__name__)

# past this many unit responses under the tip, or MAX_UNIT_BYTES of them a body, they would cost
# more than the solves they replace, and each load is solved as it comes
MAX_UNIT_COLUMNS = 48
MAX_UNIT_BYTES = 64 * 2**20
_MAX_ITERATIONS = 40  # patch iterations a press may take
_TOLERANCE = 0.02  # relative change of the patch radius that ends them


@dataclass(frozen=True, kw_only=True)
class Dent:
    """The foam's response to one press: the ``(n_nodes, 3)`` ``displacement`` (metres) of every
    mesh node (all bodies stacked), the tip's indentation ``depth_m`` below the rest surface, the
    loaded patch's ``contact_radius_m`` (both 0 on rigid ground) and the solves it took;
    ``solved``, where given, is the FEM's displacement before the contact disc is put on the tip's
    cap (what a time-stepping material carries to its next step)."""

    displacement: NDArray[np.float64]
    depth_m: float
    contact_radius_m: float
    iterations: int
    solved: NDArray[np.float64] | None = None


def block_grid(block: Block, *, element_size_m: float, top_layer_m: float,
               layer_growth: float) -> HexGrid:
    """The structured mesh of one block (:mod:`deformap.world._fem`)."""
    lo, hi = block.polygon.min(axis=0), block.polygon.max(axis=0)
    nx, ny = (max(1, int(np.ceil((hi[d] - lo[d]) / element_size_m - 1e-9))) for d in (0, 1))
    dx, dy = (hi[0] - lo[0]) / nx, (hi[1] - lo[1]) / ny
    cx, cy = np.meshgrid(lo[0] + (np.arange(nx) + 0.5) * dx, lo[1] + (np.arange(ny) + 0.5) * dy)
    active = block.contains(np.column_stack([cx.ravel(), cy.ravel()])).reshape(ny, nx)
    levels = graded_levels(block.thickness_m, min(top_layer_m, block.thickness_m), layer_growth)
    return HexGrid(origin=lo.copy(), dx=dx, dy=dy, nx=nx, ny=ny, levels=levels, active=active)


def _anisotropy(block: Block) -> tuple[float, float] | None:
    a = block.anisotropy
    return None if a is None else (a.ratio, a.axis_deg)


class FoamMesh:
    """The structured hexahedral meshes of a scenario's blocks, stacked: what the camera sees
    and every contact physics displaces (in-plane ``element_size_m``, top layer ``top_layer_m``,
    layers growing by ``layer_growth`` downwards)."""

    def __init__(self, scenario: Scenario, *, element_size_m: float, top_layer_m: float,
                 layer_growth: float) -> None:
        self.scenario = scenario
        self.grids: list[HexGrid] = []
        self.offsets: list[int] = []
        n = 0
        for block in scenario.blocks:
            grid = block_grid(block, element_size_m=element_size_m, top_layer_m=top_layer_m,
                              layer_growth=layer_growth)
            self.grids.append(grid)
            self.offsets.append(n)
            n += grid.n_nodes
        self.n_nodes = n
        self.rest_nodes = np.concatenate([g.node_xyz() for g in self.grids])
        self.foam_blocks = tuple(i for i, b in enumerate(scenario.blocks) if not b.rigid)

    def zero_displacement(self) -> NDArray[np.float64]:
        return np.zeros((self.n_nodes, 3))

    def block_at(self, target: NDArray[np.float64]) -> int | None:
        """Index of the foam block under the ``(2,)`` point, None on rigid ground."""
        index = int(self.scenario.labels(target[:1], target[1:])[0, 0])
        return index if index in self.foam_blocks else None

    def top_displacement(self, xy: NDArray[np.float64], displacement: NDArray[np.float64]
                         ) -> NDArray[np.float64]:
        """``(n, 3)`` displacement of the top surface at ``(n, 2)`` points (0 off the foam)."""
        out = np.zeros((len(xy), 3))
        claimed = np.zeros(len(xy), dtype=bool)
        for index in self.foam_blocks:
            grid, off = self.grids[index], self.offsets[index]
            inside, nodes, weights = grid.locate(xy)
            inside &= ~claimed
            u = displacement[off + nodes[inside]]  # (m, 4, 3)
            out[inside] = np.einsum("mc,mcd->md", weights[inside], u)
            claimed |= inside
        return out


class FoamModel(FoamMesh):
    """All foam bodies of a scenario as linear-elastic FEM, with the press solve (module
    docstring); the mesh as in :class:`FoamMesh`."""

    def __init__(self, scenario: Scenario, *, element_size_m: float, top_layer_m: float,
                 layer_growth: float, poisson_ratio: float) -> None:
        super().__init__(scenario, element_size_m=element_size_m, top_layer_m=top_layer_m,
                         layer_growth=layer_growth)
        self.poisson_ratio = poisson_ratio
        self.bodies: dict[int, FoamBody] = {
            index: FoamBody(self.grids[index], scenario.blocks[index].modulus_pa,
                            poisson_ratio=poisson_ratio, anisotropy=_anisotropy(scenario.blocks[index]))
            for index in self.foam_blocks}
        self.max_unit_columns = MAX_UNIT_COLUMNS
        # the press's unit responses per body: (K⁻¹ columns, column of each free unknown or -1)
        self._columns: dict[int, tuple[NDArray[np.float64], NDArray[np.int64]]] = {}
        self._reach: tuple[NDArray[np.float64], float] | None = None  # the tip's disc

    @property
    def n_dofs(self) -> int:
        """Free displacement unknowns over all foam bodies."""
        return sum(b.n_dofs for b in self.bodies.values())

    def forget(self) -> None:
        """Drop what earlier presses left to warm-start the next (the unit responses)."""
        self._columns.clear()
        self._reach = None

    def dent(self, target_xy: NDArray[np.float64], force_n: float, *, tip_radius_m: float,
             initial_radius_m: float | None = None, max_radius_m: float | None = None,
             compliance: float = 1.0, offset: NDArray[np.float64] | None = None) -> Dent:
        """Solve the press of ``force_n`` newtons at ``target_xy`` (module docstring), the patch
        iteration started at ``initial_radius_m`` (default Hertz's) and bounded by
        ``max_radius_m`` (default the tip's radius).

        A time step of a viscoelastic block (:mod:`deformap.world._viscoelastic`) solves
        ``u = compliance · K₀⁻¹ f + offset``: its algorithmic compliance and the displacement its
        internal variables leave; the defaults are the elastic press."""
        target = np.asarray(target_xy, dtype=float).reshape(1, 2)
        if self._reach is None or not np.array_equal(self._reach[0], target[0]):
            self._columns.clear()  # another target's unit responses: a press starts afresh
        index = self.block_at(target[0])
        if index is None:
            return Dent(displacement=self.zero_displacement(), depth_m=0.0,
                        contact_radius_m=0.0, iterations=0)
        top = tip_radius_m if not max_radius_m or max_radius_m <= 0.0 else min(
            float(max_radius_m), tip_radius_m)
        if initial_radius_m is not None and initial_radius_m > 0.0:
            a = min(float(initial_radius_m), top)
        else:
            modulus = self.scenario.blocks[index].modulus_pa / compliance
            a = min(hertz_contact_radius(force_n, tip_radius_m, modulus, self.poisson_ratio), top)
        self._reach = (target[0].copy(), float(top))
        low, high = 0.0, top  # the fixed point lies in [low, high]
        for iteration in range(1, _MAX_ITERATIONS + 1):
            u, points, forces = self._solve_patch(target[0], a, force_n)
            if compliance != 1.0:
                u *= compliance
            if offset is not None:
                u += offset
            mean_u = -float(forces @ self.top_displacement(points, u)[:, 2]) / force_n
            depth = max(0.0, mean_u + 0.2 * a * a / tip_radius_m)
            consistent = float(np.sqrt(tip_radius_m * depth))  # the radius this sink touches
            if consistent > a:
                low = a
            else:
                high = a
            a_new = min(float(np.sqrt(a * consistent)), top)
            if not low < a_new < high:  # would leave the bracket: bisect it
                a_new = 0.5 * (low + high)
            converged = abs(a_new - a) <= _TOLERANCE * a or high - low <= _TOLERANCE * a
            log.debug("press iteration %d: a=%.4f m, depth=%.4f m", iteration, a, depth)
            if converged or iteration == _MAX_ITERATIONS:
                break
            a = a_new
        solved = u.copy() if offset is not None else None
        self._conform_to_tip(u, target[0], a, depth, tip_radius_m)
        return Dent(displacement=u, depth_m=depth, contact_radius_m=float(a), iterations=iteration,
                    solved=solved)

    def _conform_to_tip(self, u: NDArray[np.float64], center: NDArray[np.float64], radius: float,
                        depth: float, tip_radius_m: float) -> None:
        for index in self.bodies:
            grid, off = self.grids[index], self.offsets[index]
            xyz = self.rest_nodes[off:off + grid.n_nodes]
            r2 = np.sum((xyz[:, :2] - center) ** 2, axis=1)
            top = np.isclose(xyz[:, 2], grid.levels[-1]) & (r2 < radius**2)
            top &= np.any(u[off:off + grid.n_nodes] != 0.0, axis=1)  # nodes of the block only
            cap = -depth + tip_radius_m - np.sqrt(tip_radius_m**2 - r2[top])
            u[off + np.flatnonzero(top), 2] = cap

    def _solve_patch(self, center: NDArray[np.float64], radius: float, force_n: float
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        points, forces = hertz_pressure_samples(center, radius, force_n)
        u = self.zero_displacement()
        claimed = np.zeros(len(points), dtype=bool)
        for index in self.bodies:
            grid, off = self.grids[index], self.offsets[index]
            inside, nodes, weights = grid.locate(points)
            inside &= ~claimed
            claimed |= inside
            if not inside.any():
                continue
            load = np.zeros((grid.n_nodes, 3))
            np.add.at(load[:, 2], nodes[inside].ravel(),
                      -(weights[inside] * forces[inside, None]).ravel())
            u[off:off + grid.n_nodes] = self._respond(index, load, center)
        return u, points, forces

    def _respond(self, index: int, load: NDArray[np.float64], center: NDArray[np.float64]
                 ) -> NDArray[np.float64]:
        """Block ``index``'s displacement under nodal forces ``load`` centred at ``center``."""
        body = self.bodies[index]
        f = load.ravel()[body.free]
        loaded = np.flatnonzero(f)
        columns = self._unit_columns(index, loaded)
        if columns is None:
            return body.solve(load)
        z, where = columns
        coefficients = np.zeros(z.shape[1])
        coefficients[where[loaded]] = f[loaded]
        u = np.zeros(3 * body.grid.n_nodes)
        u[body.free] = z @ coefficients
        return u.reshape(-1, 3)

    def _unit_columns(self, index: int, loaded: NDArray[np.int64]
                      ) -> tuple[NDArray[np.float64], NDArray[np.int64]] | None:
        """Body ``index``'s unit responses to ``loaded`` (and :meth:`_under_tip`), or None."""
        body = self.bodies[index]
        z, where = self._columns.get(index, (np.zeros((body.n_dofs, 0)),
                                             np.full(body.n_dofs, -1, dtype=np.int64)))
        wanted = loaded if z.shape[1] else np.union1d(loaded, self._under_tip(index))
        missing = wanted[where[wanted] < 0]
        n_columns = z.shape[1] + missing.size
        if n_columns > self.max_unit_columns or 8 * n_columns * body.n_dofs > MAX_UNIT_BYTES:
            return None
        if missing.size:
            unit = np.zeros((body.n_dofs, missing.size), order="F")
            unit[missing, np.arange(missing.size)] = 1.0
            solved = body.solve_free(unit)  # before `where` changes: a failed solve leaves it
            where[missing] = z.shape[1] + np.arange(missing.size)
            z = np.hstack([z, solved])  # the old and new columns both, for a moment
            self._columns[index] = (z, where)
        return z, where

    def _under_tip(self, index: int) -> NDArray[np.int64]:
        """Positions in ``free`` of the top nodes' vertical unknowns the tip's disc reaches."""
        if self._reach is None:
            return np.zeros(0, dtype=np.int64)
        (cx, cy), radius = self._reach
        grid, body = self.grids[index], self.bodies[index]
        x0 = grid.origin[0] + np.arange(grid.nx) * grid.dx
        y0 = grid.origin[1] + np.arange(grid.ny) * grid.dy
        gap_x = np.maximum.reduce([x0 - cx, np.zeros_like(x0), cx - (x0 + grid.dx)])
        gap_y = np.maximum.reduce([y0 - cy, np.zeros_like(y0), cy - (y0 + grid.dy)])
        near = (gap_y[:, None] ** 2 + gap_x[None, :] ** 2 < radius**2) & grid.active
        jj, ii = np.nonzero(near)
        nodes = np.concatenate([grid.node_id(ii + c0, jj + c1, grid.nz)
                                for c0 in (0, 1) for c1 in (0, 1)])
        dofs = np.unique(3 * nodes + 2)
        at = np.clip(np.searchsorted(body.free, dofs), 0, body.free.size - 1)
        return at[body.free[at] == dofs]
