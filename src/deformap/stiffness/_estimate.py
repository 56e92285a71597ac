"""Stiffness and Young's modulus from one force–travel record (:mod:`deformap.stiffness`)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_positive
from deformap.errors import InvalidArgumentError
from deformap.stiffness._compare import average_models, read_model
from deformap.stiffness._config import MIN_SAMPLES, StiffnessConfig, StiffnessEstimate, force_std
from deformap.stiffness._dent_evidence import DentSamples, dent_terms
from deformap.stiffness._fit import fit_record
from deformap.stiffness._tables import BONDED_LAYER, FOUNDATION, MAX_FOUNDATION_NU

__all__ = ["estimate_stiffness"]

# thicker than any foam a table-top probe presses: a larger value is a unit slip (millimetres)
_MAX_THICKNESS_M = 2.0
# the series holds for χ ≲ 1 (Dimitriadis et al. 2002); past half the layer the foam nears its
# collapse plateau (Gibson & Ashby, ch. 5)
_MAX_CHI = 1.0
_MAX_STRAIN = 0.5


def _check_record(travel_m: Any, force_n: Any, config: StiffnessConfig,
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    travel = check_array("travel_m", travel_m, (None,), what="travels in metres", min_rows=MIN_SAMPLES)
    force = check_array("force_n", force_n, (None,), what="forces in newtons", min_rows=MIN_SAMPLES)
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
    sigma = force_std(force, config)
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
    """Travel gained from the first force to ``force_c`` on a line of travel against force, and
    its standard deviation from the travel noise."""
    centred = force - force.mean()
    sxx = float(centred @ centred)
    span = float(centred @ travel) / sxx * (force_c - force[0])
    return span, sigma_t * abs(force_c - force[0]) / np.sqrt(sxx)


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


def estimate_stiffness(travel_m: Any, force_n: Any, *, tip_radius_m: float, thickness_m: float,
                       commanded_force_n: float | None = None, thickness_std_m: float = 0.0,
                       config: StiffnessConfig | None = None,
                       dent: DentSamples | None = None) -> StiffnessEstimate:
    """Stiffness and Young's modulus with their uncertainties from one force–travel record.

    ``travel_m (n,)`` [m] since first contact, ``n >= 3``, and ``force_n (n,)`` [N] rising to
    ``commanded_force_n`` (default the largest), which the last force must be near; the tip's
    radius; the layer's thickness at the contact in ``(0, 2]`` m, above the travel, and its std
    (σ(E) includes a refit at ``h ± σ_h``); optionally the ``dent`` the camera saw, whose shape
    joins the record's fit as evidence between the contact models (:mod:`deformap.stiffness`).

    Raises
    ------
    InvalidArgumentError
        Naming the argument: a record that is not finite, too short, not from contact, negative,
        stepping back beyond its noise, not rising, not below the thickness, not ending near the
        commanded force, or outside the contact model's range (:mod:`deformap.stiffness`).
    """
    config = StiffnessConfig() if config is None else config
    radius = check_positive("tip_radius_m", tip_radius_m)
    travel, force = _check_record(travel_m, force_n, config)
    if commanded_force_n is None:
        force_c = float(force.max())
    else:
        force_c = check_positive("commanded_force_n", commanded_force_n)
        allowed = max(config.force_tolerance_rel * force_c + config.force_tolerance_abs_n,
                      3.0 * float(force_std(np.array([force_c]), config)[0]))
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
    modulus, offset, cov, chi2_red, fit = fit_record(travel, force, radius, thickness, config,
                                                     BONDED_LAYER)
    for _ in range(2):  # keep the samples within the sphere's range (:mod:`deformap.stiffness`)
        within = int(np.count_nonzero(np.cumprod(travel + offset <= radius)))
        if within == travel.size:
            break
        if within < MIN_SAMPLES:
            raise InvalidArgumentError(
                f"`force_n`/`travel_m` leave the contact model's range: only {within} sample(s) "
                f"lie within the tip's {radius * 1e3:.3g} mm radius (`tip_radius_m`), "
                f"{MIN_SAMPLES} needed; deeper, the sphere's contact is no Hertz cap")
        travel, force = travel[:within], force[:within]
        modulus, offset, cov, chi2_red, fit = fit_record(travel, force, radius, thickness, config,
                                                         BONDED_LAYER)
    depth_c = float(fit.table.depth_at(np.array([force_c / modulus]))[0])
    chi = float(np.sqrt(radius * depth_c) / thickness)
    strain = depth_c / thickness
    if depth_c > 2.0 * radius:
        raise InvalidArgumentError(
            f"`force_n`/`travel_m` leave the contact model's range: the tip sank "
            f"{depth_c * 1e3:.3g} mm, more than its {2e3 * radius:.3g} mm diameter "
            f"(`tip_radius_m` {radius:g} m): the sphere is buried and what holds it above "
            f"presses the surface too")
    if chi > _MAX_CHI or strain > _MAX_STRAIN or modulus <= 1.001 * fit.low_bound:
        raise InvalidArgumentError(
            f"`force_n`/`travel_m` leave the contact model's range (χ = {chi:.2f}, at most "
            f"{_MAX_CHI}; indentation {strain:.0%} of the {thickness:.3g} m layer, at most "
            f"{_MAX_STRAIN:.0%}): the tip presses too deep into this layer to read its modulus")
    # the reference model in range, then every other model the record lies in the range of
    readings = [read_model(BONDED_LAYER, travel, force, radius, thickness, thickness_std,
                           force_c, config, fitted=(modulus, cov, chi2_red, fit))]
    readings += [read_model(name, travel, force, radius, thickness, thickness_std, force_c,
                            config) for name in config.contact_models if name != BONDED_LAYER
                 and (name != FOUNDATION or config.poisson_ratio <= MAX_FOUNDATION_NU)]
    if readings[0] is None:  # E is the reference model's: it must hold the record (Range)
        raise InvalidArgumentError(
            "`force_n`/`travel_m` leave the contact model's range: the commanded force lies "
            "beyond the bonded layer's table at the modulus the record reads")
    in_range = [r for r in readings if r is not None]
    if dent is not None:  # the dent's shape: evidence beside the record's own fit
        terms, tau = dent_terms(dent, [(r.name, r.table, r.depth) for r in in_range], radius,
                                thickness, config.poisson_ratio)
        in_range = [dataclasses.replace(r, dent_terms=t, dent_tau=tau)
                    for r, t in zip(in_range, terms, strict=True)]
    modulus, modulus_std, stiffness, stiffness_std, error_pa, fits = average_models(in_range)
    return StiffnessEstimate(
        stiffness_n_per_m=stiffness, stiffness_std_n_per_m=stiffness_std,
        stiffness_lower_n_per_m=None, modulus_pa=modulus, modulus_std_pa=modulus_std,
        model_error_pa=error_pa, contact_offset_m=offset, depth_m=depth_c, max_chi=chi,
        reduced_chi2=None if np.isnan(chi2_red) else float(chi2_red), rigid=False,
        n_samples=int(travel.size), model_fits=fits)
