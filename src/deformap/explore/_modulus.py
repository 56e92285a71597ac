"""The modulus field: a Gaussian random field over ln E (E in Pa) from the pokes' force–travel
records. A poke with a modulus enters as ``ln E`` with σ ``σ_E / E`` (delta method), at least the
field's floor, ``σ_E`` the reference contact model's own (the bonded layer's). The spread
between contact models in the estimate's σ is left out of the field and so of its σ: it is
taken as a bias that moves the pokes of one material alike (it does not scatter one material's
pokes), which holds where one model wins on all of them; it is not a constant across materials
(a foundation-like foam's bias grows with its stiffness), and each poke's own
``stiffness.modulus_std_pa`` keeps it. A *rigid* poke enters at its detection bound
(:func:`rigid_modulus_bound`) with ``rigid_log_std``, never a huge number that would drag the
prior mean; a poke without a usable record is left out
(:attr:`ModulusField.readings` says why).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError
from deformap.explore._config import FieldName, ModulusFieldConfig
from deformap.explore._field import PokeField, PokeSet, layer_thickness
from deformap.explore._records import PokeRecord
from deformap.mechanics import layer_indentation_force

__all__ = ["ModulusField", "ModulusReading", "modulus_reading", "rigid_modulus_bound"]


@dataclass(frozen=True)
class ModulusReading:
    """One poke on the modulus field's axis: its ``index``, ln E [ln Pa] and σ before the floor
    (``None`` when left out), whether it read ``rigid`` (ln E is then the detection bound), and why
    it is ``excluded`` (``None`` when it is in)."""

    index: int
    log_modulus: float | None
    log_std: float | None
    rigid: bool
    excluded: str | None

    def to_dict(self) -> dict[str, object]:
        return {"index": self.index, "log_modulus_ln_pa": self.log_modulus,
                "log_modulus_std": self.log_std, "rigid": self.rigid,
                "used": self.excluded is None, "excluded_because": self.excluded}  # fmt: skip


def rigid_modulus_bound(record: PokeRecord, poisson_ratio: float) -> float:
    """The smallest Young's modulus [Pa] a rigid poke's record could not tell from rigid:
    ``E_b = F / g(δ_b)`` with ``δ_b = F / k_lower`` the travel bound and ``g`` the bonded-layer
    force at unit modulus (Hertz's half-space without a layer thickness)."""
    estimate = record.stiffness
    if estimate is None or not estimate.rigid or estimate.stiffness_lower_n_per_m is None:
        raise InvalidArgumentError("`record` must be a poke whose force–travel record read rigid")
    force, radius, thickness = record.force_n, record.contact.tip_radius_m, record.layer_thickness_m
    depth = force / estimate.stiffness_lower_n_per_m
    if thickness is not None and np.isfinite(thickness) and thickness > depth:
        unit = float(layer_indentation_force(np.array([depth]), radius, thickness, 1.0,
                                             poisson_ratio)[0])  # fmt: skip
    else:
        unit = 4.0 / 3.0 / (1.0 - poisson_ratio**2) * np.sqrt(radius) * depth**1.5
    return float(force / unit)


def modulus_reading(record: PokeRecord, config: ModulusFieldConfig,
                    poisson_ratio: float) -> ModulusReading:
    """Where one poke sits on the ln E axis, or why it is left out (module docstring)."""
    estimate = record.stiffness
    if estimate is None:
        why = record.stiffness_error
        reason = ("no force–travel record came with the press" if why is None
                  else f"its force–travel record was not used: {why}")  # fmt: skip
        return ModulusReading(record.index, None, None, False, reason)
    if estimate.rigid:
        bound = rigid_modulus_bound(record, poisson_ratio)
        return ModulusReading(record.index, float(np.log(bound)), config.rigid_log_std, True, None)
    assert estimate.modulus_pa is not None and estimate.modulus_std_pa is not None
    # the reference contact model's own σ (module docstring): the models' spread is left out
    std = next((f.modulus_std_pa for f in estimate.model_fits if f.name == "bonded-layer"),
               estimate.modulus_std_pa)
    return ModulusReading(record.index, float(np.log(estimate.modulus_pa)),
                          float(std / estimate.modulus_pa), False, None)


class ModulusField(PokeField):
    """The modulus field over ln E [ln Pa] of the pokes that have a modulus (none: the prior)."""

    name: ClassVar[FieldName] = "modulus"

    def __init__(self, pokes: PokeSet, xs: NDArray[np.float64], ys: NDArray[np.float64],
                 config: ModulusFieldConfig, readings: Sequence[ModulusReading] = ()) -> None:
        super().__init__(pokes, xs, ys, config)
        self.readings = tuple(readings)

    @classmethod
    def of_records(cls, records: Sequence[PokeRecord], xs: NDArray[np.float64],
                   ys: NDArray[np.float64], config: ModulusFieldConfig,
                   poisson_ratio: float) -> ModulusField:
        """The modulus field of the pokes ``records`` that have a modulus or read rigid."""
        readings = [modulus_reading(r, config, poisson_ratio) for r in records]
        used = [(r, m) for r, m in zip(records, readings, strict=True) if m.excluded is None]
        xy = np.array([r.contact_xy for r, _ in used], dtype=float).reshape(-1, 2)
        values = np.array([m.log_modulus for _, m in used], dtype=float)
        noise = np.maximum(np.array([m.log_std for _, m in used], dtype=float), config.noise_floor)
        index = np.array([m.index for _, m in used], dtype=np.int64)
        thickness = layer_thickness([r for r, _ in used])
        return cls(PokeSet(xy, values, noise.reshape(-1), index, thickness=thickness), xs, ys,
                   config, readings)

    @property
    def std(self) -> NDArray[np.float64]:
        """Posterior standard deviation of ln E on the grid (without the contact models' spread:
        module docstring)."""
        return np.sqrt(self.variance)

    @cached_property
    def median_pa(self) -> NDArray[np.float64]:
        """``exp(mean)``: the posterior median of E [Pa] on the grid (NaN without a poke)."""
        return np.exp(self.mean)
