"""Meshless shape matching (Müller et al. 2005) and the β estimation of Caccamo et al. (2016).

A poke is simulated for each β as the steady state of position-based shape matching
(:func:`simulate_poke`); β̂ minimises the paper's E(β), the mean distance from the simulated
surface to the observed deformed one (:func:`estimate_beta`).

``ShapeMatchingConfig.contact``: ``"pinned"``, the paper's protocol, is the surface sheet with
fixed edges and the particle nearest the contact pinned at its observed depth; ``"force"``
(default) applies the measured force to the particles under the tip, with a spring stiffness
``k`` calibrated so that the rigid-goal body dents like a Hertz half-space of
``reference_modulus_pa``, on layers down to a fixed floor (a sheet fixed at its edges can only
bend). ``beta_scale`` (force only): on ``"odds"`` β's springs are ``k / β``, so β = 0 is rigid
(the paper's meaning) and β / (1 − β) the compliance against the reference; on ``"reference"``
every β's springs are ``k`` and β = 0 is the reference body.

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
