"""Stiffness and Young's modulus in physical units from a press's force–travel record.

A press records, from first contact to the commanded force, the probe's travel along the press
direction ``t`` [m] and the normal force ``F`` [N]. This package reads from it, as pure functions
(:func:`estimate_stiffness` in ``_estimate.py``, its settings and result in ``_config.py``, the
fit in ``_fit.py``):

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
soft skin over a stiffer core. What it cannot see: a modulus that rises *smoothly* with the
indentation is absorbed by the contact offset (a Hertz curve of a higher ``E`` and a smaller
``δ₀`` fits it within the noise), and then neither the two halves, nor a jackknife over the load
levels, nor the local secant modulus ``Fᵢ / g(tᵢ + δ₀)`` shows it, so the claimed σ does not
cover that bias. On records of the model itself it is zero whenever ``D² < σ_D²``.

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

from deformap.stiffness._config import LAYER_MODEL, StiffnessConfig, StiffnessEstimate
from deformap.stiffness._estimate import estimate_stiffness

__all__ = ["LAYER_MODEL", "StiffnessConfig", "StiffnessEstimate", "estimate_stiffness"]
