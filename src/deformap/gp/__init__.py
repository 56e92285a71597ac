"""Gaussian random fields: the paper's kernel, exact and grid-sparse GP regression, hyperparameters
by maximum marginal likelihood, and the posterior algebra that needs no observed values.

Shared parameters: ``length_scale`` σ_w (metres) and ``signal_std`` σₑ of the kernel
k = σₑ² exp(−‖xᵢ − xⱼ‖² / σ_w²) (no factor 2), and ``noise_std`` σₙ (units of the value).
"""

from __future__ import annotations

from deformap.gp._exact import cholesky_with_jitter
from deformap.gp._field import AUTO_EXACT_MAX_POINTS, GaussianRandomField
from deformap.gp._hyper import (
    GPHyperparameters,
    default_bounds,
    fit_hyperparameters,
    log_marginal_likelihood,
)
from deformap.gp._kernels import grid_points, squared_exponential
from deformap.gp._posterior import PosteriorDesign, apply_smoother, variance_after_adding

__all__ = ["AUTO_EXACT_MAX_POINTS", "GPHyperparameters", "GaussianRandomField", "PosteriorDesign",
           "apply_smoother", "cholesky_with_jitter", "default_bounds", "fit_hyperparameters",
           "grid_points", "log_marginal_likelihood", "squared_exponential", "variance_after_adding"]
