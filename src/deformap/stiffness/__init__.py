"""Stiffness and Young's modulus in physical units from a press's force–travel record.

A record holds, from first contact to the commanded force ``F_c``, the probe's travel ``t`` [m]
along the press direction and the normal force ``F`` [N]. :func:`estimate_stiffness` returns the
local stiffness ``k = dF/dδ`` [N/m] at ``F_c`` and Young's modulus ``E`` [Pa], each with a
standard deviation, or reports the surface *rigid*: stiffer than probe and arm can tell apart.

Model: an elastic layer of thickness ``h`` bonded to the rigid table under a rigid sphere of
radius ``R``, ``F = E · g(δ)`` (:func:`deformap.mechanics.layer_indentation_force`: Hertz with the
finite-thickness series of Dimitriadis et al. 2002). The indentation is ``δ = t + δ₀``: the record
starts at a contact threshold, so the offset ``δ₀`` is fitted with ``E``, kept at or above
``−3 σ_t``.

Fit: weighted least squares of the travel (the noisier variable relative to its span),
``tᵢ = g⁻¹(Fᵢ / E) − δ₀``, with the effective variance ``σ_t² + (σ_F(Fᵢ) dδ/dF)²`` (Orear 1982)
re-evaluated a few times; ``g⁻¹`` from a log–log table of ``g``; for a given ``E`` the best ``δ₀``
is a weighted mean, and ``log E`` is found on a grid refined by Brent's method. The covariance of
``(E, δ₀)`` is ``(JᵀJ)⁻¹``, scaled by the reduced χ² when above 1 (Birge 1932); ``k = E g'(δ_c)``
with ``E g(δ_c) = F_c``, its σ by the delta method.

Model error: the record is fitted again with one modulus for its lower half (the first ``n // 2``
samples) and one for its upper half, sharing ``δ₀`` (Gauss–Newton from the joint fit). With ``D``
the halves' log-difference and ``σ_D`` its standard deviation, ``σ_model = E √max(0, D² − σ_D²)
/ 2`` (DerSimonian & Laird 1986) is added to ``E``'s variance in quadrature; not computed below
four samples. A modulus that rises smoothly with depth is absorbed by ``δ₀`` and not seen.

Range: samples whose fitted indentation exceeds ``R`` (no Hertz cap there) are left out and the
record refitted, at least three kept; a record whose indentation at ``F_c`` exceeds ``2R``, or
with ``χ = √(Rδ_c)/h`` above 1 or ``δ_c`` above ``h / 2``, is refused.

Rigid: before any fit, the travel gained up to ``F_c`` is estimated by a straight line of travel
against force; below ``rigid_travel_sigmas`` travel noises the surface is rigid, with a lower
bound on ``k``: the force gained over the span plus two of its standard deviations.

The noise defaults are sensor specifications; ν = 0.33 is Gibson & Ashby's open-cell foam.

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
