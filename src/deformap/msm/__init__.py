"""Meshless shape matching (Müller et al. 2005) and the β estimation of Caccamo et al. (2016).

A poke is simulated for each β as the steady state of position-based shape matching
(:func:`simulate_poke`); β̂ minimises the paper's E(β), the mean distance from the simulated
surface to the observed deformed one (:func:`estimate_beta`).

``ShapeMatchingConfig.contact``: ``"pinned"`` (the paper's) pins the sheet's particle nearest the
contact at its observed depth; ``"force"`` applies the measured force under the tip, on springs
``k`` calibrated so that the rigid-goal body, layered down to a fixed floor, dents like a Hertz
half-space of ``reference_modulus_pa``. ``beta_scale``: on ``"odds"`` β's springs are ``k / β``
(β = 0 rigid, as in the paper); on ``"reference"`` they are ``k`` (β = 0 the reference body).

References
----------
Müller, M., Heidelberger, B., Teschner, M., Gross, M. (2005). Meshless deformations based on
shape matching. ACM Transactions on Graphics 24(3), 471–478.
Caccamo, S., Güler, P., Kjellström, H., Kragic, D. (2016). Active Perception and Modeling of
Deformable Surfaces using Gaussian Processes and Position-based Dynamics. IEEE-RAS Humanoids.
"""

from __future__ import annotations

from deformap.msm._beta import BetaEstimate, estimate_beta, matching_error
from deformap.msm._config import ShapeMatchingConfig
from deformap.msm._grid import ParticleGrid
from deformap.msm._poke import PokeSimulation
from deformap.msm._polar import polar_rotation
from deformap.msm._simulate import shape_matching_goals, simulate_poke

__all__ = ["BetaEstimate", "ParticleGrid", "PokeSimulation", "ShapeMatchingConfig", "estimate_beta",
           "matching_error", "polar_rotation", "shape_matching_goals", "simulate_poke"]
