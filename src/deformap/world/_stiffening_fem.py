"""The ``stiffening-fem`` physics: the FEM's foam blocks made of the foam that stiffens toward
densification (:mod:`deformap.world._densification`), each press's equilibrium found by Newton's
method, never refactorising.

Force control and the patch iteration are the FEM's (:class:`~deformap.world._foam.FoamModel`).
Each patch's equilibrium ``K₀ u + C s(Cᵀu) = f`` (``s = V Φ'``): the near set (the elements the
linear press would stiffen by more than 5 %, 8 to ``near_elements`` of them) takes its tangent
exactly by a Woodbury update ``Z = K₀⁻¹ C_N`` (a dense ``n × n`` Newton system); the other
elements' forces are an outer fixed point (Anderson-accelerated, Walker & Ni 2011), one ``K₀``
solve a round, and an element compressed past ``ε_d / 5`` joins the near set. Converged when the
residual over every free unknown is below ``tolerance · F``.

References
----------
Walker, H. F., Ni, P. (2011). Anderson acceleration for fixed-point iterations. SINUM 49(4).
"""

from __future__ import annotations

import logging
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from deformap.world._densification import (
    StrainOperator,
    strain_operator,
    volumetric_stress,
    volumetric_tangent,
)
from deformap.world._foam import FoamModel
from deformap.world._scenario import Scenario

__all__ = ["StiffeningFem"]

log = logging.getLogger(__name__)

_MAX_ROUNDS = 60  # outer rounds (one K₀ solve each) a patch may take
_MAX_NEWTON = 60  # Newton steps of one round's near-field solve
_JOIN_STRAIN = 0.2  # a far element past this fraction of ε_d joins the near set
_TARGETS_KEPT = 2  # near sets (with their K₀⁻¹ C_N) kept, the most recent
# an element the linear press would stiffen by less than this (Φ'' / M₀) is left to the outer
# rounds, which then shrink the residual by about as much each; the near set has at least a few
_NEAR_STIFFENING = 0.05
_NEAR_LEAST = 8


@dataclass
class _NearSet:
    """A target's near set with ``Z = K₀⁻¹ C_N``, ``G = C_Nᵀ Z`` and its last solves."""

    elements: NDArray[np.int64]
    columns: sp.csc_matrix  # C_N
    z: NDArray[np.float64]
    g: NDArray[np.float64]
    #: the target's last two solves: (force, far elements' forces, near elements' strains)
    solved: list[tuple[float, NDArray[np.float64], NDArray[np.float64]]] = field(
        default_factory=list)

    def predict(self, force: float, size: int
                ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
        """Far forces and near strains at ``force``, scaled from the last solves as its powers."""
        if not self.solved:
            return np.zeros(size), None
        f1, far1, eps1 = self.solved[-1]
        powers = [2.0, 1.0]
        if len(self.solved) == 2 and not np.isclose(self.solved[0][0], f1):
            f0, far0, eps0 = self.solved[0]
            for i, (a, b) in enumerate(((far0, far1), (eps0, eps1))):
                na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
                if na > 0.0 and nb > 0.0:
                    powers[i] = float(np.clip(np.log(nb / na) / np.log(f1 / f0), 0.5, 4.0))
        return far1 * (force / f1) ** powers[0], eps1 * (force / f1) ** powers[1]

    def remember(self, force: float, far: NDArray[np.float64], eps: NDArray[np.float64]) -> None:
        if self.solved and np.isclose(self.solved[-1][0], force):
            self.solved.pop()  # a patch iteration of the same level: keep its settled solve
        self.solved = [*self.solved[-1:], (force, far, eps)]


class StiffeningFem(FoamModel):
    """All foam blocks of a scenario as FEM bodies of the stiffening foam (module docstring).

    ``near_elements``: 48 bounds each Newton step's dense system to 48 × 48. ``tolerance``: 1e-4
    of the force keeps the force–travel record's error far below the encoders' noise.
    """

    def __init__(self, scenario: Scenario, *, element_size_m: float, top_layer_m: float,
                 layer_growth: float, poisson_ratio: float, densification_strain: float,
                 stiffening_exponent: float, near_elements: int = 48,
                 tolerance: float = 1e-4) -> None:
        super().__init__(scenario, element_size_m=element_size_m, top_layer_m=top_layer_m,
                         layer_growth=layer_growth, poisson_ratio=poisson_ratio)
        self.densification_strain = densification_strain
        self.stiffening_exponent = stiffening_exponent
        self.near_elements = near_elements
        self.tolerance = tolerance
        self.operators = {index: strain_operator(body) for index, body in self.bodies.items()}
        self._near: OrderedDict[tuple[int, bytes], _NearSet] = OrderedDict()

    def _law(self, strain: NDArray[np.float64], op: StrainOperator, elements: NDArray[np.int64],
             tangent: bool = False) -> NDArray[np.float64]:
        """``V Φ'`` (or ``V Φ''``) of ``elements`` at their ``strain``: element forces [N]."""
        f = volumetric_tangent if tangent else volumetric_stress
        return op.volume[elements] * f(strain, op.constrained_pa[elements],
                                       densification=self.densification_strain,
                                       exponent=self.stiffening_exponent)

    def _respond(self, index: int, load: NDArray[np.float64], center: NDArray[np.float64]
                 ) -> NDArray[np.float64]:
        body = self.bodies[index]
        f = load.ravel()[body.free]
        force = float(-f.sum())
        if self.stiffening_exponent == 0.0 or force <= 0.0:  # the linear FEM's response
            return super()._respond(index, load, center)
        u = np.zeros(3 * body.grid.n_nodes)
        u[body.free] = self._solve(index, f, force, center)
        return u.reshape(-1, 3)

    def _with_columns(self, index: int, near: _NearSet, extra: NDArray[np.int64]) -> _NearSet:
        """``near`` with the elements ``extra`` added: their ``K₀⁻¹ cₑ`` in one solve call."""
        op, body = self.operators[index], self.bodies[index]
        elements = np.concatenate([near.elements, extra])
        columns = op.matrix[:, elements]
        z = np.hstack([near.z, body.solve_free(op.matrix[:, extra].toarray())])
        g = columns.T @ z
        log.debug("stiffening FEM: near set of %d elements", elements.size)
        return _NearSet(elements, columns, z, 0.5 * (g + g.T))

    def forget(self) -> None:
        """Drop the unit responses, near sets and warm starts earlier presses left."""
        super().forget()
        self._near.clear()

    def _solve(self, index: int, f: NDArray[np.float64], force: float,
               center: NDArray[np.float64]) -> NDArray[np.float64]:
        """Block ``index``'s free displacements in equilibrium with the free nodal forces ``f``."""
        op, body = self.operators[index], self.bodies[index]
        key = (index, np.asarray(center, dtype=float).tobytes())
        near = self._near.get(key)
        linear = None
        if near is None:  # the target's first press: the linear response picks the near set
            linear = body.solve_free(f)
            near = self._near_set(index, linear)
            self._near[key] = near
            while len(self._near) > _TARGETS_KEPT:
                self._near.popitem(last=False)
        self._near.move_to_end(key)
        far, eps = near.predict(force, f.size)
        history: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
        residual = np.inf
        for rounds in range(1, _MAX_ROUNDS + 1):
            # the first round of a new target has no far forces yet: its linear response
            response = linear if linear is not None and rounds == 1 else body.solve_free(f - far)
            eps = solved = self._newton(near.columns.T @ response, near, op, eps)
            u = response - near.z @ self._law(eps, op, near.elements)
            strain = op.matrix.T @ u
            stress = self._law(strain, op, np.arange(strain.size))
            stress[near.elements] = 0.0
            hard = np.flatnonzero(strain > _JOIN_STRAIN * self.densification_strain)
            joining = hard[stress[hard] != 0.0]
            if joining.size:  # a far element compressed hard: its tangent is taken exactly too
                near = self._with_columns(index, near, joining)
                self._near[key] = near
                eps, history = None, []
                continue
            new_far = op.matrix @ stress
            residual = float(np.linalg.norm(new_far - far))
            if residual <= self.tolerance * force:
                break
            far = _anderson(far, new_far, history)
        else:
            log.warning("stiffening FEM: the press did not converge in %d rounds (residual "
                        "%.3g N at %.3g N)", _MAX_ROUNDS, residual, force)
        near.remember(force, far, solved)
        return u

    def _near_set(self, index: int, linear: NDArray[np.float64]) -> _NearSet:
        """The near set of the linear response ``linear`` (module docstring)."""
        op = self.operators[index]
        strain = op.matrix.T @ linear
        order = np.argsort(strain)[::-1][:min(self.near_elements, strain.size)]
        stiffening = volumetric_tangent(strain[order], np.ones(order.size),
                                        densification=self.densification_strain,
                                        exponent=self.stiffening_exponent)
        count = max(int(np.count_nonzero(stiffening > _NEAR_STIFFENING)),
                    min(_NEAR_LEAST, order.size))
        chosen = np.sort(order[:count])
        empty = _NearSet(np.zeros(0, dtype=np.int64), op.matrix[:, :0],
                         np.zeros((linear.size, 0)), np.zeros((0, 0)))
        return self._with_columns(index, empty, chosen)

    def _newton(self, b: NDArray[np.float64], near: _NearSet, op: StrainOperator,
                start: NDArray[np.float64] | None) -> NDArray[np.float64]:
        """The near strains with ``ε − b + G s(ε) = 0``, by Newton's method with halved steps."""
        cap, g, elements = self.densification_strain, near.g, near.elements
        eps = np.minimum(b, 0.5 * cap) if start is None or start.size != b.size else start
        eps = np.minimum(eps, 0.999 * cap)

        def residual(e: NDArray[np.float64]) -> NDArray[np.float64]:
            return e - b + g @ self._law(e, op, elements)

        r = residual(eps)
        norm = float(np.linalg.norm(r))
        scale = max(float(np.abs(b).max()), 1e-12)
        for _ in range(_MAX_NEWTON):
            if norm <= 1e-13 * scale:
                return eps
            jac = np.eye(b.size) + g * self._law(eps, op, elements, tangent=True)[None, :]
            delta = np.linalg.solve(jac, -r)
            alpha = 1.0
            while True:
                trial = eps + alpha * delta
                if np.all(trial < cap):
                    r_trial = residual(trial)
                    n_trial = float(np.linalg.norm(r_trial))
                    if n_trial < norm or alpha < 1e-6:
                        break
                elif alpha < 1e-6 or not np.all(np.isfinite(delta)):
                    # no step keeps the strains below densification, or the step is not a number
                    log.warning("stiffening FEM: the near-field Newton step is not usable "
                                "(residual %.3g); the last strains are kept", norm)
                    return eps
                alpha *= 0.5
            eps, r, norm = trial, r_trial, n_trial
        log.warning("stiffening FEM: the near-field Newton solve stopped at %.3g", norm)
        return eps


_ANDERSON_DEPTH = 3


def _anderson(x: NDArray[np.float64], fx: NDArray[np.float64],
              history: list[tuple[NDArray[np.float64], NDArray[np.float64]]]
              ) -> NDArray[np.float64]:
    """The next iterate of ``x = T(x)`` by Anderson mixing over ``history`` (updated)."""
    history.append((x, fx))
    del history[:-(_ANDERSON_DEPTH + 1)]
    if len(history) < 2:
        return fx
    gaps = [t - y for y, t in history]
    d_gap = np.column_stack([gaps[i + 1] - gaps[i] for i in range(len(gaps) - 1)])
    d_t = np.column_stack([history[i + 1][1] - history[i][1] for i in range(len(gaps) - 1)])
    gamma = np.linalg.lstsq(d_gap, gaps[-1], rcond=None)[0]
    return np.asarray(fx - d_t @ gamma)
