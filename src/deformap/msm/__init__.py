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

The β scale's window: β lives in [0, 1) and the body's stiffness is one number, so β reads a window
of stiffnesses whose stiff end is set by the calibration. On analytic Hertz dents (0.6 N, 1 cm tip)
β̂ reaches 0 once the dent is shallower than about twice the reference's pole depth, not at the
reference itself (the β = 0 body's dent is wider than Hertz's, and E(β) compares the whole ROI):
100 kPa reads 0.93 / 0.87 / 0.76 / 0.67 / 0.43 for 30 / 60 / 110 / 150 / 250 N (19 kPa, a 3.1 mm
dent) and 0 at 39 kPa (a 2.0 mm dent) and stiffer. Moving the window does not widen it: a 400 kPa
reference reads 0.98 / 0.96 / 0.91 / 0.88 / 0.79 (the soft foams a step of the β resolution apart)
and still 0 at 77 kPa; calibrating on the reference's whole Hertz surface instead of its pole depth
reads 0.98 / 0.96 / 0.92 / 0.88 / 0.80 and 0 at 77 kPa; scaling every β's dent to the measured
indentation (β as pure shape) reads 0.99 / 0.90 / 0 / 0 / 0. Past the window's stiff end the
force–travel record carries the reading (Young's modulus,
:func:`deformap.explore.estimate_stiffness`); a fixed reference is kept so that β means the same on
every poke and in every session.

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
