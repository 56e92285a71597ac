"""Foam hardness (ISO 2439 indentation force) to Young's modulus and back.

Foam makers grade polyurethane foam by its indentation hardness: the force ``H`` in newtons that a
flat circular indenter of 323 cm² (203 mm diameter, ISO 2439 / ASTM D3574) needs to compress a
sample to 40 % of its thickness. Reading that test as uniaxial compression of the material under the
indenter gives a secant modulus

    E = (H / A) / ε,    A = 0.0323 m²,  ε = 0.4,

ignoring the foam around the indenter and the non-linearity of foam at 40 % strain.

References
----------
ISO 2439 (2008). Flexible cellular polymeric materials — Determination of hardness (indentation
technique). ASTM D3574, test B1 (indentation force deflection).
"""

from __future__ import annotations

import numpy as np

from deformap._validation import check_positive

__all__ = ["INDENTATION_STRAIN", "INDENTER_AREA_M2", "hardness_to_youngs_modulus",
           "youngs_modulus_to_hardness"]

INDENTER_AREA_M2 = 0.0323
"""Area of the ISO 2439 indenter foot (203 mm diameter), m²."""

INDENTATION_STRAIN = 0.4
"""Compression at which the hardness force is read (40 % of the thickness)."""


def hardness_to_youngs_modulus(hardness_n: float) -> float:
    """Young's modulus ``(hardness_n / 0.0323) / 0.4`` in pascals of a foam of indentation
    hardness ``hardness_n > 0`` newtons."""
    h = check_positive("hardness_n", hardness_n)
    return float(h / INDENTER_AREA_M2 / INDENTATION_STRAIN)


def youngs_modulus_to_hardness(youngs_modulus_pa: float) -> float:
    """Inverse of :func:`hardness_to_youngs_modulus`: hardness in newtons of a modulus in Pa."""
    e = check_positive("youngs_modulus_pa", youngs_modulus_pa)
    return float(np.float64(e) * INDENTER_AREA_M2 * INDENTATION_STRAIN)
