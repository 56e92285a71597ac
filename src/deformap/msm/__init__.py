"""Meshless shape matching (Müller et al. 2005) and the β estimation of Caccamo et al. (2016).

A poke is simulated for every β of a sweep at once, as the converged steady state of position-based
shape matching (:func:`simulate_poke`), and β̂ minimises the paper's E(β), the mean distance from
the simulated surface to the observed deformed one (:func:`estimate_beta`: a coarse sweep,
then a search on the ``beta_resolution`` grid around its minimum, each β started from the nearby
solved ones; the ROI's clusters and the banded Cholesky factorisations, shared by nearby β, are
computed once).

Two protocols (``ShapeMatchingConfig.contact``):

``"pinned"`` — the paper: the surface sheet, edges fixed, the particle nearest the contact pinned at
its observed depth. Converged, it does not separate foams: with the depth imposed, and depth is
what hardness changes, the dent of an elastic foam is matched best by the most rigid sheet
(β̂ = 0 whatever the hardness) on a nearly flat E(β).

``"force"`` (default) — the measured tactile force acts on the particles under the tip, the body's
spring stiffness is calibrated so that β = 0 dents like a 100 kPa elastic half-space, and the body
is the surface over three layers of particles down to a fixed floor (a sheet fixed at its edges can
only bend, and its dent is a cone as wide as the ROI). Softer foams dent deeper and need larger β:
β̂ falls with hardness, and a rigid surface gives β̂ = 0. The README ("β separates hardness only
under the force-driven protocol") has both protocols' βs on analytic and simulated dents.

References
----------
Müller, M., Heidelberger, B., Teschner, M., Gross, M. (2005). Meshless deformations based on
shape matching. ACM Transactions on Graphics 24(3), 471–478.
Caccamo, S., Güler, P., Kjellström, H., Kragic, D. (2016). Active Perception and Modeling of
Deformable Surfaces using Gaussian Processes and Position-based Dynamics. IEEE-RAS Humanoids.
"""

from __future__ import annotations

from deformap.msm._beta import BetaEstimate, estimate_beta, matching_error
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
    "matching_error",
    "polar_rotation",
    "shape_matching_goals",
    "simulate_poke",
]
