"""A force–travel record's fit under one contact model and its two-part model-error test
(:mod:`deformap.stiffness`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from deformap.stiffness._config import StiffnessConfig, force_std
from deformap.stiffness._tables import ContactTable, contact_table

__all__ = ["RecordFit", "fit_record", "model_error"]

_EFFECTIVE_VARIANCE_ROUNDS = 4
_MODULUS_GRID = 61
# the model-error test's three parameters (two moduli, one δ₀) and one degree of freedom
_MIN_PART_SAMPLES = 4
_PART_ROUNDS = 8


class RecordFit:
    """Effective-variance weighted least squares of ``t = g⁻¹(F / E) − δ₀``."""

    def __init__(self, travel: NDArray[np.float64], force: NDArray[np.float64],
                 table: ContactTable, config: StiffnessConfig) -> None:
        self.travel, self.force, self.table, self.config = travel, force, table, config
        self.force_std = force_std(force, config)
        self.weights = np.full(travel.size, 1.0 / config.travel_noise_m**2)
        self.low_bound = 0.0

    def depths(self, modulus: float) -> NDArray[np.float64]:
        return self.table.depth_at(self.force / modulus)

    def _free_offset(self, modulus: float) -> float:
        gap = self.depths(modulus) - self.travel
        return float(self.weights @ gap / self.weights.sum())

    def offset(self, modulus: float) -> float:
        """The weighted least-squares ``δ₀`` at ``modulus``, at least ``−3 σ_t``."""
        return max(self._free_offset(modulus), -3.0 * self.config.travel_noise_m)

    def chi2(self, log_modulus: float) -> float:
        return float(self.chi2_grid(np.array([log_modulus]))[0])

    def chi2_grid(self, log_moduli: NDArray[np.float64]) -> NDArray[np.float64]:
        """The weighted χ² at each of ``log_moduli`` (δ₀ at its best, as :meth:`offset`)."""
        gap = self.table.depth_at(self.force / np.exp(log_moduli)[:, None]) - self.travel
        offset = np.maximum(gap @ self.weights / self.weights.sum(),
                            -3.0 * self.config.travel_noise_m)
        r = offset[:, None] - gap
        return np.asarray((r * r) @ self.weights)

    def reweight(self, modulus: float) -> None:
        """Each sample's variance: the travel's plus the force's carried through ``g⁻¹``."""
        ddepth_dforce = 1.0 / (modulus * self.table.slope(self.depths(modulus)))
        self.weights = 1.0 / (self.config.travel_noise_m**2
                              + (self.force_std * ddepth_dforce) ** 2)

    def solve(self) -> float:
        f_max = float(self.force.max())
        # softest: the largest force inside the table; stiffest: a thousandth of the travel noise
        low = np.log(f_max / self.table.force_limit)
        high = np.log(f_max / float(self.table.force_at(
            np.array([1e-3 * self.config.travel_noise_m]))[0]))
        self.low_bound = float(np.exp(low))
        log_modulus = low
        for _ in range(_EFFECTIVE_VARIANCE_ROUNDS):
            grid = np.linspace(low, high, _MODULUS_GRID)
            values = self.chi2_grid(grid)
            best = int(np.argmin(values))
            lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
            found = minimize_scalar(self.chi2, bounds=(lo, hi), method="bounded",
                                    options={"xatol": 1e-6})
            log_modulus = float(found.x) if found.fun <= values[best] else float(grid[best])
            self.reweight(float(np.exp(log_modulus)))
        return float(np.exp(log_modulus))

    def covariance(self, modulus: float) -> tuple[NDArray[np.float64], float]:
        """Birge-scaled covariance of ``(E, δ₀)`` from the weighted Jacobian, and the reduced χ²."""
        sw = np.sqrt(self.weights)
        depth = self.depths(modulus)
        # ∂δᵢ/∂E = −(Fᵢ / E²) / g'(δᵢ); the residual is t + δ₀ − δ
        d_depth = -(self.force / modulus**2) / self.table.slope(depth)
        # columns in relative units: the raw ones differ by ten orders of magnitude
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
        return self._free_offset(modulus) < -3.0 * self.config.travel_noise_m

    def part_difference(self, modulus: float) -> tuple[float, float] | None:
        """``log E_hi − log E_lo`` of the two-part model and its standard deviation, or ``None``
        with too few samples (``δ₀`` held at the joint fit's when that sits on its bound)."""
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


def fit_record(travel: NDArray[np.float64], force: NDArray[np.float64], radius: float,
               thickness: float, config: StiffnessConfig, model: str
               ) -> tuple[float, float, NDArray[np.float64], float, RecordFit]:
    """``(E, δ₀, cov(E, δ₀), reduced χ², fit)`` of the record under contact ``model`` on a layer
    of ``thickness``."""
    table = contact_table(model, radius, thickness, config.poisson_ratio)
    fit = RecordFit(travel, force, table, config)
    modulus = fit.solve()
    cov, chi2_red = fit.covariance(modulus)
    return modulus, fit.offset(modulus), cov, chi2_red, fit


def model_error(fit: RecordFit, modulus: float) -> float | None:
    """σ_model of ``E`` [Pa] (:mod:`deformap.stiffness`, Model error), or ``None``."""
    part = fit.part_difference(modulus)
    if part is None:
        return None
    difference, std = part
    return float(modulus * np.sqrt(max(difference**2 - std**2, 0.0)) / 2.0)
