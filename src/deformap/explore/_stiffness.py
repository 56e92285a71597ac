"""Stiffness and Young's modulus in physical units from a press's force–travel record.

A press records, from first contact to the commanded force, the probe's travel along the press
direction ``t`` [m] and the normal force ``F`` [N]. This module reads from it, as pure functions:

- the local stiffness ``k = dF/dδ`` [N/m] at the commanded force, and
- Young's modulus ``E`` [Pa] of the surface under the probe,

each with a standard deviation, or says that the surface is *rigid*: stiffer than the probe and
arm can tell apart.

Model
-----
The surface is an elastic layer of thickness ``h`` (the surface model's height above the table at
the contact) bonded to the rigid table, pressed by the rigid spherical tip of radius ``R``:
``F = E · g(δ)`` with ``g`` the bonded-layer force at unit modulus
(:func:`deformap.mechanics.layer_indentation_force`, Hertz with the finite-thickness series of
Dimitriadis et al. 2002; its docstring gives the range of validity, and each estimate reports the
``χ = √(Rδ)/h`` it reached).

Contact offset
--------------
The record starts where the force first crossed a contact threshold, so at zero travel the tip is
already sunk by a small, unknown ``δ₀`` (and the zero itself is one noisy encoder reading). The
indentation is ``δ = t + δ₀``, and ``δ₀`` is fitted with ``E``: a free parameter kept at or above
``−3 σ_t`` (below zero only by what the zero reading's noise explains). Its uncertainty enters
``E``'s through the joint covariance.

Fit
---
Weighted least squares with errors in both variables by the effective-variance method (Orear
1982), written for the travel: ``tᵢ = g⁻¹(Fᵢ / E) − δ₀``, each sample's variance
``σ_t² + (σ_F(Fᵢ) · dδ/dF)²``, evaluated on the current fit and re-evaluated a few times (weights
fixed within one solve). The travel is the response because on stiff surfaces it is the noisier
variable relative to its span (0.05 mm on a few tenths of a millimetre, against 1–3 % on the
force), and a noisy regressor biases a non-linear fit low (regression dilution); the force's
smaller noise only enters through the effective variance. ``g⁻¹`` is read from a table of ``g``
(log–log interpolation) that stops short of the depth where the series' force turns down
(:func:`deformap.mechanics.layer_chi_limit`) and at the layer's thickness. For a given ``E`` the
best ``δ₀`` is a weighted mean (variable projection), and ``log E`` is found by a grid refined
with Brent's bounded method. The covariance of ``(E, δ₀)`` is ``(JᵀJ)⁻¹`` of the weighted
residuals, scaled by the reduced χ² when that exceeds 1 (Birge's ratio: a curve the model does not
explain widens the interval instead of hiding it). The stiffness at the commanded force ``F_c`` is
``k = E g'(δ_c)`` with ``E g(δ_c) = F_c``; its standard deviation follows from ``E``'s by the
delta method (``k`` at a fixed force depends on ``E`` only).

Model error
-----------
The fit's covariance covers the sensors' noise and, through Birge's ratio, a misfit that looks
like noise. A model that describes the material reads the same ``E`` from any part of the record;
so the record is fitted once more with one modulus for its lower half (the first ``n // 2``
samples) and another for its upper half, sharing one ``δ₀`` (Gauss–Newton from the joint fit,
with its weights; the covariance Birge-scaled like the joint fit's). Under the model the two
halves' log-difference ``D`` is zero within its own standard deviation ``σ_D``; what exceeds it is
model error. Read as two estimates of one modulus with a spread between them, the halves'
between-part variance is ``τ² = max(0, D² − σ_D²) / 2`` (DerSimonian & Laird's moment estimator
for two parts) and ``E``, their pooled value, carries ``τ² / 2``:
``σ_model = E √max(0, D² − σ_D²) / 2`` (``model_error_pa``), added to ``E``'s variance in
quadrature. Nothing in it is fitted to any world; ``E`` itself is the joint fit's, unchanged.
With fewer than four samples (three parameters) it is not computed. Where the halves' disagreement
has already widened the joint fit's Birge-scaled covariance, adding it again counts part of it
twice: the term errs on the side of a wider σ.

What it sees: a modulus that changes along the record faster than ``δ₀`` can follow, such as a
soft skin over a stiffer core (``tests/explore/test_stiffness.py``: the share of records whose
``E ± 2σ`` reaches the range of moduli the press crossed rises from 71 to 82 %). What it cannot
see: a modulus that rises *smoothly* with the indentation is absorbed by the contact offset (a
Hertz curve of a higher ``E`` and a smaller ``δ₀`` fits it within the noise), and then neither
the two halves, nor a jackknife over the load levels, nor the local secant modulus
``Fᵢ / g(tᵢ + δ₀)`` shows it: on the simulated foam that stiffens (``stiffening-fem``) the
halves agree within ±1.6 ``σ_D`` and the secant modulus is flat from the first sample, so the
term adds at most 5 % of ``E`` there and the claimed σ does not cover that world's bias (README,
the hardness study). On records of the model itself it is zero in about two records of three
(``D² < σ_D²``, as noise alone gives in 68 %), and widens σ by 9 % on average (noise-only σ; 5 %
with the Poisson ratio's term).

The sphere's range
------------------
Hertz's contact radius ``√(Rδ)`` reaches the sphere's own radius at ``δ = R``: deeper, the
contact is no paraboloid cap and the model does not describe the press. Samples whose fitted
indentation exceeds ``R`` are left out and the record is fitted again on those within it (the
first ones: the travel rises), at least three; ``n_samples`` counts the samples used, and ``k``
at a commanded force beyond ``R`` is the model's extrapolation. A record with fewer than three
samples within ``R`` is refused, and so is one whose indentation at the commanded force exceeds
the tip's diameter (the sphere buried, the stick that holds it pressing the surface too).

Rigid
-----
Before any fit, the travel gained from the first sample to the commanded force is estimated by a
straight line of travel against force (model-free; its standard deviation from the travel noise).
When that span is below ``rigid_travel_sigmas`` times the travel noise, the surface is reported
rigid: no ``E`` or ``k``, but a lower bound on ``k``: the force gained over the span's upper bound
(the span plus two of its standard deviations), which bounds the slope at the commanded force from
below for any curve that stiffens as it is pressed (a convex ``F(δ)``, as contact curves are).

Sensor defaults
---------------
The noise defaults are sensor specifications, not fitted to any world: 0.05 mm for the travel (a
robot arm's joint encoders through its forward kinematics) and ``1 % of reading + 5 mN`` for the
force (a wrist force–torque sensor's class). The Poisson ratio defaults to 0.33, the value of
open-cell foams in Gibson & Ashby's analysis (cell edges that bend give ``G ≈ 3E/8``, so
``ν = E/(2G) − 1 ≈ 1/3``); it is an assumption the caller may change: ``E`` scales with
``1 − ν²`` (about 2 % between 0.3 and 0.36) and the layer correction moves with it. A press does
not measure ν, so σ(E) also carries the assumption's own uncertainty: ``poisson_ratio_std`` 0.07,
the spread of ν taken as anywhere in [0.2, 0.45] (a foam's ν depends on its cell structure and
its strain; a range about 1/3 rather than a fitted figure), which moves E by about ±5 %.

References
----------
Dimitriadis, E. K., et al. (2002). Determination of elastic moduli of thin layers of soft material
using the atomic force microscope. Biophysical Journal 82(5), 2798–2810.
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids, 2nd ed., ch. 5. Cambridge University Press.
Orear, J. (1982). Least squares when both variables have uncertainties. American Journal of
Physics 50(10), 912–916.
Birge, R. T. (1932). The calculation of errors by the method of least squares. Physical Review
40, 207–227.
DerSimonian, R., Laird, N. (1986). Meta-analysis in clinical trials. Controlled Clinical Trials
7(3), 177–188.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from deformap._validation import check_array, check_positive, check_settings, setting
from deformap.errors import InvalidArgumentError
from deformap.mechanics import (
    layer_chi_limit,
    layer_indentation_force,
    layer_indentation_stiffness,
)

__all__ = ["LAYER_MODEL", "StiffnessConfig", "StiffnessEstimate", "estimate_stiffness"]

#: The contact model's name in :attr:`StiffnessEstimate.model`.
LAYER_MODEL = "sphere-on-bonded-layer (Hertz + Dimitriadis 2002)"

_MIN_SAMPLES = 3
_EFFECTIVE_VARIANCE_ROUNDS = 4
_MODULUS_GRID = 61
_TABLE_SIZE = 800
# the fit stays below the depth where the series' force turns down (and at most χ = 3, far past
# the series' range), where the inverse's slope still means something
_CHI_FRACTION = 0.95
_CHI_CAP = 3.0
# thicker than any foam a table-top probe presses: a larger value is a unit slip (millimetres)
_MAX_THICKNESS_M = 2.0
# the range the contact model is read in: the finite-thickness series holds for χ ≲ 1 (Dimitriadis
# et al. 2002); past half the layer the tip nears the table and the foam under it nears its
# collapse plateau (Gibson & Ashby, ch. 5), far outside the small-strain expansion the series is
# (which a 1 cm tip pressed some millimetres into foam already stretches; README)
_MAX_CHI = 1.0
_MAX_STRAIN = 0.5
# the model-error test fits one modulus to each half of the record with one shared δ₀: three
# parameters, at least one degree of freedom left (module docstring, Model error)
_MIN_PART_SAMPLES = 4
_PART_ROUNDS = 8


@dataclass(frozen=True, kw_only=True)
class StiffnessConfig:
    """How a force–travel record is read (module docstring: model, fit, rigid test, defaults).

    Parameters
    ----------
    poisson_ratio : float
        ``ν`` of the surface's material, an assumption (open-cell foam: 0.33).
    poisson_ratio_std : float
        How uncertain that assumption is; σ(E) carries what it moves E by (a refit at
        ``ν ± poisson_ratio_std``). The default 0.07 is the standard deviation of ν spread
        uniformly over [0.2, 0.45], about Gibson & Ashby's 1/3 (module docstring); 0 claims ν is
        known.
    travel_noise_m : float
        Standard deviation of one travel reading (encoders through kinematics).
    force_noise_rel, force_noise_abs_n : float
        Standard deviation of one force reading: ``rel · |F| + abs``.
    rigid_travel_sigmas : float
        A record whose travel span at the commanded force is below this many ``travel_noise_m``
        is rigid.
    backwards_sigmas : float
        How far, in standard deviations of the difference of two readings, travel or force may
        step back between samples before the record is refused (noise moves them a little).
    force_tolerance_rel, force_tolerance_abs_n : float
        When the commanded force is given, the record's last force may differ from it by
        ``rel · F + abs`` (or three force standard deviations, if larger) before it is refused:
        the same rule as :class:`deformap.environment.PressObservation`'s, so that a record the
        protocol accepts is read.
    """

    poisson_ratio: float = setting(0.33, ge=0.0, le=0.5)
    poisson_ratio_std: float = setting(0.07, ge=0.0, le=0.25)
    travel_noise_m: float = setting(5e-5, gt=0.0, lt=0.01)
    force_noise_rel: float = setting(0.01, ge=0.0, lt=1.0)
    force_noise_abs_n: float = setting(0.005, gt=0.0)
    rigid_travel_sigmas: float = setting(3.0, gt=0.0)
    backwards_sigmas: float = setting(4.0, gt=0.0)
    force_tolerance_rel: float = setting(0.25, ge=0.0, le=1.0)
    force_tolerance_abs_n: float = setting(0.05, ge=0.0)

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class StiffnessEstimate:
    """What one force–travel record says about the surface, in SI units.

    Parameters
    ----------
    stiffness_n_per_m, stiffness_std_n_per_m : float or None
        ``k = dF/dδ`` at the commanded force and its standard deviation; ``None`` when rigid.
    stiffness_lower_n_per_m : float or None
        When rigid, a lower bound on ``k`` (module docstring); otherwise ``None``.
    modulus_pa, modulus_std_pa : float or None
        Young's modulus from the contact model and its standard deviation; ``None`` when rigid.
    contact_offset_m : float or None
        The fitted indentation ``δ₀`` at zero travel; ``None`` when rigid.
    depth_m : float
        Indentation at the commanded force (the model's ``δ_c``); when rigid, the travel span
        estimated by the rigid test.
    max_chi : float or None
        ``√(R δ_c) / h`` at the commanded force: the contact model holds for ``χ ≲ 1``.
    reduced_chi2 : float or None
        The fit's χ² per degree of freedom: about 1 when the model and the noise settings explain
        the record, well above it when they do not; ``None`` when rigid.
    rigid : bool
        The surface is stiffer than the probe and arm can tell apart.
    n_samples : int
        Samples the estimate used (those within the tip's radius; module docstring).
    model : str
        The contact model (:data:`LAYER_MODEL`).
    model_error_pa : float or None
        The model-error part of ``modulus_std_pa`` (in quadrature with the rest): half the
        difference between the moduli the record's lower and upper halves read, beyond what
        their own noise explains (module docstring, Model error); 0 when they agree, ``None``
        when rigid or the record has fewer than four samples (then not tested).
    """

    stiffness_n_per_m: float | None
    stiffness_std_n_per_m: float | None
    stiffness_lower_n_per_m: float | None
    modulus_pa: float | None
    modulus_std_pa: float | None
    contact_offset_m: float | None
    depth_m: float
    max_chi: float | None
    reduced_chi2: float | None
    rigid: bool
    n_samples: int
    model: str = LAYER_MODEL
    model_error_pa: float | None = None

    def __post_init__(self) -> None:
        if self.model != LAYER_MODEL:
            raise InvalidArgumentError(f"`model` must be {LAYER_MODEL!r}; got {self.model!r}")
        if isinstance(self.n_samples, bool) or not isinstance(self.n_samples, int) \
                or self.n_samples < _MIN_SAMPLES:
            raise InvalidArgumentError(
                f"`n_samples` must be an integer >= {_MIN_SAMPLES}; got {self.n_samples!r}")
        read = ("stiffness_n_per_m", "stiffness_std_n_per_m", "modulus_pa", "modulus_std_pa")
        if self.rigid:
            if any(getattr(self, n) is not None for n in (*read, "model_error_pa")) or not (
                    self.stiffness_lower_n_per_m is not None and self.stiffness_lower_n_per_m > 0):
                raise InvalidArgumentError(
                    "a rigid estimate has no stiffness, modulus or model error, and a positive "
                    "`stiffness_lower_n_per_m`")
        elif any(getattr(self, n) is None or not np.isfinite(getattr(self, n))
                 or getattr(self, n) < 0 or (getattr(self, n) == 0 and "std" not in n)
                 for n in read):
            raise InvalidArgumentError(
                f"an estimate that is not rigid has finite {', '.join(read)}, the values "
                "positive and their standard deviations not negative")
        elif self.model_error_pa is not None and not (
                np.isfinite(self.model_error_pa) and self.model_error_pa >= 0):
            raise InvalidArgumentError(
                f"`model_error_pa` must be None or finite and >= 0; got {self.model_error_pa!r}")


def _force_std(force: NDArray[np.float64], config: StiffnessConfig) -> NDArray[np.float64]:
    return np.asarray(config.force_noise_rel * np.abs(force) + config.force_noise_abs_n)


def _check_record(travel_m: Any, force_n: Any, config: StiffnessConfig,
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    travel = check_array("travel_m", travel_m, (None,), what="travels in metres",
                         min_rows=_MIN_SAMPLES)
    force = check_array("force_n", force_n, (None,), what="forces in newtons",
                        min_rows=_MIN_SAMPLES)
    if force.shape != travel.shape:
        raise InvalidArgumentError(f"`force_n` must have one value per travel sample "
                                   f"({travel.size}); got {force.size}")
    if abs(travel[0]) > config.backwards_sigmas * config.travel_noise_m:
        raise InvalidArgumentError(
            f"`travel_m` must start at first contact (0 within its noise, "
            f"{config.backwards_sigmas * config.travel_noise_m:.3g} m); got {travel[0]:.4g} m "
            "(an absolute position rather than the travel since contact?)")
    if force.min() < -3.0 * config.force_noise_abs_n:
        raise InvalidArgumentError(
            f"`force_n` must be the force pressing the surface, >= 0 within its noise; got "
            f"{force.min():.4g} N (a sensor not zeroed, or its reaction force not negated?)")
    step_t = config.backwards_sigmas * np.sqrt(2.0) * config.travel_noise_m
    if np.any(np.diff(travel) < -step_t):
        at = int(np.argmax(np.diff(travel) < -step_t)) + 1
        raise InvalidArgumentError(
            f"`travel_m` must not go backwards by more than its noise ({step_t:.3g} m); sample "
            f"{at} goes back by {travel[at - 1] - travel[at]:.3g} m")
    sigma = _force_std(force, config)
    step_f = config.backwards_sigmas * np.hypot(sigma[:-1], sigma[1:])
    rise = force[-1] - force[0]
    if rise <= config.backwards_sigmas * np.hypot(sigma[0], sigma[-1]) or np.any(
            np.diff(force) < -step_f):
        raise InvalidArgumentError(
            f"`force_n` must rise from contact to the commanded force (no step back beyond its "
            f"noise); got {force[0]:.4g} N to {force[-1]:.4g} N, smallest step "
            f"{np.diff(force).min():.4g} N")
    return travel, force


def _travel_span(travel: NDArray[np.float64], force: NDArray[np.float64], force_c: float,
                 sigma_t: float) -> tuple[float, float]:
    """Travel gained from the first force to ``force_c`` by a straight line of travel against
    force, and its standard deviation from the travel noise."""
    centred = force - force.mean()
    sxx = float(centred @ centred)
    slope = float(centred @ travel) / sxx
    span = slope * (force_c - force[0])
    return span, sigma_t * abs(force_c - force[0]) / np.sqrt(sxx)


class _LayerTable:
    """The bonded-layer force at unit modulus, ``g(δ)``, tabulated on ``[0, δ_lim]`` for its
    inverse; ``δ_lim`` stays below the depth where the series' force stops rising and at most the
    layer's thickness."""

    def __init__(self, radius: float, thickness: float, nu: float) -> None:
        self.radius, self.thickness, self.nu = radius, thickness, nu
        self.low_bound = 0.0  # the softest modulus the fit may return (set by the fit)
        chi_lim = min(_CHI_FRACTION * layer_chi_limit(nu), _CHI_CAP)
        # nor deeper than the layer: with R < h that comes first (χ = √(R/h) < 1 at δ = h)
        self.depth_limit = min((chi_lim * thickness) ** 2 / radius, thickness)
        self.depth = self.depth_limit * np.geomspace(1e-9, 1.0, _TABLE_SIZE)
        self.log_depth = np.log(self.depth)
        self.log_force = np.log(layer_indentation_force(self.depth, radius, thickness, 1.0, nu))

    @property
    def force_limit(self) -> float:
        """``g(δ_lim)``: the largest force per pascal the table holds."""
        return float(np.exp(self.log_force[-1]))

    def depth_at(self, force_per_pa: NDArray[np.float64]) -> NDArray[np.float64]:
        """``g⁻¹``: log–log interpolation, Hertz's ``δ ∝ F^(2/3)`` below the table, ``δ_lim``
        above it."""
        u = np.log(np.maximum(force_per_pa, 1e-300))
        below = self.log_depth[0] + (u - self.log_force[0]) / 1.5
        inside = np.interp(u, self.log_force, self.log_depth)
        return np.asarray(np.exp(np.where(u < self.log_force[0], below, inside)))

    def slope(self, depth: NDArray[np.float64]) -> NDArray[np.float64]:
        """``g'(δ)`` at unit modulus, N/m per Pa."""
        return layer_indentation_stiffness(np.maximum(depth, self.depth[0]), self.radius,
                                           self.thickness, 1.0, self.nu)


class _Fit:
    """Effective-variance weighted least squares of ``t = g⁻¹(F / E) − δ₀`` (module
    docstring)."""

    def __init__(self, travel: NDArray[np.float64], force: NDArray[np.float64],
                 table: _LayerTable, config: StiffnessConfig) -> None:
        self.travel, self.force, self.table, self.config = travel, force, table, config
        self.force_std = _force_std(force, config)
        self.weights = np.full(travel.size, 1.0 / config.travel_noise_m**2)
        self.low_bound = 0.0

    def depths(self, modulus: float) -> NDArray[np.float64]:
        return self.table.depth_at(self.force / modulus)

    def offset(self, modulus: float) -> float:
        """The weighted least-squares ``δ₀`` at ``modulus`` (closed form), kept at or above
        ``−3 σ_t``."""
        gap = self.depths(modulus) - self.travel
        return max(float(self.weights @ gap / self.weights.sum()),
                   -3.0 * self.config.travel_noise_m)

    def chi2(self, log_modulus: float) -> float:
        modulus = float(np.exp(log_modulus))
        r = self.travel + self.offset(modulus) - self.depths(modulus)
        return float(self.weights @ (r * r))

    def reweight(self, modulus: float) -> None:
        """Each sample's variance: the travel's plus the force's carried through ``g⁻¹``."""
        ddepth_dforce = 1.0 / (modulus * self.table.slope(self.depths(modulus)))
        self.weights = 1.0 / (self.config.travel_noise_m**2
                              + (self.force_std * ddepth_dforce) ** 2)

    def solve(self) -> float:
        f_max = float(self.force.max())
        # the softest modulus keeps the largest force inside the table; the stiffest sinks the
        # tip by a thousandth of the travel noise
        low = np.log(f_max / self.table.force_limit)
        high = np.log(f_max / float(layer_indentation_force(
            1e-3 * self.config.travel_noise_m, self.table.radius, self.table.thickness, 1.0,
            self.table.nu)))
        self.low_bound = float(np.exp(low))
        log_modulus = low
        for _ in range(_EFFECTIVE_VARIANCE_ROUNDS):
            grid = np.linspace(low, high, _MODULUS_GRID)
            values = [self.chi2(x) for x in grid]
            best = int(np.argmin(values))
            lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
            found = minimize_scalar(self.chi2, bounds=(lo, hi), method="bounded",
                                    options={"xatol": 1e-6})
            log_modulus = float(found.x) if found.fun <= values[best] else float(grid[best])
            self.reweight(float(np.exp(log_modulus)))
        return float(np.exp(log_modulus))

    def covariance(self, modulus: float) -> tuple[NDArray[np.float64], float]:
        """Covariance of ``(E, δ₀)`` from the weighted residuals' Jacobian, Birge-scaled, and
        the reduced χ²."""
        sw = np.sqrt(self.weights)
        depth = self.depths(modulus)
        # ∂δᵢ/∂E = −(Fᵢ / E²) / g'(δᵢ); the residual is t + δ₀ − δ
        d_depth = -(self.force / modulus**2) / self.table.slope(depth)
        # columns in relative units (E's fraction, δ₀ in travel-noise units): the raw ones differ
        # by ten orders of magnitude
        scale = np.array([modulus, self.config.travel_noise_m])
        jac = np.column_stack([-d_depth * sw, sw]) * scale
        if self.offset_clamped(modulus):  # δ₀ sits on its bound: not a free parameter there
            scale, jac = scale[:1], jac[:, :1]
        dof = self.force.size - jac.shape[1]
        chi2_red = self.chi2(float(np.log(modulus))) / dof if dof > 0 else float("nan")
        cov = np.linalg.pinv(jac.T @ jac) * np.outer(scale, scale)
        if dof > 0 and chi2_red > 1.0:
            cov = cov * chi2_red
        return cov, chi2_red

    def offset_clamped(self, modulus: float) -> bool:
        """Whether the best ``δ₀`` at ``modulus`` lies on its ``−3 σ_t`` bound."""
        gap = self.depths(modulus) - self.travel
        return float(self.weights @ gap / self.weights.sum()) < -3.0 * self.config.travel_noise_m

    def part_difference(self, modulus: float) -> tuple[float, float] | None:
        """The two-part model's ``log E_hi − log E_lo`` and its standard deviation (module
        docstring, Model error), or ``None`` when the record has too few samples to tell.

        The lower samples (the first ``n // 2``) read ``E_lo``, the others ``E_hi``, all one
        ``δ₀`` (held at the joint fit's when that sits on its bound); Gauss–Newton from the joint
        fit with its effective-variance weights, the covariance Birge-scaled like the joint
        fit's."""
        n = self.force.size
        if n < _MIN_PART_SAMPLES:
            return None
        upper = np.arange(n) >= n // 2
        free_offset = not self.offset_clamped(modulus)
        sigma_t = self.config.travel_noise_m
        # (log E_lo, log E_hi, δ₀ / σ_t): columns of one order of magnitude
        params = np.array([np.log(modulus), np.log(modulus), self.offset(modulus) / sigma_t])
        sw = np.sqrt(self.weights)

        def linearise(p: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
            per_sample = np.exp(np.where(upper, p[1], p[0]))
            depth = self.table.depth_at(self.force / per_sample)
            # the residual t + δ₀ − δ; ∂δ/∂log E = −(F / E) / g'(δ)
            d_log = (self.force / per_sample) / self.table.slope(depth)
            columns = [np.where(upper, 0.0, d_log), np.where(upper, d_log, 0.0)]
            if free_offset:
                columns.append(np.full(n, sigma_t))
            residual = (self.travel + p[2] * sigma_t - depth) * sw
            return residual, np.column_stack(columns) * sw[:, None]

        k = 3 if free_offset else 2
        for _ in range(_PART_ROUNDS):
            residual, jac = linearise(params)
            step = np.linalg.lstsq(jac, -residual, rcond=None)[0]
            params[:k] += step
            if not np.all(np.isfinite(params)):
                return None
            if np.max(np.abs(step[:2])) < 1e-8:
                break
        residual, jac = linearise(params)
        dof = n - k
        cov = np.linalg.pinv(jac.T @ jac)
        chi2_red = float(residual @ residual) / dof
        if chi2_red > 1.0:
            cov = cov * chi2_red
        var = float(cov[0, 0] + cov[1, 1] - 2.0 * cov[0, 1])
        if not (np.isfinite(var) and var >= 0.0):
            return None
        return float(params[1] - params[0]), float(np.sqrt(var))


def _check_thickness(thickness_m: float, travel: NDArray[np.float64]) -> float:
    thickness = check_positive("thickness_m", thickness_m)
    if thickness > _MAX_THICKNESS_M:
        raise InvalidArgumentError(
            f"`thickness_m` must be in metres, at most {_MAX_THICKNESS_M}; got {thickness} "
            f"(millimetres?)")
    if travel.max() >= thickness:
        raise InvalidArgumentError(
            f"`travel_m` must be in metres and below the layer's thickness ({thickness} m); got "
            f"a travel of {travel.max()} (millimetres?)")
    return thickness


def _fit(travel: NDArray[np.float64], force: NDArray[np.float64], radius: float,
         thickness: float, config: StiffnessConfig
         ) -> tuple[float, float, NDArray[np.float64], float, _Fit]:
    """``(E, δ₀, cov(E, δ₀), reduced χ², fit)`` of the record on a layer of ``thickness``."""
    table = _LayerTable(radius, thickness, config.poisson_ratio)
    fit = _Fit(travel, force, table, config)
    modulus = fit.solve()
    table.low_bound = fit.low_bound
    cov, chi2_red = fit.covariance(modulus)
    return modulus, fit.offset(modulus), cov, chi2_red, fit


def _model_error(fit: _Fit, modulus: float) -> float | None:
    """The model-error standard deviation of ``E`` [Pa] from the two-part test (module
    docstring, Model error): half the parts' difference beyond its own noise; ``None`` when the
    record has too few samples to tell."""
    part = fit.part_difference(modulus)
    if part is None:
        return None
    difference, std = part
    return float(modulus * np.sqrt(max(difference**2 - std**2, 0.0)) / 2.0)


def estimate_stiffness(travel_m: Any, force_n: Any, *, tip_radius_m: float, thickness_m: float,
                       commanded_force_n: float | None = None, thickness_std_m: float = 0.0,
                       config: StiffnessConfig | None = None) -> StiffnessEstimate:
    """Stiffness and Young's modulus with their uncertainties from one force–travel record.

    Parameters
    ----------
    travel_m : (n,) float, metres
        The probe's travel along the press direction since first contact, in time order,
        ``n >= 3``; it may step back by no more than its noise.
    force_n : (n,) float, newtons
        The normal force at each sample; it rises from the contact threshold to the commanded
        force.
    tip_radius_m : float
        Radius of the probe's spherical tip.
    thickness_m : float
        The elastic layer's thickness at the contact (the surface's height above the table), in
        ``(0, 2]`` m; the travel must stay below it.
    commanded_force_n : float, optional
        The force the press was commanded to; the record's last force must be near it
        (``config.force_tolerance_rel`` and ``force_tolerance_abs_n``). Default: the record's
        largest force.
    thickness_std_m : float
        Standard deviation of ``thickness_m`` (the surface model's at the contact); E's
        standard deviation includes what it moves E by (a refit at ``h ± σ_h``).
    config : StiffnessConfig, optional

    Returns
    -------
    StiffnessEstimate
        ``k`` at the commanded force and ``E`` with their standard deviations (module docstring),
        or ``rigid=True`` with ``None`` for both.

    Raises
    ------
    InvalidArgumentError
        Naming the argument: NaN or infinite values, fewer than three samples, a travel that does
        not start at contact, a negative force, travel or force going backwards beyond their
        noise, force not rising, a travel not below the thickness (millimetres for metres), a
        last force far from the commanded one, a bad radius or thickness, or a record that leaves
        the contact model's range (an indentation deeper than the tip's diameter, where the
        sphere is buried and the stick holding it presses too; ``χ`` above 1; an indentation
        deeper than half the layer; or a modulus on the fit's lower bound): the tip sank too
        deep to read the layer.
    """
    config = StiffnessConfig() if config is None else config
    radius = check_positive("tip_radius_m", tip_radius_m)
    travel, force = _check_record(travel_m, force_n, config)
    if commanded_force_n is None:
        force_c = float(force.max())
    else:
        force_c = check_positive("commanded_force_n", commanded_force_n)
        allowed = max(config.force_tolerance_rel * force_c + config.force_tolerance_abs_n,
                      3.0 * float(_force_std(np.array([force_c]), config)[0]))
        if abs(force[-1] - force_c) > allowed:
            raise InvalidArgumentError(
                f"`force_n` must end near the commanded force {force_c} N (within {allowed:.3g} "
                f"N); its last value is {force[-1]:.4g} N")
    # rigid needs no layer: a board or the bare table, which a surface model may read as thin
    span, span_std = _travel_span(travel, force, force_c, config.travel_noise_m)
    if span < config.rigid_travel_sigmas * config.travel_noise_m:
        bound = max(span, 0.0) + 2.0 * span_std
        return StiffnessEstimate(
            stiffness_n_per_m=None, stiffness_std_n_per_m=None,
            stiffness_lower_n_per_m=float((force_c - force[0]) / bound), modulus_pa=None,
            modulus_std_pa=None, contact_offset_m=None, depth_m=float(span), max_chi=None,
            reduced_chi2=None, rigid=True, n_samples=int(travel.size))
    thickness = _check_thickness(thickness_m, travel)
    thickness_std = check_positive("thickness_std_m", thickness_std_m, allow_zero=True)
    modulus, offset, cov, chi2_red, fit = _fit(travel, force, radius, thickness, config)
    for _ in range(2):  # keep the samples within the sphere's range (module docstring)
        within = int(np.count_nonzero(np.cumprod(travel + offset <= radius)))
        if within == travel.size:
            break
        if within < _MIN_SAMPLES:
            raise InvalidArgumentError(
                f"`force_n`/`travel_m` leave the contact model's range: only {within} sample(s) "
                f"lie within the tip's {radius * 1e3:.3g} mm radius (`tip_radius_m`), "
                f"{_MIN_SAMPLES} needed; deeper, the sphere's contact is no Hertz cap")
        travel, force = travel[:within], force[:within]
        modulus, offset, cov, chi2_red, fit = _fit(travel, force, radius, thickness, config)
    table = fit.table
    depth_c = float(table.depth_at(np.array([force_c / modulus]))[0])
    chi = float(np.sqrt(radius * depth_c) / thickness)
    strain = depth_c / thickness
    if depth_c > 2.0 * radius:
        raise InvalidArgumentError(
            f"`force_n`/`travel_m` leave the contact model's range: the tip sank "
            f"{depth_c * 1e3:.3g} mm, more than its {2e3 * radius:.3g} mm diameter "
            f"(`tip_radius_m` {radius:g} m): the sphere is buried and what holds it above "
            f"presses the surface too")
    if chi > _MAX_CHI or strain > _MAX_STRAIN or modulus <= 1.001 * table.low_bound:
        raise InvalidArgumentError(
            f"`force_n`/`travel_m` leave the contact model's range (χ = {chi:.2f}, at most "
            f"{_MAX_CHI}; indentation {strain:.0%} of the {thickness:.3g} m layer, at most "
            f"{_MAX_STRAIN:.0%}): the tip presses too deep into this layer to read its modulus")
    modulus_var = max(cov[0, 0], 0.0)
    model_error = _model_error(fit, modulus)  # what the record shows the model misses
    if model_error is not None:
        modulus_var += model_error**2
    if thickness_std > 0:  # the layer's thickness is read from the surface model: its error too
        moduli = [_fit(travel, force, radius, max(thickness + d, 1.01 * travel.max()), config)[0]
                  for d in (-thickness_std, thickness_std)]
        modulus_var += ((moduli[1] - moduli[0]) / 2.0) ** 2
    if config.poisson_ratio_std > 0:  # the material's ν is assumed, not measured: its spread too
        nus = [min(max(config.poisson_ratio + d, 0.0), 0.5)
               for d in (-config.poisson_ratio_std, config.poisson_ratio_std)]
        moduli = [_fit(travel, force, radius, thickness,
                       dataclasses.replace(config, poisson_ratio=nu))[0] for nu in nus]
        # the slope over the span actually taken (ν is clamped to [0, 0.5] at the ends)
        slope = (moduli[1] - moduli[0]) / (nus[1] - nus[0])
        modulus_var += (slope * config.poisson_ratio_std) ** 2
    modulus_std = float(np.sqrt(modulus_var))

    def stiffness_at(e: float) -> float:
        return float(e * table.slope(table.depth_at(np.array([force_c / e])))[0])

    step = 1e-4 * modulus
    dk_de = (stiffness_at(modulus + step) - stiffness_at(modulus - step)) / (2.0 * step)
    return StiffnessEstimate(
        stiffness_n_per_m=stiffness_at(modulus),
        stiffness_std_n_per_m=float(abs(dk_de) * modulus_std), stiffness_lower_n_per_m=None,
        modulus_pa=modulus, modulus_std_pa=modulus_std, model_error_pa=model_error,
        contact_offset_m=offset,
        depth_m=depth_c, max_chi=chi,
        reduced_chi2=None if np.isnan(chi2_red) else float(chi2_red), rigid=False,
        n_samples=int(travel.size))
