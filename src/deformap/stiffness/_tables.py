"""The contact models a force–travel record is compared against, each as ``F = E · g(δ)`` tabulated
for its inverse (:mod:`deformap.stiffness`, Contact models)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap.mechanics import (
    foundation_indentation,
    layer_chi_limit,
    layer_indentation_force,
    layer_indentation_stiffness,
)

__all__ = ["BONDED_LAYER", "CONTACT_MODELS", "FOUNDATION", "HALF_SPACE", "MAX_FOUNDATION_NU",
           "ContactTable", "contact_table"]

#: The bonded elastic layer (Hertz + Dimitriadis et al. 2002): the reference model, whose range
#: a record must lie in.
BONDED_LAYER = "bonded-layer"
#: Hertz's elastic half-space: the layer without its base.
HALF_SPACE = "half-space"
#: A two-parameter (Vlasov) foundation: vertical displacement only, one mode through the layer.
FOUNDATION = "foundation"
#: Every model a record is compared against, the reference first.
CONTACT_MODELS: tuple[str, ...] = (BONDED_LAYER, HALF_SPACE, FOUNDATION)
#: The foundation's spring needs a compressible layer (``M → ∞`` as ``ν → 0.5``): above this ``ν``
#: the model is left out, and its ``ν`` refits stop here.
MAX_FOUNDATION_NU = 0.49

_TABLE_SIZE = 800
# the layer's table stops short of where the series' force turns down, and at most at χ = 3
_CHI_FRACTION = 0.95
_CHI_CAP = 3.0


class ContactTable:
    """``g(δ)``, a model's force at unit modulus [N/Pa], on ``[δ₀, δ_lim]`` with its slope ``g'``.

    Below the table ``g`` follows the power law of its first two entries (Hertz: ``δ^(3/2)``).
    """

    def __init__(self, depth: NDArray[np.float64], force: NDArray[np.float64],
                 slope: NDArray[np.float64], contact_radius: NDArray[np.float64] | None = None,
                 ) -> None:
        self.depth = depth
        self.contact_radius = contact_radius
        self.depth_limit = float(depth[-1])
        self.log_depth = np.log(depth)
        self.log_force = np.log(force)
        self.log_slope = np.log(slope)
        self.power = float((self.log_force[1] - self.log_force[0])
                           / (self.log_depth[1] - self.log_depth[0]))

    @property
    def force_limit(self) -> float:
        """``g(δ_lim)``: the largest force per pascal the table holds."""
        return float(np.exp(self.log_force[-1]))

    def depth_at(self, force_per_pa: NDArray[np.float64]) -> NDArray[np.float64]:
        """``g⁻¹``: log–log interpolation, the first entries' power law below the table."""
        u = np.log(np.maximum(force_per_pa, 1e-300))
        below = self.log_depth[0] + (u - self.log_force[0]) / self.power
        inside = np.interp(u, self.log_force, self.log_depth)
        return np.asarray(np.exp(np.where(u < self.log_force[0], below, inside)))

    def force_at(self, depth: NDArray[np.float64]) -> NDArray[np.float64]:
        """``g(δ)`` for ``δ`` up to ``δ_lim``."""
        v = np.log(np.maximum(depth, 1e-300))
        below = self.log_force[0] + (v - self.log_depth[0]) * self.power
        inside = np.interp(v, self.log_depth, self.log_force)
        return np.asarray(np.exp(np.where(v < self.log_depth[0], below, inside)))

    def slope(self, depth: NDArray[np.float64]) -> NDArray[np.float64]:
        """``g'(δ)`` at unit modulus, N/m per Pa (the first entry's power law below the table)."""
        v = np.log(np.maximum(depth, 1e-300))
        below = self.log_slope[0] + (v - self.log_depth[0]) * (self.power - 1.0)
        inside = np.interp(v, self.log_depth, self.log_slope)
        return np.asarray(np.exp(np.where(v < self.log_depth[0], below, inside)))


def _layer(radius: float, thickness: float, nu: float, half_space: bool) -> ContactTable:
    if half_space:  # Hertz: the series' χ → 0 limit, to a sphere's depth
        h = 1e6 * radius
        depth = radius * np.geomspace(1e-9, 1.0, _TABLE_SIZE)
    else:
        h = thickness
        chi_lim = min(_CHI_FRACTION * layer_chi_limit(nu), _CHI_CAP)
        # nor deeper than the layer: with R < h that comes first (χ = √(R/h) < 1 at δ = h)
        depth = min((chi_lim * h) ** 2 / radius, h) * np.geomspace(1e-9, 1.0, _TABLE_SIZE)
    return ContactTable(depth, layer_indentation_force(depth, radius, h, 1.0, nu),
                        layer_indentation_stiffness(depth, radius, h, 1.0, nu))


def _foundation(radius: float, thickness: float, nu: float) -> ContactTable:
    # the contact radius from a millionth of the tip's to all of it; a sphere's depth at most
    contact = radius * np.geomspace(1e-6, 1.0, _TABLE_SIZE)
    depth, force = foundation_indentation(contact, radius, thickness, 1.0, nu)
    keep = depth <= min(radius, thickness)
    depth, force, contact = depth[keep], force[keep], contact[keep]
    slope = force / depth * np.gradient(np.log(force), np.log(depth))
    return ContactTable(depth, force, slope, contact)


def contact_table(model: str, radius: float, thickness: float, nu: float) -> ContactTable:
    """The table of ``model`` (one of :data:`CONTACT_MODELS`) for a tip of ``radius`` on a layer
    of ``thickness`` [m] with Poisson's ratio ``nu`` (the foundation's needs ``nu < 0.5``)."""
    if model == BONDED_LAYER:
        return _layer(radius, thickness, nu, half_space=False)
    if model == HALF_SPACE:
        return _layer(radius, thickness, nu, half_space=True)
    if model == FOUNDATION:
        return _foundation(radius, thickness, nu)
    raise ValueError(f"unknown contact model {model!r}")
