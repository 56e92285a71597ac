"""A press on a viscoelastic block, solved by the FEM in time.

The block is a generalised Maxwell solid (:class:`~deformap.world._materials.Viscoelastic`): the
stress is ``σ = g∞ σ₀ + Σ_i h_i`` with ``σ₀ = C₀ ε`` the instantaneous elastic stress and ``h_i``
the arms' internal stresses. Implicit time stepping with the recursive update of Simo & Hughes
(1998, §10.3; Taylor, Pister & Goudreau 1970), exact for a strain linear over the step,

    ``h_i⁽ⁿ⁺¹⁾ = e^(−Δt/τ_i) h_i⁽ⁿ⁾ + γ_i (σ₀⁽ⁿ⁺¹⁾ − σ₀⁽ⁿ⁾)``,
    ``γ_i = g_i (1 − e^(−Δt/τ_i)) / (Δt/τ_i)``,

makes each step's equilibrium ``s K₀ u⁽ⁿ⁺¹⁾ = f⁽ⁿ⁺¹⁾ − Σ_i K₀ (e^(−Δt/τ_i) q_i⁽ⁿ⁾ − γ_i u⁽ⁿ⁾)``
with the algorithmic modulus ``s = g∞ + Σ γ_i`` on the block's own stiffness ``K₀`` at ``E₀``.
The kernel is one scalar function for the whole stress and the block is homogeneous, so every
Gauss point's ``h_i`` is ``C₀ ε(q_i)`` of a nodal field ``q_i`` that obeys the same update
(``q_i⁽ⁿ⁺¹⁾ = e^(−Δt/τ_i) q_i⁽ⁿ⁾ + γ_i (u⁽ⁿ⁺¹⁾ − u⁽ⁿ⁾)``): the internal variables are carried
exactly as those fields, and each step is the elastic press solve
(:meth:`~deformap.world._foam.FoamModel.dent`, its Hertz patch iterated to consistency) with
compliance ``1 / s`` and the offset the internal variables leave.

The press is load-controlled: the force follows the protocol's schedule (ramp, force held,
unloading; :mod:`deformap.world._force_travel`), so a hold shows creep (the travel grows at
constant force). Each interval between samples is cut into steps of at most a quarter of the
shortest relaxation time (at most :data:`MAX_SUBSTEPS`). Every press starts from rest: the robot
lets the foam recover between presses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from deformap.world._foam import Dent, FoamModel
from deformap.world._materials import Viscoelastic

__all__ = ["MAX_RECOVERY_STEPS", "MAX_SUBSTEPS", "MaxwellState", "PressHistory", "press_history",
           "recovered"]

#: Most time steps between two samples of the record.
MAX_SUBSTEPS = 8
#: Most time steps of the recovery after the tip has left.
MAX_RECOVERY_STEPS = 400


class MaxwellState:
    """The displacement ``u`` and the arms' fields ``q_i`` of a generalised Maxwell body
    (module docstring), of any shape, from rest."""

    def __init__(self, material: Viscoelastic, shape: tuple[int, ...]) -> None:
        self.g, self.tau = material.prony
        self.g_inf = material.relaxed_ratio
        self.u = np.zeros(shape)
        self.q = np.zeros((self.g.size, *shape))

    def copy(self) -> MaxwellState:
        """An independent copy of the state."""
        out = MaxwellState.__new__(MaxwellState)
        out.g, out.tau, out.g_inf = self.g, self.tau, self.g_inf
        out.u, out.q = self.u.copy(), self.q.copy()
        return out

    def step(self, dt: float) -> tuple[float, NDArray[np.float64], NDArray[np.float64],
                                       NDArray[np.float64]]:
        """For a step of ``dt`` seconds: the compliance ``1 / s``, the offset, each arm's decay and
        ``γ_i`` (``u⁽ⁿ⁺¹⁾ = K₀⁻¹ f / s + offset``)."""
        x = dt / self.tau
        decay = np.exp(-x)
        gamma = self.g * (-np.expm1(-x) / x if dt > 0.0 else np.ones_like(x))
        s = self.g_inf + float(np.sum(gamma))
        offset = -np.tensordot(decay, self.q, axes=1) + float(np.sum(gamma)) * self.u
        return 1.0 / s, offset / s, decay, gamma

    def commit(self, u_new: NDArray[np.float64], decay: NDArray[np.float64],
               gamma: NDArray[np.float64]) -> None:
        """Take ``u_new`` as the step's solution and update the arms' fields."""
        change = u_new - self.u
        self.q = decay.reshape(-1, *[1] * change.ndim) * self.q + np.multiply.outer(gamma, change)
        self.u = u_new.copy()

    def advance_free(self, dt: float) -> None:
        """A step of ``dt`` seconds with no load (the tip gone)."""
        _, offset, decay, gamma = self.step(dt)
        self.commit(offset, decay, gamma)


@dataclass(frozen=True, kw_only=True)
class PressHistory:
    """A viscoelastic press: the true indentation at each sample of the ramp, the hold and the
    unloading (metres), the dent at the end of the hold (what the camera sees while pressing),
    the state when the tip leaves and the time the tip left (seconds on the ramp's clock);
    ``step_times``, ``step_forces`` and ``step_depths`` the time, force and indentation at every
    time step solved."""

    ramp: NDArray[np.float64]
    hold: NDArray[np.float64]
    unloading: NDArray[np.float64]
    step_times: NDArray[np.float64]
    step_forces: NDArray[np.float64]
    step_depths: NDArray[np.float64]
    held: Dent
    state: MaxwellState
    left_s: float


def press_history(foam: FoamModel, material: Viscoelastic, target: NDArray[np.float64], *,
                  times: NDArray[np.float64], forces: NDArray[np.float64], n_ramp: int,
                  n_hold: int, tip_radius_m: float) -> PressHistory:
    """Step the press through the samples ``times`` ``(n,)`` at ``forces`` ``(n,)`` (the ramp's
    ``n_ramp`` samples, then the hold's ``n_hold``, then the unloading's), the force linear in
    time between samples (module docstring)."""
    state = MaxwellState(material, (foam.n_nodes, 3))
    shortest = float(np.min(state.tau))
    depths = np.empty(times.size)
    held: Dent | None = None
    radius: float | None = None
    t_prev, f_prev = 0.0, 0.0
    steps: list[tuple[float, float, float]] = []
    foam.forget()
    for k, (t, f) in enumerate(zip(times, forces, strict=True)):
        span = float(t - t_prev) if k else 0.0
        n_sub = int(min(MAX_SUBSTEPS, max(1, np.ceil(4.0 * span / shortest))))
        for j in range(1, n_sub + 1):
            dt = span / n_sub
            force = f_prev + (float(f) - f_prev) * j / n_sub if k else float(f)
            compliance, offset, decay, gamma = state.step(dt)
            dent = foam.dent(target, force, tip_radius_m=tip_radius_m, initial_radius_m=radius,
                             compliance=compliance, offset=offset)
            assert dent.solved is not None
            state.commit(dent.solved, decay, gamma)
            radius = dent.contact_radius_m or None
            steps.append((t_prev + span * j / n_sub if k else float(t), force, dent.depth_m))
        depths[k] = dent.depth_m
        if k == n_ramp + n_hold - 1:
            held = dent
        t_prev, f_prev = float(t), float(f)
    assert held is not None
    return PressHistory(ramp=depths[:n_ramp], hold=depths[n_ramp:n_ramp + n_hold],
                        unloading=depths[n_ramp + n_hold:], held=held, state=state,
                        left_s=float(times[-1]), step_times=np.array([p[0] for p in steps]),
                        step_forces=np.array([p[1] for p in steps]),
                        step_depths=np.array([p[2] for p in steps]))


def recovered(state: MaxwellState, after_s: float) -> NDArray[np.float64]:
    """The displacement ``after_s`` seconds after the tip left a body in ``state`` (unchanged):
    the load removed at once (the instantaneous elastic spring-back), then free recovery in steps
    of at most a quarter of the shortest relaxation time (at most :data:`MAX_RECOVERY_STEPS`)."""
    free = state.copy()
    free.advance_free(0.0)
    n = int(min(MAX_RECOVERY_STEPS, max(1, np.ceil(4.0 * after_s / float(np.min(free.tau))))))
    if after_s > 0.0:
        for _ in range(n):
            free.advance_free(after_s / n)
    return free.u
