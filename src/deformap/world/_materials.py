"""What a foam block is made of besides its modulus: viscoelastic relaxation, in-plane anisotropy
and plasticity.

A block's ``youngs_modulus_pa`` (or ``hardness_n``) is the instantaneous modulus ``E₀``. With
:class:`Viscoelastic` it relaxes as the normalised Prony series (a generalised Maxwell solid)

    ``G(t) / E₀ = g∞ + Σ_i g_i exp(−t / τ_i)``,  ``g∞ + Σ_i g_i = 1``,

one term being the standard linear solid; the relaxation acts on the whole stress (Poisson's ratio
stays constant). With :class:`Orthotropic` the block is stiffer along an in-plane axis: Young's
moduli ``E₁ = ratio · E`` along the axis at ``axis_deg`` from x, ``E₂ = E₃ = E`` across it and
vertically, and Huber's orthotropy for the rest (``ν_ij / E_i = ν / sqrt(E_i E_j)``,
``G_ij = sqrt(E_i E_j) / (2 (1 + ν))``), which is isotropic at ratio 1 and positive definite for
every ratio when ``ν < 0.5``. With :class:`Plastic` it yields (von Mises, linear isotropic
hardening; :mod:`deformap.world._plastic`) and keeps a dent after release.

References
----------
Simo, J. C., Hughes, T. J. R. (1998). Computational Inelasticity, §10. Springer.
Huber, M. T. (1923). The theory of crosswise reinforced ferroconcrete slabs. Der Bauingenieur 4.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import SettingError, check_settings, setting

__all__ = ["Orthotropic", "Plastic", "Viscoelastic", "orthotropic_stiffness"]

_MAX_TERMS = 8  # Prony terms: more fit noise, not a foam


@dataclass(frozen=True, kw_only=True)
class Viscoelastic:
    """A Prony series of the block's relaxation (module docstring).

    Parameters
    ----------
    relaxed_ratio : float
        ``g∞ = E∞ / E₀``, the relaxed over the instantaneous modulus; 1 is elastic.
    times_s : tuple of float
        Relaxation times ``τ_i`` in seconds, one per Maxwell arm.
    weights : tuple of float or None
        Each arm's share of the relaxing part ``1 − g∞`` (summing to 1); None: equal shares.
    """

    # a foam that loses more than 99 % of its modulus is a liquid; g∞ = 1 is elastic
    relaxed_ratio: float = setting(0.5, ge=0.01, le=1.0, doc="relaxed / instantaneous modulus")
    # from a millisecond (faster than any robot samples) to a day
    times_s: tuple[float, ...] = setting((1.0,), ge=1e-3, le=86400.0, doc="relaxation times, s")
    weights: tuple[float, ...] | None = setting(None, gt=0.0, le=1.0,
                                                doc="share of the relaxing part per time")

    def __post_init__(self) -> None:
        check_settings(self)
        if not 1 <= len(self.times_s) <= _MAX_TERMS:
            raise SettingError("times_s", f"must hold 1 to {_MAX_TERMS} relaxation times; got "
                               f"{len(self.times_s)}")
        if self.weights is not None:
            if len(self.weights) != len(self.times_s):
                raise SettingError("weights", f"must hold one share per relaxation time "
                                   f"({len(self.times_s)}); got {len(self.weights)}")
            if abs(sum(self.weights) - 1.0) > 1e-6:
                raise SettingError("weights", f"must sum to 1; got {sum(self.weights):.6g}")

    @property
    def prony(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(g_i, τ_i)``, the arms' moduli over ``E₀`` and their times."""
        shares = (np.full(len(self.times_s), 1.0 / len(self.times_s)) if self.weights is None
                  else np.asarray(self.weights, dtype=float))
        return (1.0 - self.relaxed_ratio) * shares, np.asarray(self.times_s, dtype=float)

    @property
    def relaxation_fraction(self) -> float:
        """``1 − g∞``: the share of the instantaneous modulus that relaxes."""
        return 1.0 - self.relaxed_ratio

    @property
    def time_constant_s(self) -> float:
        """The arms' times weighted by their moduli (the one time of a standard linear solid)."""
        g, tau = self.prony
        return float(np.sum(g * tau) / np.sum(g)) if np.sum(g) > 0 else float(tau[0])

    def relaxation(self, t: Any) -> NDArray[np.float64]:
        """``G(t) / E₀`` at times ``t`` (seconds)."""
        g, tau = self.prony
        t = np.asarray(t, dtype=float)
        return np.asarray(self.relaxed_ratio + np.sum(
            g[:, None] * np.exp(-t.reshape(1, -1) / tau[:, None]), axis=0).reshape(t.shape))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"relaxed_ratio": self.relaxed_ratio, "times_s": list(self.times_s)}
        if self.weights is not None:
            out["weights"] = list(self.weights)
        return out


@dataclass(frozen=True, kw_only=True)
class Orthotropic:
    """In-plane anisotropy (module docstring).

    Parameters
    ----------
    ratio : float
        In-plane stiff over soft Young's modulus, ``E₁ / E₂``; 1 is isotropic.
    axis_deg : float
        Angle of the stiff axis from the x axis, degrees counter-clockwise.
    """

    # a woven or ribbed pad reaches about 10; beyond, a layer of fibres, not a foam
    ratio: float = setting(2.0, ge=1.0, le=20.0, doc="stiff / soft in-plane modulus")
    axis_deg: float = setting(0.0, ge=-180.0, le=180.0, doc="stiff axis from x, degrees")

    def __post_init__(self) -> None:
        check_settings(self)

    def to_dict(self) -> dict[str, Any]:
        return {"ratio": self.ratio, "axis_deg": self.axis_deg}


@dataclass(frozen=True, kw_only=True)
class Plastic:
    """J2 plasticity with linear isotropic hardening (:mod:`deformap.world._plastic`).

    Parameters
    ----------
    yield_stress_pa : float
        Initial yield stress ``σ_y`` (von Mises), Pa.
    hardening_pa : float
        Linear isotropic hardening modulus ``H``: the yield stress grows by ``H`` per unit of
        equivalent plastic strain, Pa.
    """

    # from a putty (10 Pa) to a stiff clay (10 MPa)
    yield_stress_pa: float = setting(2000.0, ge=10.0, le=1e7, doc="yield stress, Pa")
    # H > 0 keeps the initial-stress iterations contracting; 10 GPa is a metal's tangent
    hardening_pa: float = setting(1000.0, gt=0.0, le=1e10, doc="hardening modulus, Pa")

    def __post_init__(self) -> None:
        check_settings(self)

    def to_dict(self) -> dict[str, Any]:
        return {"yield_stress_pa": self.yield_stress_pa, "hardening_pa": self.hardening_pa}


def orthotropic_stiffness(ratio: float, axis_deg: float, nu: float) -> NDArray[np.float64]:
    """``(3, 3, 3, 3)`` elasticity tensor at unit soft modulus (module docstring), its stiff axis
    rotated ``axis_deg`` about z."""
    moduli = np.array([ratio, 1.0, 1.0])
    compliance = np.zeros((6, 6))
    root = np.sqrt(np.outer(moduli, moduli))
    compliance[:3, :3] = -nu / root
    compliance[np.arange(3), np.arange(3)] = 1.0 / moduli
    # Voigt order 11, 22, 33, 23, 13, 12 with engineering shear strains
    for v, (i, j) in zip((3, 4, 5), ((1, 2), (0, 2), (0, 1)), strict=True):
        compliance[v, v] = 2.0 * (1.0 + nu) / root[i, j]
    voigt = np.linalg.inv(compliance)
    pairs = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    tensor = np.zeros((3, 3, 3, 3))
    for a, (i, j) in enumerate(pairs):
        for b, (k, m) in enumerate(pairs):
            for ii, jj in {(i, j), (j, i)}:
                for kk, mm in {(k, m), (m, k)}:
                    tensor[ii, jj, kk, mm] = voigt[a, b]
    c, s = np.cos(np.radians(axis_deg)), np.sin(np.radians(axis_deg))
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.asarray(np.einsum("ia,jb,kc,ld,abcd->ijkl", rot, rot, rot, rot, tensor))
