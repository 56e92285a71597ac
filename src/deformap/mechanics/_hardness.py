"""Foam hardness (ISO 2439 indentation force) to Young's modulus and back.

The hardness ``H`` is the force in newtons that a flat indenter of 323 cm² needs to compress a
sample to 40 % of its thickness; read as uniaxial compression under the indenter (ignoring the foam
around it and the non-linearity at 40 % strain) it gives the secant modulus
``E = (H / A) / ε``, ``A = 0.0323 m²``, ``ε = 0.4``.

References
----------
ISO 2439 (2008). Flexible cellular polymeric materials — Determination of hardness.
"""

from __future__ import annotations

import numpy as np

from deformap._validation import check_positive

__all__ = ["INDENTATION_STRAIN", "INDENTER_AREA_M2", "hardness_to_youngs_modulus",
           "youngs_modulus_to_hardness"]

INDENTER_AREA_M2 = 0.0323  # the ISO 2439 indenter foot (203 mm diameter), m²
INDENTATION_STRAIN = 0.4  # the compression at which the hardness force is read


def hardness_to_youngs_modulus(hardness_n: float) -> float:
    """Young's modulus ``(hardness_n / 0.0323) / 0.4`` in pascals of a foam of indentation
    hardness ``hardness_n > 0`` newtons."""
    h = check_positive("hardness_n", hardness_n)
    return float(h / INDENTER_AREA_M2 / INDENTATION_STRAIN)


def youngs_modulus_to_hardness(youngs_modulus_pa: float) -> float:
    """Inverse of :func:`hardness_to_youngs_modulus`: hardness in newtons of a modulus in Pa."""
    e = check_positive("youngs_modulus_pa", youngs_modulus_pa)
    return float(np.float64(e) * INDENTER_AREA_M2 * INDENTATION_STRAIN)
