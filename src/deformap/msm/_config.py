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
        Deformation mode of each cluster (Müller et al. 2005); ``"rigid"`` ignores β.
    cluster_size : int
        Side ``k`` of the overlapping ``k × k`` particle clusters (every ``k × k`` window of the
        particle grid). 3 is the paper's best value.
    contact : {"force", "pinned"}
        How the poke enters the simulation. ``"pinned"``, the paper's protocol, holds the particle
        nearest the contact at its observed position; ``"force"`` applies the measured force to the
        particles under the tip and solves the static equilibrium, so that the dent's depth per
        newton is simulated, not copied (:func:`~deformap.msm.simulate_poke`).
    n_beta : int
        Number of β of the coarse sweep ``β_j = j / n_beta`` over ``[0, 1)``, each solved from the
        β already solved. E(β) is smooth, so 10 values bracket its minimum.
    refine : bool
        Refine β̂ around the sweep's minimum on the ``beta_resolution`` grid. A parabolic search
        (in ``1 / (1 − β)``) within one sweep step solves one grid point at a time until the lowest
        has both grid neighbours solved.
    beta_resolution : float
        Step of the local refinement (dimensionless).
    tol : float
        Relative fixed-point tolerance of every β the refinement compares. Iteration stops when the
        largest particle update is below ``tol`` times the largest displacement from rest (or the
        particle spacing when nothing moved).
    sweep_tol : float
        Tolerance of the coarse sweep and of the stiffness calibration when ``refine`` is on (at
        least ``tol``). The sweep only brackets the minimum; a swept β the refinement compares is
        solved again to ``tol``.
    max_iter : int
        Iteration cap; a β that hits it is reported as not converged, never silently accepted.
    regularization : float
        Relative eigenvalue cut-off of each cluster's moment matrix. Directions below
        ``regularization × largest moment`` (features scaled by the cluster's RMS radius) are left
        out of the fit, so the rest shape stays an exact fixed point and affine / quadratic
        deformations are reproduced exactly at β = 1.
    reference_modulus_pa : float, pascals
        Young's modulus of the elastic half-space whose Hertz dent calibrates the spring stiffness
        ``k`` (force protocol only). 100 kPa lies above the stiffest polyurethane foams and below
        rubbers.
    beta_scale : {"odds", "reference"}
        What β = 0 is (force protocol only). ``"odds"``: each β's springs are ``k / β``, so β = 0
        is rigid (the paper's meaning) and β / (1 − β) is the compliance against the reference;
        ``"reference"``: every β's springs are ``k`` and β = 0 is the reference body, so β̂ is 0
        for every surface about as stiff as the reference or stiffer (:mod:`deformap.msm`).
    poisson_ratio : float
        Poisson's ratio of the reference half-space; it enters only through ``E / (1 − ν²)``.
    layers : int or None
        Layers of particles under the surface sheet; ``None`` picks 0 for ``"pinned"`` and 3 for
        ``"force"``. Sides and bottom are fixed, spacings grow by ``layer_growth`` and sum to half
        the ROI's smaller side, and clusters span two layers; ``0`` is the paper's sheet, which,
        fixed at its edges, can only bend.
    layer_growth : float
        Ratio of successive layer spacings: fine under the surface where strains are large.
    uncertainty : {"bootstrap", "tolerance"}
        How ``beta_std`` is obtained. ``"bootstrap"`` resamples blocks of particles, paired across
        β (:mod:`deformap.msm._uncertainty`); ``"tolerance"`` takes the β interval where E(β) stays
        within ``error_tolerance_m`` of its minimum (width / √12).
    bootstrap_tile_m : float, metres
        Side of the resampled blocks. 2 cm, twice the tip radius and the touch GP's length scale,
        resamples correlated neighbours together.
    error_tolerance_m : float, metres
        Tolerance on E(β) of the ``"tolerance"`` uncertainty, of the order of the touch GP's error.
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
