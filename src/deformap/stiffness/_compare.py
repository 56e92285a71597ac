"""Each contact model's reading of one record and their smooth average (:mod:`deformap.stiffness`,
Contact models)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2 as chi2_dist

from deformap.stiffness._config import ContactModelFit, StiffnessConfig
from deformap.stiffness._fit import RecordFit, fit_record, model_error
from deformap.stiffness._tables import (
    BONDED_LAYER,
    FOUNDATION,
    HALF_SPACE,
    MAX_FOUNDATION_NU,
    ContactTable,
)

__all__ = ["ModelReading", "average_models", "model_weights", "read_model"]

# the grid along each principal axis of the evidence's covariance (two axes at most with three
# models): ±6 σ in steps of σ / 20, which resolves the softmax while a step moves its log-weights
# by well under one, not for a σ of hundreds in log-weight units
_NORMAL_REACH = 6.0
_NORMAL_NODES = 241


@dataclass(frozen=True)
class ModelReading:
    """One model's ``E``, its σ² (fit, model error, thickness, ν), the model-error part, the
    record's χ² and its degrees of freedom, ``k`` with ``dk/dE`` and the depth ``δ_c`` at the
    commanded force, its table, the record's χ² terms (each sample's squared residual over its
    variance, in order of travel, their lag-1 correlation) and the dent's χ² terms with the
    dent's correlation factor ``τ`` (none without a dent): the evidence that counts in its
    weight."""

    name: str
    modulus: float
    variance: float
    error: float | None
    chi2: float
    dof: int
    stiffness: float
    dk_de: float
    depth: float
    table: ContactTable
    record_terms: NDArray[np.float64]
    lag_correlation: float
    dent_terms: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros(0))
    dent_tau: float = 1.0


def _stiffness_at(fit: RecordFit, modulus: float, force_c: float) -> float:
    table = fit.table
    return float(modulus * table.slope(table.depth_at(np.array([force_c / modulus])))[0])


def read_model(name: str, travel: NDArray[np.float64], force: NDArray[np.float64], radius: float,
               thickness: float, thickness_std: float, force_c: float, config: StiffnessConfig,
               fitted: tuple[float, NDArray[np.float64], float, RecordFit] | None = None,
               ) -> ModelReading | None:
    """``name``'s reading of the record, or ``None`` when the record leaves its table (softer
    than the model holds at the commanded force). ``fitted`` ``(E, cov, reduced χ², fit)``
    reuses a fit already made."""
    if fitted is None:
        modulus, _, cov, chi2_red, fit = fit_record(travel, force, radius, thickness, config, name)
    else:
        modulus, cov, chi2_red, fit = fitted
    if modulus <= 1.001 * fit.low_bound or force_c / modulus > fit.table.force_limit:
        return None
    variance = max(float(cov[0, 0]), 0.0)
    error = model_error(fit, modulus)  # what the record shows the model misses
    if error is not None:
        variance += error**2
    if thickness_std > 0 and name != HALF_SPACE:  # the thickness is read from the surface model
        moduli = [fit_record(travel, force, radius, max(thickness + d, 1.01 * travel.max()),
                             config, name)[0] for d in (-thickness_std, thickness_std)]
        variance += ((moduli[1] - moduli[0]) / 2.0) ** 2
    if config.poisson_ratio_std > 0:  # the material's ν is assumed, not measured: its spread too
        top = MAX_FOUNDATION_NU if name == FOUNDATION else 0.5
        nus = [min(max(config.poisson_ratio + d, 0.0), top)
               for d in (-config.poisson_ratio_std, config.poisson_ratio_std)]
        if nus[1] > nus[0]:
            moduli = [fit_record(travel, force, radius, thickness,
                                 dataclasses.replace(config, poisson_ratio=nu), name)[0]
                      for nu in nus]
            # the slope over the span actually taken (ν is clamped at the ends)
            slope = (moduli[1] - moduli[0]) / (nus[1] - nus[0])
            variance += (slope * config.poisson_ratio_std) ** 2
    dof = travel.size - (1 if fit.offset_clamped(modulus) else 2)
    step = 1e-4 * modulus
    dk_de = (_stiffness_at(fit, modulus + step, force_c)
             - _stiffness_at(fit, modulus - step, force_c)) / (2.0 * step)
    chi2 = float(chi2_red * dof) if dof > 0 else 0.0
    # the record's residuals in units of their σ, in order of travel: their lag-1 correlation
    z = (travel + fit.offset(modulus) - fit.depths(modulus)) * np.sqrt(fit.weights)
    lag = float(z[1:] @ z[:-1]) / float(z @ z) if float(z @ z) > 0 else 0.0
    return ModelReading(name=name, modulus=modulus, variance=variance, error=error, chi2=chi2,
                        dof=dof, stiffness=_stiffness_at(fit, modulus, force_c), dk_de=dk_de,
                        depth=float(fit.table.depth_at(np.array([force_c / modulus]))[0]),
                        table=fit.table, record_terms=np.asarray(z * z), lag_correlation=lag)


def _expected_softmax(log_weights: NDArray[np.float64], cov: NDArray[np.float64]
                      ) -> NDArray[np.float64]:
    """``E[softmax(l + u)]`` for ``u ~ N(0, cov)``: the normal's density on an even grid (to
    ±6 σ) along each principal axis of the contrasts ``uₖ − u₀`` (a shift common to all models
    moves no weight); ``cov = 0`` gives the softmax itself."""
    k = log_weights.size
    contrast = np.hstack([-np.ones((k - 1, 1)), np.eye(k - 1)])
    values, vectors = np.linalg.eigh(contrast @ cov @ contrast.T)
    keep = values > 1e-12
    if not np.any(keep):
        e = np.exp(log_weights - log_weights.max())
        return np.asarray(e / e.sum())
    # (models, axes): model 0 is the contrasts' origin
    axes = np.vstack([np.zeros((1, int(keep.sum()))), vectors[:, keep] * np.sqrt(values[keep])])
    nodes = np.linspace(-_NORMAL_REACH, _NORMAL_REACH, _NORMAL_NODES)
    node_weights = np.exp(-0.5 * nodes**2)
    node_weights /= node_weights.sum()
    dims = axes.shape[1]
    grid = np.stack(np.meshgrid(*([nodes] * dims), indexing="ij"), -1).reshape(-1, dims)
    mass = np.prod(np.stack(np.meshgrid(*([node_weights] * dims), indexing="ij"), -1
                            ).reshape(-1, dims), axis=1)
    shifted = log_weights[None, :] + grid @ axes.T
    e = np.exp(shifted - shifted.max(axis=1, keepdims=True))
    return np.asarray(mass @ (e / e.sum(axis=1, keepdims=True)))


def model_weights(readings: list[ModelReading]) -> NDArray[np.float64]:
    """Each model's weight: pseudo-BMA+ (Yao et al. 2018) over the record's and the dent's χ²
    (the in-sample quasi-likelihood in place of the leave-one-out density: equal parameters).

    Evidence: quasi-likelihood AIC (Burnham & Anderson 2002, §2.5; every model has the
    parameters ``E`` and ``δ₀``, so the penalties cancel), the record's χ² over ``ĉ`` (the best
    record fit's reduced χ², at least 1) and counted at ``n (1 − ρ) / (1 + ρ)`` samples, ``ρ``
    the lag-1 correlation of the best fit's residuals (an AR(1) sequence's effective size;
    Bayley & Hammersley 1946), plus the dent's χ² over its correlation factor ``τ``. Weights
    ``E[softmax(−½ (evidence + u))]`` with ``u`` the evidence's sampling error: normal with the
    covariance the Bayesian bootstrap over the samples gives (each part's per-sample χ² terms,
    their sample covariance between models, scaled as the part is and over its effective
    samples). Two models whose evidence differs by less than the points' own scatter of that
    difference keep both their weight; a difference many times that scatter gives the Akaike
    weight ``∝ exp(−½ ΔQAIC)``."""
    dofs = np.array([max(r.dof, 1) for r in readings])
    chi2 = np.array([r.chi2 for r in readings])
    best = int(np.argmin(chi2))
    rho = min(max(readings[best].lag_correlation, 0.0), 0.99)
    c_hat = max(1.0, float(chi2[best] / dofs[best]))
    count = (1.0 - rho) / (1.0 + rho)  # the record's effective samples per sample
    # (terms (models, n), scale on the evidence, effective samples per sample) per part
    parts = [(np.array([r.record_terms for r in readings]), count / c_hat, count)]
    if readings[0].dent_terms.size:
        tau = readings[0].dent_tau
        parts.append((np.array([r.dent_terms for r in readings]), 1.0 / tau, 1.0 / tau))
    evidence = sum(scale * terms.sum(axis=1) for terms, scale, _ in parts)
    cov = np.zeros((len(readings), len(readings)))
    for terms, scale, per_sample in parts:
        centred = terms - terms.mean(axis=1, keepdims=True)
        cov += scale**2 / per_sample * (centred @ centred.T)
    # the log-likelihood is −½ χ²: its covariance a quarter of the evidence's
    return _expected_softmax(-0.5 * np.asarray(evidence), 0.25 * cov)


def average_models(readings: list[ModelReading]
                   ) -> tuple[float, float, float, float, float | None, tuple[ContactModelFit, ...]]:
    """``(E, σ_E, k, σ_k, model error, fits)``: ``E`` and ``k`` the reference model's (the bonded
    layer's), their variance the second moment about it of the models' mixture under the
    weights of :func:`model_weights`: ``Σ wᵢ σᵢ² + Σ wᵢ (Eᵢ − E)²`` (Burnham & Anderson 2002,
    §4.3, the moment taken about the reference model's ``E``). A model's weight moves σ, never
    ``E``, so two samplings of one press that weigh the models differently read the same ``E``."""
    w = model_weights(readings)
    moduli = np.array([r.modulus for r in readings])
    variances = np.array([r.variance for r in readings])
    stiff = np.array([r.stiffness for r in readings])
    # E and k are the reference model's, their variance the models' mixture's second moment about it
    ref = [r.name for r in readings].index(BONDED_LAYER)
    modulus = float(moduli[ref])
    spread = float(w @ (moduli - modulus) ** 2)
    modulus_std = float(np.sqrt(w @ variances + spread))
    stiffness = float(stiff[ref])
    stiffness_var = float(w @ (np.array([r.dk_de for r in readings]) ** 2 * variances)
                          + w @ (stiff - stiffness) ** 2)
    errors = [r.error for r in readings]
    model_err = None if all(e is None for e in errors) and len(readings) == 1 else float(
        np.sqrt(w @ np.array([0.0 if e is None else e * e for e in errors]) + spread))
    fits = tuple(ContactModelFit(
        name=r.name, modulus_pa=r.modulus, modulus_std_pa=float(np.sqrt(r.variance)),
        reduced_chi2=float(r.chi2 / max(r.dof, 1)),
        p_value=float(chi2_dist.sf(r.chi2, r.dof)) if r.dof > 0 else 1.0,
        weight=float(wi)) for r, wi in zip(readings, w, strict=True))
    return modulus, modulus_std, stiffness, float(np.sqrt(stiffness_var)), model_err, fits
