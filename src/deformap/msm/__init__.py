"""Meshless shape matching (Müller et al. 2005) and the β estimation of Caccamo et al. (2016).

A poke is simulated for every β of a sweep as the converged steady state of position-based shape
matching (:func:`simulate_poke`); β̂ minimises the paper's E(β), the mean distance from the
simulated surface to the observed deformed one (:func:`estimate_beta`: a coarse sweep, then a
search on the ``beta_resolution`` grid around its minimum).

Two protocols (``ShapeMatchingConfig.contact``):

- ``"pinned"``, the paper's: the surface sheet, edges fixed, the particle nearest the contact
  pinned at its observed depth.
- ``"force"`` (default): the measured force acts on the particles under the tip; the spring
  stiffness ``k`` is calibrated so that the body of rigid goals dents like an elastic half-space of
  ``reference_modulus_pa`` (Hertz); the body is the surface over layers of particles down to a fixed
  floor, because a sheet fixed at its edges can only bend.

The β scale (``ShapeMatchingConfig.beta_scale``, force protocol only): on the default ``"odds"``
scale β's springs are ``k / β`` (Müller's goal stiffness ``α₀ / β``), so β = 0 is the rigid body
(the paper's "if β is close to 0, the object behaves like a rigid body") and the odds
β / (1 − β) is the body's compliance against the reference; β is monotone in the modulus with no
stiff end short of rigid. On the ``"reference"`` scale every β's springs are ``k`` and β = 0 is
the reference body, so every surface stiffer than about the reference reads β̂ = 0. A press the
force–travel record reads rigid is given β = 0 by :func:`deformap.explore.measure_press`.

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

__all__ = [
    "BetaEstimate",
    "ParticleGrid",
    "PokeSimulation",
    "ShapeMatchingConfig",
    "estimate_beta",
    "matching_error",
    "polar_rotation",
    "shape_matching_goals",
    "simulate_poke",
]
