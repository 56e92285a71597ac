"""The force–travel estimator's settings and what it returns (:mod:`deformap.stiffness`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_settings, setting
from deformap.errors import InvalidArgumentError

__all__ = ["FIT_P_VALUE", "LAYER_MODEL", "MIN_SAMPLES", "ContactModelFit", "StiffnessConfig",
           "StiffnessEstimate", "force_std"]

#: A contact model a record is compared against (:mod:`deformap.stiffness`, Contact models).
ContactModel = Literal["bonded-layer", "half-space", "foundation"]

#: The contact model's name in :attr:`StiffnessEstimate.model`.
LAYER_MODEL = "sphere-on-bonded-layer (Hertz + Dimitriadis 2002)"
#: Fewest samples a record needs: the fit has two parameters, E and δ₀.
MIN_SAMPLES = 3
#: A contact model *fits* a record when its χ² under the effective variance is at least this
#: likely under the record's noise (the usual 1 % test level; the weights do not use it).
FIT_P_VALUE = 0.01


@dataclass(frozen=True, kw_only=True)
class StiffnessConfig:
    """How a force–travel record is read (:mod:`deformap.stiffness`).

    Parameters
    ----------
    poisson_ratio : float
        ``ν`` of the surface's material, an assumption (open-cell foam: 0.33).
    poisson_ratio_std : float
        Uncertainty of ν, carried into σ(E) by refits at ``ν ± poisson_ratio_std``.
        0.07 is the standard deviation of ν uniform over [0.2, 0.45]; 0 claims ν is known.
    travel_noise_m : float
        Standard deviation of one travel reading (encoders through kinematics).
    force_noise_rel, force_noise_abs_n : float
        Standard deviation of one force reading: ``rel · |F| + abs``.
    rigid_travel_sigmas : float
        A travel span at the commanded force below this many ``travel_noise_m`` reads rigid.
    backwards_sigmas : float
        How far, in standard deviations of a two-reading difference, travel or force may step back.
    force_tolerance_rel, force_tolerance_abs_n : float
        Allowed gap ``rel · F + abs`` (or three force σ) between the last and commanded force.
    contact_models : tuple of str
        The contact models whose spread widens E's σ: ``bonded-layer`` (the reference, whose E
        is reported, always in) and any of ``half-space`` and ``foundation``. By default the
        layer and the foundation, the two kinematics a foam on a table may follow;
        ``half-space`` is for a layer whose base is not known to be there (with the base known,
        neither a record nor a dent tells the two apart, and the half-space would only widen σ
        by the layer's correction). A user who
        knows the surface is a bonded elastic layer (a gel bonded to glass) names only
        ``bonded-layer``.
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
    contact_models: tuple[ContactModel, ...] = ("bonded-layer", "foundation")

    def __post_init__(self) -> None:
        check_settings(self)
        if "bonded-layer" not in self.contact_models or len(set(self.contact_models)) != len(
                self.contact_models):
            raise InvalidArgumentError(
                f"`contact_models` must hold `bonded-layer` (the reference model) and each model "
                f"once; got {list(self.contact_models)}")


@dataclass(frozen=True, kw_only=True)
class ContactModelFit:
    """One contact model's reading of a record (:mod:`deformap.stiffness`, Contact models).

    ``name`` the model; ``modulus_pa`` its E and ``modulus_std_pa`` its σ (its own fit, model
    error, thickness and ν terms); ``reduced_chi2`` its χ² per degree of freedom under the
    effective variance and ``p_value`` that χ²'s upper tail; ``weight`` its share of the models'
    mixture whose second moment about the reference's E is σ² (the weights sum to 1).
    """

    name: str
    modulus_pa: float
    modulus_std_pa: float
    reduced_chi2: float
    p_value: float
    weight: float

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidArgumentError(f"`name` must be a model's name; got {self.name!r}")
        for n in ("modulus_pa", "modulus_std_pa", "reduced_chi2", "p_value", "weight"):
            v = getattr(self, n)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) \
                    or v < 0 or (n == "modulus_pa" and v == 0) or (n in ("p_value", "weight")
                                                                    and v > 1):
                raise InvalidArgumentError(
                    f"`{n}` must be a finite number >= 0 (a modulus > 0, a p-value or weight "
                    f"<= 1); got {v!r}")

    @property
    def fits(self) -> bool:
        """Whether the record is consistent with this model: ``p_value > FIT_P_VALUE``."""
        return self.p_value > FIT_P_VALUE


@dataclass(frozen=True, kw_only=True)
class StiffnessEstimate:
    """What one force–travel record says, in SI units; the read fields are ``None`` when ``rigid``.

    ``stiffness_n_per_m`` ``k = dF/dδ`` at the commanded force, ``modulus_pa`` E, and their stds;
    ``stiffness_lower_n_per_m`` a bound on ``k`` when rigid; ``contact_offset_m`` δ₀; ``depth_m``
    δ_c (rigid: the travel span); ``max_chi`` ``√(R δ_c) / h``; ``reduced_chi2``; ``n_samples``
    used; ``model_error_pa`` the model-error part of ``modulus_std_pa``: each model's two-part
    term and the spread between the models (None under four samples with one model in range).
    ``model`` names the reference model, whose range the record must lie in and whose δ₀, δ_c and
    ``χ`` these are; ``model_fits`` each contact model in its range, the reference first
    (:class:`ContactModelFit`; E and k are the reference's, the weights set their σ).
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
    model_fits: tuple[ContactModelFit, ...] = ()

    def __post_init__(self) -> None:
        if self.model != LAYER_MODEL:
            raise InvalidArgumentError(f"`model` must be {LAYER_MODEL!r}; got {self.model!r}")
        if isinstance(self.n_samples, bool) or not isinstance(self.n_samples, int) \
                or self.n_samples < MIN_SAMPLES:
            raise InvalidArgumentError(
                f"`n_samples` must be an integer >= {MIN_SAMPLES}; got {self.n_samples!r}")
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
        if not isinstance(self.model_fits, tuple) or not all(
                isinstance(f, ContactModelFit) for f in self.model_fits) or (
                self.rigid and self.model_fits):
            raise InvalidArgumentError(
                "`model_fits` must be a tuple of ContactModelFit, empty when rigid")
        if self.model_fits and abs(sum(f.weight for f in self.model_fits) - 1.0) > 1e-6:
            raise InvalidArgumentError(
                f"`model_fits`' weights must sum to 1; got {[f.weight for f in self.model_fits]}")

def force_std(force: NDArray[np.float64], config: StiffnessConfig) -> NDArray[np.float64]:
    """Standard deviation [N] of each force reading: ``force_noise_rel · |F| + force_noise_abs_n``."""
    return np.asarray(config.force_noise_rel * np.abs(force) + config.force_noise_abs_n)
