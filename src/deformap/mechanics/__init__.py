"""Contact mechanics: the tactile contact, Hertz contact of the probe's sphere, a sphere on a bonded
elastic layer (its force and its surface) and on a two-parameter (Vlasov) foundation, foam hardness.

The physics both the simulated world and the estimator use (SI units); it imports numpy, scipy's
special functions and the validators only, so that ``world`` can use it without the estimator.
Each module gives its references.
"""

from __future__ import annotations

from deformap.mechanics._contact import TactileContact
from deformap.mechanics._foundation import foundation_indentation, foundation_surface_deflection
from deformap.mechanics._hardness import (
    INDENTATION_STRAIN,
    INDENTER_AREA_M2,
    hardness_to_youngs_modulus,
    youngs_modulus_to_hardness,
)
from deformap.mechanics._hertz import (
    elastic_dent,
    hertz_contact_radius,
    hertz_indentation,
    hertz_pressure_samples,
    hertz_surface_at_depth,
    hertz_surface_deflection,
    reduced_modulus,
)
from deformap.mechanics._layer import (
    layer_chi_limit,
    layer_correction,
    layer_correction_coefficients,
    layer_indentation_force,
    layer_indentation_stiffness,
)
from deformap.mechanics._layer_surface import layer_surface_deflection

__all__ = [
    "INDENTATION_STRAIN", "INDENTER_AREA_M2", "TactileContact", "elastic_dent",
    "foundation_indentation", "foundation_surface_deflection",
    "hardness_to_youngs_modulus", "hertz_contact_radius", "hertz_indentation",
    "hertz_pressure_samples", "hertz_surface_at_depth", "hertz_surface_deflection",
    "layer_chi_limit", "layer_correction",
    "layer_correction_coefficients", "layer_indentation_force", "layer_indentation_stiffness",
    "layer_surface_deflection", "reduced_modulus", "youngs_modulus_to_hardness",
]
