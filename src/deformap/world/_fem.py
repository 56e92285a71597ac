"""Linear elasticity of a foam block bonded to a rigid table, on a structured hexahedral mesh.

A block is meshed as a tensor grid: uniform ``dx``, ``dy`` over the bounding box of its footprint
and layers that grow geometrically from the top to the bottom (bonded to the table: displacements
zero). A column of hexes belongs to the block when its centre lies in the footprint. Elements are
trilinear (scikit-fem ``ElementHex1``, 2×2×2 Gauss points) with a per-element Young's modulus.

Every hex of one layer has the same shape, so its stiffness is one 24×24 matrix computed by
scikit-fem for a unit modulus, scaled per element and scattered with numpy. The stiffness is
factorised once (SuperLU); a block of one modulus ``E`` solves ``K₁⁻¹ f / E`` on a unit-modulus
factorisation shared by the homogeneous blocks of that mesh.

References
----------
Gustafsson, T., McBain, G. D. (2020). scikit-fem. Journal of Open Source Software 5(52), 2369.
"""

from __future__ import annotations

import logging
from collections import OrderedDict
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import SuperLU, splu

from deformap.errors import NotPositiveDefiniteError

__all__ = ["FoamBody", "HexGrid", "graded_levels", "orthotropic_hex_stiffness",
           "unit_hex_stiffness"]

log = logging.getLogger(__name__)

# the most recent unit-modulus factorisations (tens of MB each on the default mesh)
_UNIT_FACTORS: OrderedDict[bytes, SuperLU] = OrderedDict()
_UNIT_FACTORS_KEPT = 2

# Corner c = ci + 2 cj + 4 ck of a hex, as offsets (ci, cj, ck) from its lowest node.
_CORNERS = np.array([[c & 1, (c >> 1) & 1, (c >> 2) & 1] for c in range(8)])


def graded_levels(thickness_m: float, top_m: float, growth: float) -> NDArray[np.float64]:
    """``(nz + 1,)`` z levels from 0 to ``thickness_m``, the top layer about ``top_m`` thick and
    the layers growing by ``growth`` going down."""
    sizes = [top_m]
    while (sum(sizes) < thickness_m * (1 - 1e-9)
           and sum(sizes) + sizes[-1] * growth < thickness_m * 1.2):
        sizes.append(sizes[-1] * growth)
    sizes_arr = np.array(sizes[::-1]) * (thickness_m / sum(sizes))
    return np.concatenate([[0.0], np.cumsum(sizes_arr)])


@lru_cache(maxsize=256)
def unit_hex_stiffness(dx: float, dy: float, dz: float, nu: float) -> NDArray[np.float64]:
    """``(24, 24)`` stiffness of a ``dx × dy × dz`` trilinear hex with E = 1 Pa, by scikit-fem,
    ordered ``3 c + component`` with corner ``c = ci + 2 cj + 4 ck``."""
    from skfem import BilinearForm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    form: BilinearForm = linear_elasticity(*lame_parameters(1.0, nu))
    return _hex_matrix(dx, dy, dz, form)


def _hex_matrix(dx: float, dy: float, dz: float, form: Any) -> NDArray[np.float64]:
    """The 24×24 matrix of bilinear ``form`` on one ``dx×dy×dz`` hex (scikit-fem), its rows and
    columns in this module's corner order (3 per corner), read-only."""
    from skfem import Basis, ElementHex1, ElementVectorH1, MeshHex, asm

    mesh = MeshHex.init_tensor(np.array([0.0, dx]), np.array([0.0, dy]), np.array([0.0, dz]))
    basis = Basis(mesh, ElementVectorH1(ElementHex1()))
    k = asm(form, basis).toarray()
    corner_of_node = np.rint(mesh.p.T / np.array([dx, dy, dz])).astype(int)
    ours = corner_of_node[:, 0] + 2 * corner_of_node[:, 1] + 4 * corner_of_node[:, 2]
    perm = np.empty(24, dtype=int)
    perm[(3 * ours[:, None] + np.arange(3)).ravel()] = np.asarray(basis.nodal_dofs).T.ravel()
    out = k[np.ix_(perm, perm)]
    out.setflags(write=False)
    return np.asarray(out)


@lru_cache(maxsize=256)
def orthotropic_hex_stiffness(dx: float, dy: float, dz: float, nu: float, ratio: float,
                              axis_deg: float) -> NDArray[np.float64]:
    """As :func:`unit_hex_stiffness`, of the rotated orthotropic material at unit soft modulus
    (:func:`~deformap.world._materials.orthotropic_stiffness`), by scikit-fem."""
    from skfem import BilinearForm
    from skfem.helpers import ddot, sym_grad

    from deformap.world._materials import orthotropic_stiffness

    tensor = orthotropic_stiffness(ratio, axis_deg, nu)

    @BilinearForm
    def form(u, v, _):
        return ddot(np.einsum("ijkl,kl...->ij...", tensor, sym_grad(u)), sym_grad(v))

    return _hex_matrix(dx, dy, dz, form)


@dataclass(frozen=True, kw_only=True)
class HexGrid:
    """One block's structured mesh: ``nx × ny`` columns of ``dx × dy`` (metres) from ``origin``
    ``(x0, y0)``, node heights ``levels`` ``(nz + 1,)`` from 0 at the table, and the ``(ny, nx)``
    ``active`` columns that belong to the block."""

    origin: NDArray[np.float64]
    dx: float
    dy: float
    nx: int
    ny: int
    levels: NDArray[np.float64]
    active: NDArray[np.bool_]

    @property
    def nz(self) -> int:
        return len(self.levels) - 1

    @property
    def n_nodes(self) -> int:
        return (self.nx + 1) * (self.ny + 1) * (self.nz + 1)

    def node_id(self, i: NDArray[np.int64], j: NDArray[np.int64], k: NDArray[np.int64] | int
                ) -> NDArray[np.int64]:
        return np.asarray((k * (self.ny + 1) + j) * (self.nx + 1) + i)

    def node_xyz(self) -> NDArray[np.float64]:
        """``(n_nodes, 3)`` node coordinates in metres."""
        k, j, i = np.meshgrid(np.arange(self.nz + 1), np.arange(self.ny + 1),
                              np.arange(self.nx + 1), indexing="ij")
        return np.column_stack([self.origin[0] + i.ravel() * self.dx,
                                self.origin[1] + j.ravel() * self.dy, self.levels[k.ravel()]])

    def surface_quads(self) -> NDArray[np.int64]:
        """``(m, 4)`` node ids of the outer faces (top and sides; the bottom lies on the table)."""
        jj, ii = np.nonzero(self.active)
        k_top = np.full_like(ii, self.nz)
        quads = [np.column_stack([self.node_id(ii + a, jj + b, k_top)
                                  for a, b in ((0, 0), (1, 0), (1, 1), (0, 1))])]
        pad = np.pad(self.active, 1)
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            open_side = ~pad[1 + jj + dj, 1 + ii + di]
            si, sj = ii[open_side], jj[open_side]
            # the two nodes of the column's edge on that side, then extruded over every layer
            if di:
                a, b = (si + (di > 0), sj), (si + (di > 0), sj + 1)
            else:
                a, b = (si, sj + (dj > 0)), (si + 1, sj + (dj > 0))
            for k in range(self.nz):
                quads.append(np.column_stack([self.node_id(*a, k), self.node_id(*b, k),
                                              self.node_id(*b, k + 1), self.node_id(*a, k + 1)]))
        return np.concatenate(quads, axis=0)

    def locate(self, xy: NDArray[np.float64]
               ) -> tuple[NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
        """Top-face bilinear interpolation at ``(n, 2)`` points: ``inside`` ``(n,)`` (on an active
        column), the column's top node ids ``(n, 4)`` (corners 00, 10, 01, 11; 0 where not
        inside) and the bilinear weights ``(n, 4)``."""
        u = (xy[:, 0] - self.origin[0]) / self.dx
        v = (xy[:, 1] - self.origin[1]) / self.dy
        i = np.clip(np.floor(u).astype(np.int64), 0, self.nx - 1)
        j = np.clip(np.floor(v).astype(np.int64), 0, self.ny - 1)
        inside = (u >= 0) & (u <= self.nx) & (v >= 0) & (v <= self.ny)
        inside &= self.active[j, i]
        s, t = np.clip(u - i, 0, 1), np.clip(v - j, 0, 1)
        k = np.full_like(i, self.nz)
        nodes = np.column_stack([self.node_id(i, j, k), self.node_id(i + 1, j, k),
                                 self.node_id(i, j + 1, k), self.node_id(i + 1, j + 1, k)])
        weights = np.column_stack([(1 - s) * (1 - t), s * (1 - t), (1 - s) * t, s * t])
        return inside, np.where(inside[:, None], nodes, 0), np.where(inside[:, None], weights, 0.0)


class FoamBody:
    """One elastic block: its mesh, stiffness factorised once, and solves for nodal loads.

    ``anisotropy`` ``(ratio, axis_deg)``: an in-plane orthotropic material
    (:class:`~deformap.world._materials.Orthotropic`) whose soft modulus is ``modulus_pa``; None:
    isotropic. ``modulus_pa`` is Young's modulus, one or ``(nz, ny, nx)`` per element; ``symmetry`` names
    the planes ``"x_min"``/``"y_min"`` of the box held in their normal direction (a quarter of a
    symmetric problem).
    """

    def __init__(self, grid: HexGrid, modulus_pa: float | NDArray[np.float64], *,
                 poisson_ratio: float, symmetry: tuple[str, ...] = (),
                 anisotropy: tuple[float, float] | None = None) -> None:
        self.grid = grid
        self.poisson_ratio = poisson_ratio
        self.anisotropy = anisotropy
        self.modulus = np.broadcast_to(np.asarray(modulus_pa, dtype=float),
                                       (grid.nz, grid.ny, grid.nx))
        self.free = self._free_dofs(symmetry)
        used = self.modulus[:, grid.active]
        uniform = used.size > 0 and bool(np.all(used == used.flat[0]))
        # K₁ is assembled at E = 1 itself, so a solve does not depend on what was built before
        self._scale = 1.0 / float(used.flat[0]) if uniform else 1.0
        factored = self._assemble(np.ones_like(self.modulus) if uniform else self.modulus)
        self.stiffness = factored * float(used.flat[0]) if uniform else factored
        key = self._geometry_key(symmetry) if uniform else None
        cached = None if key is None else _UNIT_FACTORS.get(key)
        if key is not None and cached is not None:
            _UNIT_FACTORS.move_to_end(key)
            self._lu = cached
            return
        k_ff = factored[self.free][:, self.free].tocsc()
        try:
            self._lu = splu(k_ff, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
        except RuntimeError as exc:  # singular: a block that is not held by the table
            raise NotPositiveDefiniteError(
                f"foam stiffness could not be factorised: {exc}") from None
        log.debug("factorised %d DOFs", self.free.size)
        if key is not None:
            _UNIT_FACTORS[key] = self._lu
            while len(_UNIT_FACTORS) > _UNIT_FACTORS_KEPT:
                _UNIT_FACTORS.popitem(last=False)

    def _geometry_key(self, symmetry: tuple[str, ...]) -> bytes:
        """What the unit-modulus stiffness depends on: the mesh, ``ν`` and the held planes."""
        g = self.grid
        head = np.array([*np.asarray(g.origin, dtype=float), g.dx, g.dy, g.nx, g.ny,
                         self.poisson_ratio, *(self.anisotropy or (np.nan, np.nan))], dtype=float)
        return b"|".join([head.tobytes(), np.asarray(g.levels, dtype=float).tobytes(),
                          np.packbits(np.asarray(g.active, dtype=bool)).tobytes(),
                          ",".join(sorted(symmetry)).encode()])

    @property
    def n_dofs(self) -> int:
        """Number of free displacement unknowns."""
        return int(self.free.size)

    def element_dofs(self, k: int
                     ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
        """``(m, 24)`` DOF ids of the hexes of layer ``k`` and their columns ``jj, ii``."""
        g = self.grid
        jj, ii = np.nonzero(g.active)
        nodes = np.column_stack([g.node_id(ii + c[0], jj + c[1], np.full_like(ii, k + c[2]))
                                 for c in _CORNERS])
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(ii), 24)
        return dofs, jj, ii

    def _assemble(self, modulus: NDArray[np.float64]) -> sp.csr_matrix:
        g = self.grid
        n = 3 * g.n_nodes
        total = sp.csr_matrix((n, n))
        for k in range(g.nz):
            dz = float(g.levels[k + 1] - g.levels[k])
            ke = (unit_hex_stiffness(g.dx, g.dy, dz, self.poisson_ratio) if self.anisotropy is None
                  else orthotropic_hex_stiffness(g.dx, g.dy, dz, self.poisson_ratio,
                                                 *self.anisotropy))
            dofs, jj, ii = self.element_dofs(k)
            vals = modulus[k, jj, ii][:, None] * ke.ravel()[None, :]
            rows = np.repeat(dofs, 24, axis=1).ravel()
            cols = np.tile(dofs, (1, 24)).ravel()
            total = total + sp.csr_matrix((vals.ravel(), (rows, cols)), shape=(n, n))
        return total.tocsr()

    def _free_dofs(self, symmetry: tuple[str, ...]) -> NDArray[np.int64]:
        g = self.grid
        used = np.zeros(g.n_nodes, dtype=bool)
        for k in range(g.nz):
            used[self.element_dofs(k)[0][:, ::3] // 3] = True
        xyz = g.node_xyz()
        fixed = np.zeros((g.n_nodes, 3), dtype=bool)
        fixed[~used] = True
        fixed[xyz[:, 2] <= 0.0] = True  # bonded to the table
        if "x_min" in symmetry:
            fixed[np.isclose(xyz[:, 0], g.origin[0]), 0] = True
        if "y_min" in symmetry:
            fixed[np.isclose(xyz[:, 1], g.origin[1]), 1] = True
        return np.flatnonzero(~fixed.ravel())

    def solve_free(self, rhs: NDArray[np.float64]) -> NDArray[np.float64]:
        """``K⁻¹ rhs`` on the free unknowns, ``rhs`` ``(n_dofs,)`` or ``(n_dofs, k)``."""
        # SuperLU copies its right-hand sides into Fortran order (a C-order block twice over)
        out = np.asarray(self._lu.solve(np.asfortranarray(rhs, dtype=float)))
        out *= self._scale
        return out

    def solve(self, nodal_force: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n_nodes, 3)`` displacements in metres for ``(n_nodes, 3)`` nodal forces in newtons."""
        u = np.zeros(3 * self.grid.n_nodes)
        u[self.free] = self.solve_free(nodal_force.ravel()[self.free])
        return u.reshape(-1, 3)
