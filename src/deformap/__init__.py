"""deformap: map how deformable a surface is, region by region, from a few robot pokes.

The method is Caccamo et al., "Active Perception and Modeling of Deformable Surfaces using Gaussian
Processes and Position-based Dynamics", HUMANOIDS 2016: a Gaussian random field models the surface,
meshless shape matching explains each poke's dent with one deformability value β, and a second
Gaussian random field (the β-field) spreads the βs over the surface and chooses the next poke.

Subpackages follow the architecture of ``DESIGN.md``: :mod:`deformap.cloud`, :mod:`deformap.gp`,
:mod:`deformap.msm`, :mod:`deformap.explore`, :mod:`deformap.world`, :mod:`deformap.replay`,
:mod:`deformap.eval` and :mod:`deformap.viz` (a leaf that nothing in the core imports).
"""

from __future__ import annotations

__version__ = "0.1.0"

from deformap.errors import DeformapError

__all__ = ["DeformapError", "__version__"]
