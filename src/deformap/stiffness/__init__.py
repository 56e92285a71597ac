"""Stiffness and Young's modulus in physical units from a press's force–travel record and the
contact model it follows.

A record holds, from first contact to the commanded force ``F_c``, the probe's travel ``t`` [m]
and the normal force ``F`` [N]. :func:`estimate_stiffness` returns ``k = dF/dδ`` [N/m] at ``F_c``
and Young's modulus ``E`` [Pa], each with a standard deviation, or reports the surface *rigid*.

Model: an elastic layer of thickness ``h`` bonded to the table under a sphere of radius ``R``,
``F = E · g(δ)`` (:func:`deformap.mechanics.layer_indentation_force`, Hertz with the series of
Dimitriadis et al. 2002), ``δ = t + δ₀`` with the contact offset ``δ₀ ≥ −3 σ_t`` fitted with ``E``.

Fit: weighted least squares of ``tᵢ = g⁻¹(Fᵢ / E) − δ₀`` with the effective variance
``σ_t² + (σ_F(Fᵢ) dδ/dF)²`` (Orear 1982), re-evaluated a few times; for a given ``E`` the best
``δ₀`` is a weighted mean, and ``log E`` is found on a grid refined by Brent's method. cov(E, δ₀)
``= (JᵀJ)⁻¹``, scaled by the reduced χ² when above 1 (Birge 1932); ``k = E g'(δ_c)`` with
``E g(δ_c) = F_c``, its σ by the delta method.

Model error: one modulus for the record's lower half and one for its upper half, sharing ``δ₀``;
with ``D`` their log-difference and ``σ_D`` its std, ``σ_model = E √max(0, D² − σ_D²) / 2``
(DerSimonian & Laird 1986) joins ``E``'s variance in quadrature (from four samples).

Contact models (``StiffnessConfig.contact_models``): besides the bonded layer, the same record
is fitted, each as ``F = E · gᵢ(δ)`` by the fit above with its own ``δ₀`` and σ terms, by a
sphere on a two-parameter (Vlasov) foundation (:func:`deformap.mechanics.foundation_indentation`:
a layer that deforms only vertically, spring and shear from ``E``, ``ν`` and ``h``) and, when
asked, on Hertz's half-space. A model *fits* when its χ² has ``p > 0.01``. Each model's evidence
is its χ² under the effective variance plus, when the camera's points about the press are given
(:class:`DentSamples`), the χ² of the dent's shape: the model's own surface (the foundation's,
the bonded layer's of thickness ``h``, :func:`deformap.mechanics.layer_surface_deflection`, or
Hertz's half-space) at its depth at ``F_c``, with a free offset, σ from the best
model's MAD, and divided by the points' correlation factor ``τ`` (batch means over cells of the
touch model's length scale; Thiébaux & Zwiers 1984), so that ``m / τ`` points count. The
evidence is quasi-likelihood AIC with equal parameter counts, the record's χ² over ``ĉ`` (the
best record fit's reduced χ², at least 1; Burnham & Anderson 2002) and counted at
``n (1 − ρ) / (1 + ρ)`` samples (``ρ`` the best fit's lag-1 residual correlation: a record
sampled faster than it varies gains nothing by it). Weights are pseudo-BMA+ (Yao et al. 2018):
``wᵢ = E[softmax(−½ (evidence + u))ᵢ]``, ``u`` the evidence's sampling error, normal with the
covariance the Bayesian bootstrap gives over the record's samples and the dent's points (each
one's χ² term under every model, counted at the part's effective size): a difference in
evidence within the scatter its own terms show leaves both models weight, one far beyond it
gives the Akaike weight ``∝ exp(−½ Δevidence)``. ``E`` stays the bonded
layer's and ``σ² = Σ wᵢ σᵢ² + Σ wᵢ (Eᵢ − E)²``, the second moment about it of the models'
mixture (``k`` likewise): a model that fits better widens σ toward its own ``E`` and never moves
``E``, so two samplings of one press, or two presses of one material, that weigh the models
differently read the same ``E``. The record must lie in the bonded layer's range (Range);
``δ₀``, ``δ_c`` and ``χ`` are that model's.

Range: samples whose fitted indentation exceeds ``R`` are left out and the record refitted (at
least three kept); ``δ_c > 2R``, ``χ = √(Rδ_c)/h > 1`` or ``δ_c > h / 2`` is refused. Rigid: a
straight line of travel against force gains less than ``rigid_travel_sigmas`` travel noises up
to ``F_c``; ``k``'s lower bound is the force gained over that span plus two of its σ.

References
----------
Dimitriadis, E. K., et al. (2002). Determination of elastic moduli of thin layers of soft material
using the atomic force microscope. Biophysical Journal 82(5), 2798–2810.
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids, 2nd ed., ch. 5. Cambridge University Press.
Orear, J. (1982). Least squares when both variables have uncertainties. Am. J. Phys. 50(10).
Birge, R. T. (1932). The calculation of errors by the method of least squares. Phys. Rev. 40.
DerSimonian, R., Laird, N. (1986). Meta-analysis in clinical trials. Control. Clin. Trials 7(3).
Burnham, K. P., Anderson, D. R. (2002). Model Selection and Multimodel Inference, 2nd ed.,
§2.5 (QAIC) and §4.3 (a model mixture's variance; here its second moment is taken about the
reference model's E rather than about the average). Springer.
Thiébaux, H. J., Zwiers, F. W. (1984). The interpretation and estimation of effective sample
size. J. Climate Appl. Meteor. 23(5), 800–811.
Yao, Y., Vehtari, A., Simpson, D., Gelman, A. (2018). Using stacking to average Bayesian
predictive distributions. Bayesian Analysis 13(3), 917–1007 (pseudo-BMA+).
Vlasov, V. Z., Leontiev, N. N. (1966). Beams, Plates and Shells on Elastic Foundations.
Bayley, G. V., Hammersley, J. M. (1946). The "effective" number of independent observations in
an autocorrelated time series. Suppl. J. R. Stat. Soc. 8(2), 184–197.
"""

from __future__ import annotations

from deformap.stiffness._anisotropy import ANISOTROPY_WINDOW_RADII, dent_anisotropy
from deformap.stiffness._behaviour import (
    BEHAVIOURS,
    PressBehaviour,
    PressRecord,
    press_behaviour,
    record_dent_floor,
    released_dent,
)
from deformap.stiffness._config import (
    FIT_P_VALUE,
    LAYER_MODEL,
    ContactModelFit,
    StiffnessConfig,
    StiffnessEstimate,
)
from deformap.stiffness._dent_evidence import DentSamples
from deformap.stiffness._estimate import estimate_stiffness
from deformap.stiffness._tables import CONTACT_MODELS

__all__ = [
    "ANISOTROPY_WINDOW_RADII",
    "BEHAVIOURS",
    "CONTACT_MODELS",
    "FIT_P_VALUE",
    "LAYER_MODEL",
    "ContactModelFit",
    "DentSamples",
    "PressBehaviour",
    "PressRecord",
    "StiffnessConfig",
    "StiffnessEstimate",
    "dent_anisotropy",
    "estimate_stiffness",
    "press_behaviour",
    "record_dent_floor",
    "released_dent",
]
