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
spring stiffness ``k`` is calibrated so that the body of rigid goals dents like a 100 kPa elastic
half-space, and the body is the surface over three layers of particles down to a fixed floor (a
sheet fixed at its edges can only bend, and its dent is a cone as wide as the ROI). On the
default ``"odds"`` β scale the springs of β are ``k / β``: β = 0 is rigid and softer foams dent
deeper and need larger β. The README ("β separates hardness only under the force-driven
protocol") has both protocols' βs on analytic and simulated dents.

The β scale (``ShapeMatchingConfig.beta_scale``). Why the former scale saturated: on the
``"reference"`` scale every β's springs are ``k``, so β = 0 is the calibrated 100 kPa body, whose
dent is the shallowest any β produces (depth ``δ_ref``, Hertz at the measured force: ∝ ``F^(2/3)``,
whatever the ROI, grid or layers, since ``k`` absorbs them), and raising β only deepens it, about
as ``1 / (1 − β)`` (pole depth 1, 1.41, 1.95, 3.09, 7.96, 14.4, 32.5 × ``δ_ref`` at β = 0, 0.3,
0.5, 0.7, 0.9, 0.95, 0.98 on a 12 cm ROI, 0.6 N, 1 cm tip). The shape of that dent, not only its
depth, ends the window: the force is shared over the tip's radius, so the body's dent is as
wide as the tip (at 5 mm from the axis 0.85 of its pole depth; 0.83 on a 2.5 mm grid, 0.82 with
2 × 2 clusters, 0.11 with the whole force on one particle), where a Hertz dent falls to 0.60 /
0.42 / 0.29 of its depth at 19 / 39 / 100 kPa (its contact radius ``√(Rδ)`` shrinks as the
surface stiffens), and the body's dent dies out towards the fixed sides and floor (0.006 of its
depth at 3 cm) where Hertz's falls as ``1 / r`` (0.05 at 39 kPa). E(β) sums over the ROI: at 39
kPa the particles beyond 3 cm add 60 µm of the 90 µm at every β, and deepening the body's dent
to reach the observed pole (1 µm better) pushes the ring at 4–8 mm deeper below the observed one
(4.3 → 15.5 µm from β = 0 to 0.5), so β̂ = 0. On analytic Hertz dents (0.6 N, 1 cm tip, 12 cm ROI,
5 mm grid) that scale reads 0.93 / 0.87 / 0.76 / 0.67 / 0.43 for 2.3 / 4.6 / 8.5 / 11.6 / 19.4 kPa
(30–250 N foams) and 0 from 39 kPa (a 2.0 mm dent, about twice ``δ_ref``); at 0.3 N it is 0 from
39 kPa (19 kPa reads 0.19), at 3 N from 77 kPa. Moving the window does not widen it: a 400 kPa
reference reads 0.98 / 0.96 / 0.91 / 0.88 / 0.79 (the soft foams a step of the β resolution
apart) and still 0 at 77 kPa; calibrating on the reference's whole Hertz surface instead of its
pole depth reads 0.98 / 0.96 / 0.92 / 0.88 / 0.80 and 0 at 77 kPa; scaling every β's dent to the
measured indentation (β as pure shape) reads 0.99 / 0.90 / 0 / 0 / 0; sharing the force over the
Hertz contact radius at the measured indentation instead of the tip's is not monotone (0.64 at
19 kPa, 0.78 at 39 kPa: on a 5 mm grid the load's footprint jumps between one and five
particles).

The ``"odds"`` scale (default) removes the floor instead: β's springs are ``k / β`` (in PBD terms
the goal stiffness, Müller's α, is ``α₀ / β``), the same as the body carrying β times the force.
β = 0 is then the rigid body, as the paper defines it ("if β is close to 0, the object behaves
like a rigid body"), its dent zero; β's dent is β times the reference scale's β dent (both
linear bodies), so its depth runs continuously from 0 through about the reference's near β =
1/2 to the ROI's depth as β → 1, and the odds β / (1 − β) is the body's compliance against the
reference: a log axis, ``logit β`` rising with the logarithm of the dent's depth. No constant
is added (k is the same calibration, 100 kPa the same documented reference; β = 0 rigid is the
paper's). Its shape mismatch remains (the dent as wide as the tip), but with no depth floor it
only bends the scale: on the same analytic dents β̂ = 0.94 / 0.89 / 0.81 / 0.76 / 0.65 (2.3–19.4
kPa), 0.44 / 0.28 / 0.16 / 0.08 / 0.03 at 39 / 77 / 150 / 300 kPa / 1 MPa, and 0 for a rigid
surface, strictly monotone, about linear in ``log E`` on the logit axis (``logit β ≈ −2.4 log₁₀(E /
33 kPa)``); at 0.3 N 0.97 (1 kPa) … 0.02 / 0.01 (1 / 3 MPa), at 3 N 0.98 … 0.05 / 0.02, both
monotone. The stiff end is compressed (a step of the β resolution, 0.01, is about a seventh of a
decade of E near 1 MPa), not cut off. The force–travel record reads Young's modulus in physical
units (:func:`deformap.stiffness.estimate_stiffness`); a press it reads rigid is given β = 0 (the
rigid body, measured) by :func:`deformap.explore.measure_press`.

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
