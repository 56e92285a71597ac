"""Meshless shape matching (Müller et al. 2005) and the β estimation of Caccamo et al. (2016).

References
----------
Müller, M., Heidelberger, B., Teschner, M., Gross, M. (2005). Meshless deformations based on
shape matching. ACM Transactions on Graphics 24(3), 471–478.
Caccamo, S., Güler, P., Kjellström, H., Kragic, D. (2016). Active Perception and Modeling of
Deformable Surfaces using Gaussian Processes and Position-based Dynamics. IEEE-RAS Humanoids.
"""

from __future__ import annotations

from deformap.msm._beta import BetaEstimate, estimate_beta
from deformap.msm._clusters import polar_rotation
from deformap.msm._config import ShapeMatchingConfig
from deformap.msm._grid import ParticleGrid
from deformap.msm._poke import PokeSimulation
from deformap.msm._simulate import shape_matching_goals, simulate_poke

__all__ = [
    "BetaEstimate",
    "ParticleGrid",
    "PokeSimulation",
    "ShapeMatchingConfig",
    "estimate_beta",
    "polar_rotation",
    "shape_matching_goals",
    "simulate_poke",
]
