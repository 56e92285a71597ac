"""Settings of the shape-matching simulator and the β sweep (one frozen dataclass)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from deformap._validation import SettingError, check_settings, setting

__all__ = ["ShapeMatchingConfig"]


@dataclass(frozen=True, kw_only=True)
class ShapeMatchingConfig:
    """Settings of meshless shape matching and of the β estimation.

    Parameters
    ----------
    mode : {"quadratic", "linear", "rigid"}
        Deformation mode of each cluster (Müller et al. 2005); ``"rigid"`` ignores β.
    cluster_size : int
        Side ``k`` of the overlapping ``k × k`` particle clusters; 3 is the paper's best value.
    contact : {"force", "pinned"}
        How the poke enters the simulation (:mod:`deformap.msm`).
    n_beta : int
        Number of β of the coarse sweep ``β_j = j / n_beta``; E(β) is smooth, so 10 bracket its minimum.
    refine : bool
        Refine β̂ around the sweep's minimum on the ``beta_resolution`` grid.
    beta_resolution : float
        Step of the local refinement (dimensionless).
    tol : float
        Fixed-point tolerance of every β compared: largest update over largest displacement.
    sweep_tol : float
        Tolerance of the coarse sweep and the stiffness calibration under ``refine`` (≥ ``tol``).
    max_iter : int
        Iteration cap; a β that hits it is reported as not converged.
    regularization : float
        Relative eigenvalue cut-off of each cluster's moment matrix.
    reference_modulus_pa : float, pascals
        Young's modulus of the half-space whose Hertz dent calibrates the spring stiffness ``k``.
        100 kPa lies above the stiffest polyurethane foams and below rubbers.
    beta_scale : {"odds", "reference"}
        What β = 0 is under the force protocol: the rigid body, or the reference body.
    poisson_ratio : float
        Poisson's ratio of the reference half-space; it enters only through ``E / (1 − ν²)``.
    layers : int or None
        Layers of particles under the surface sheet; ``None``: 0 for ``"pinned"``, 3 for ``"force"``.
        Spacings grow by ``layer_growth`` down to a fixed floor at half the ROI's smaller side.
    layer_growth : float
        Ratio of successive layer spacings: fine under the surface where strains are large.
    uncertainty : {"bootstrap", "tolerance"}
        How ``beta_std`` is obtained: a paired block bootstrap, or E's tolerance interval.
    bootstrap_tile_m : float, metres
        Side of the resampled blocks; 2 cm, twice the tip radius, keeps neighbours together.
    error_tolerance_m : float, metres
        Tolerance on E(β) of the ``"tolerance"`` uncertainty, of the order of the touch GP's error.
    """

    mode: Literal["quadratic", "linear", "rigid"] = "quadratic"
    cluster_size: int = setting(3, ge=2)
    contact: Literal["force", "pinned"] = "force"
    n_beta: int = setting(10, ge=2, le=1000)
    refine: bool = True
    beta_resolution: float = setting(0.01, ge=1e-6, le=0.5)
    tol: float = setting(1e-6, ge=1e-14, lt=1.0)  # below 1e-14 is float64 rounding
    sweep_tol: float = setting(1e-4, ge=1e-14, lt=1.0)
    max_iter: int = setting(500, ge=1, le=100_000)
    regularization: float = setting(1e-3, ge=0.0, lt=1.0)
    reference_modulus_pa: float = setting(100e3, gt=0.0)
    beta_scale: Literal["odds", "reference"] = "odds"
    poisson_ratio: float = setting(0.5, ge=-1.0, le=0.5)  # the range of an isotropic solid
    uncertainty: Literal["bootstrap", "tolerance"] = "bootstrap"
    bootstrap_tile_m: float = setting(0.02, gt=0.0)
    error_tolerance_m: float = setting(1e-4, gt=0.0)
    layers: int | None = setting(None, ge=0, le=32)
    layer_growth: float = setting(2.0, ge=1.0, le=10.0)

    @property
    def coarse_tol(self) -> float:
        """Tolerance of the coarse sweep and the calibration: ``sweep_tol`` if :attr:`refines`."""
        return self.sweep_tol if self.refines else self.tol

    @property
    def refines(self) -> bool:
        """Whether the coarse sweep is refined: ``refine`` and ``beta_resolution < 1 / n_beta``."""
        return self.refine and self.beta_resolution < 1.0 / self.n_beta

    @property
    def rigid_at_zero(self) -> bool:
        """Whether β = 0 is the rigid body: the force protocol on the ``"odds"`` scale."""
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
            raise SettingError("sweep_tol", f"must be >= `tol` ({self.tol:g}); got {self.sweep_tol:g}")
