"""Settings of the shape-matching simulator and the β sweep (one frozen dataclass)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from deformap._validation import SettingError, check_settings, setting

__all__ = ["BetaScale", "ContactProtocol", "DeformationMode", "ShapeMatchingConfig", "UncertaintyMethod"]

#: Müller et al.'s deformation modes of a cluster.
DeformationMode = Literal["quadratic", "linear", "rigid"]
#: How the poke enters the simulation (see ``ShapeMatchingConfig.contact``).
ContactProtocol = Literal["force", "pinned"]
#: How ``beta_std`` is obtained (see ``ShapeMatchingConfig.uncertainty``).
UncertaintyMethod = Literal["bootstrap", "tolerance"]
#: What β = 0 is and where the reference sits (see ``ShapeMatchingConfig.beta_scale``).
BetaScale = Literal["odds", "reference"]


@dataclass(frozen=True, kw_only=True)
class ShapeMatchingConfig:
    """Settings of meshless shape matching and of the β estimation.

    Parameters
    ----------
    mode : {"quadratic", "linear", "rigid"}
        Müller et al. (2005) deformation mode of each cluster. ``"rigid"`` ignores β.
    cluster_size : int
        Side ``k`` of the overlapping ``k × k`` particle clusters (every ``k × k`` window of the
        particle grid is a cluster); the paper's best value is 3.
    contact : {"force", "pinned"}
        How the poke enters the simulation. ``"pinned"`` is the paper's protocol: the particle
        nearest the contact is held at its observed displaced position. ``"force"`` applies the
        measured tactile force to the particles under the tip and lets the body find its static
        equilibrium, so that the dent's *depth per newton* (what hardness changes) is simulated
        instead of being copied from the observation. See :func:`~deformap.msm.simulate_poke`.
    n_beta : int
        Number of β values of the coarse uniform sweep ``β_j = j / n_beta`` over ``[0, 1)``
        (solved in increasing order, each started from the β already solved). E(β) is smooth, so
        10 values (a step of 0.1) bracket its minimum; the refinement then finds β̂ to
        ``beta_resolution``.
    refine : bool
        Refine around the sweep's minimum down to ``beta_resolution``: on the
        ``beta_resolution`` grid within one sweep step of the best swept β, solve one grid point
        at a time, at the vertex of the parabola (in ``1 / (1 − β)``) through the lowest β
        solved so far and its neighbours, until the lowest grid point has both grid neighbours
        solved (a few further solves, each started from the equilibria of the nearest β already
        solved).
    beta_resolution : float
        Step of the local refinement (dimensionless).
    tol : float
        Relative fixed-point tolerance: the iteration stops when the largest particle update is
        below ``tol`` times the largest particle displacement from rest (or below ``tol`` times the
        particle spacing when nothing moved). Every β that the refinement compares, and every β
        when ``refine`` is off, is solved to ``tol``.
    sweep_tol : float
        Tolerance of the coarse sweep and of the stiffness calibration when ``refine`` is on (at
        least ``tol``). The sweep only has to bracket the minimum: its E(β) differ by
        micrometres, and ``1e-4`` of a 5 mm dent is 0.5 µm, reached in fewer iterations than
        ``1e-6``. A swept β that the refinement then compares is solved again to ``tol``, started
        from its swept equilibrium.
    max_iter : int
        Iteration cap; a β that hits it is reported as not converged (never silently accepted).
    regularization : float
        Relative eigenvalue cut-off of the (linear 3×3 or quadratic 9×9) moment matrix of each
        cluster, computed on features scaled by the cluster's RMS radius: directions whose moment
        is below ``regularization × largest moment`` (e.g. the ``z`` direction of a flat patch, the
        quadratic terms of a 3×3 cluster that its 9 particles cannot determine) are left out of the
        fit (spectral truncation). The remaining directions are fitted exactly, which keeps the
        rest shape an exact fixed point and affine (linear) / quadratic (quadratic mode)
        deformations exactly reproduced at β = 1.
    reference_modulus_pa : float, pascals
        Force protocol only: the particle spring stiffness ``k`` (N/m) is calibrated per ROI so
        that the body of rigid goals (β = 0's goals) with springs ``k`` dents, under the
        measured force and tip, as deep as an elastic half-space of this Young's modulus
        (Hertz). 100 kPa lies an order of magnitude above the stiffest polyurethane foams (about
        20 kPa for a 250 N hardness) and below rubbers. On the ``"reference"`` scale that body is
        β = 0's; on the ``"odds"`` scale each β's body carries β times the force, and dents β
        times as deep as the reference scale's body of the same β.
    beta_scale : {"odds", "reference"}
        Force protocol only: what β = 0 is. ``"odds"`` (default): each β's springs are ``k /
        β``, so β = 0 is rigid (the paper's "β close to 0, the object behaves like a rigid
        body") and the odds β / (1 − β) is the body's compliance against the reference: β reads
        every stiffness from the softest foam to rigid, with no stiff end short of rigid.
        ``"reference"``: every β's springs are ``k``, β = 0 is the reference body, and β̂ is 0
        for every surface whose dent is shallower than about twice the reference's (39 kPa
        on analytic Hertz dents at 0.6 N; the scale used before issue 13). See
        :mod:`deformap.msm`, "The β scale".
    poisson_ratio : float
        Poisson ratio of that reference half-space (0.5: nearly incompressible, like solid
        rubber; the value only enters through ``E* = E / (1 − ν²)``).
    layers : int or None
        The simulated body. ``0``: the surface sheet of particles of the paper (the ROI's
        heightmap, edges fixed). ``L > 0``: the surface over ``L`` layers of particles below it
        (the same grid in x and y, shifted down; layer spacings grow by ``layer_growth`` and sum
        to half the ROI's smaller side), with the sides and the bottom layer fixed, and clusters
        of ``2 × k × k`` particles spanning two adjacent layers. A dent in an elastic body is
        carried by the material under it; a sheet fixed at its edges can only bend, and its dent
        is a cone as wide as the ROI. ``None`` picks the protocol's default: 0 for ``"pinned"``
        (the paper, faithfully) and 3 for ``"force"``. Half the ROI's side is the depth at which
        the fixed floor is as far from the contact as the fixed sides.
    layer_growth : float
        Ratio of successive layer spacings (≥ 1): fine under the surface where strains are large,
        coarse at depth.
    uncertainty : {"bootstrap", "tolerance"}
        How ``beta_std`` is obtained. ``"bootstrap"`` (default): the spread of β̂ when blocks of
        particles are resampled (:mod:`deformap.msm._uncertainty`) — paired across β, so the
        undisturbed part of the ROI, which adds the same distance at every β, does not blur it.
        ``"tolerance"``: the β interval where E(β) stays within ``error_tolerance_m`` of its
        minimum, its standard deviation (width / √12).
    bootstrap_tile_m : float, metres
        Side of the resampled blocks: 2 cm, twice the tip radius and the touch GP's correlation
        length, so that neighbouring (correlated) particles are resampled together.
    error_tolerance_m : float, metres
        Tolerance on E(β) of the ``"tolerance"`` uncertainty. 0.1 mm is the order of the touch
        GP's mean error on a 0.5 cm grid.
    """

    mode: DeformationMode = "quadratic"
    cluster_size: int = setting(3, ge=2)
    contact: ContactProtocol = "force"
    # each β is one solve of the whole body; 1000 is a step of 0.001, finer than the refinement
    # ever needs from the sweep
    n_beta: int = setting(10, ge=2, le=1000)
    refine: bool = True
    beta_resolution: float = setting(0.01, ge=1e-6, le=0.5)
    tol: float = setting(1e-6, ge=1e-14, lt=1.0)  # below 1e-14 is float64 rounding
    sweep_tol: float = setting(1e-4, ge=1e-14, lt=1.0)
    # the cap is what bounds the time of a β that does not converge (each iteration is a pass
    # over every particle)
    max_iter: int = setting(500, ge=1, le=100_000)
    regularization: float = setting(1e-3, ge=0.0, lt=1.0)
    reference_modulus_pa: float = setting(100e3, gt=0.0)
    beta_scale: BetaScale = "odds"
    poisson_ratio: float = setting(0.5, ge=-1.0, le=0.5)  # the range of an isotropic solid
    uncertainty: UncertaintyMethod = "bootstrap"
    bootstrap_tile_m: float = setting(0.02, gt=0.0)
    error_tolerance_m: float = setting(1e-4, gt=0.0)
    # each layer copies the surface's particles and widens the linear system's band, so memory
    # grows as the square of the layer count: 32 layers is about 70 times the default 3's
    layers: int | None = setting(None, ge=0, le=32)
    layer_growth: float = setting(2.0, ge=1.0, le=10.0)

    @property
    def coarse_tol(self) -> float:
        """Tolerance of the coarse sweep and the calibration: ``sweep_tol`` when the sweep is
        refined (``refine`` and ``beta_resolution`` finer than the sweep's step), else ``tol``."""
        return self.sweep_tol if self.refines else self.tol

    @property
    def refines(self) -> bool:
        """Whether the coarse sweep is refined: ``refine`` and ``beta_resolution < 1 / n_beta``."""
        return self.refine and self.beta_resolution < 1.0 / self.n_beta

    @property
    def rigid_at_zero(self) -> bool:
        """Whether β = 0 is the rigid body: the force protocol on the ``"odds"`` scale (the
        pinned protocol has no load to share, and its β keeps the paper's meaning)."""
        return self.contact == "force" and self.beta_scale == "odds"

    @property
    def body_layers(self) -> int:
        """Layers under the surface actually simulated (``layers``, or the protocol's default)."""
        if self.layers is not None:
            return int(self.layers)
        return 0 if self.contact == "pinned" else 3

    def __post_init__(self) -> None:
        check_settings(self)
        if self.sweep_tol < self.tol:
            raise SettingError(
                "sweep_tol", f"must be >= `tol` ({self.tol:g}); got {self.sweep_tol:g}"
            )
