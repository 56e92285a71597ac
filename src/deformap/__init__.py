"""deformap: map how deformable a surface is, region by region, from a few robot pokes.

The method is Caccamo et al., "Active Perception and Modeling of Deformable Surfaces using Gaussian
Processes and Position-based Dynamics", HUMANOIDS 2016: a Gaussian random field models the surface,
meshless shape matching explains each poke's dent with one deformability value β, and a second
Gaussian random field (the β-field) spreads the βs over the surface and chooses the next poke.

The packages, what each owns and may import, the data flow and the contracts are in
``docs/architecture.md`` (a test enforces its import table):

- :mod:`deformap.cloud`: point clouds, filters, tactile points, file and ROS 2 bag I/O;
- :mod:`deformap.gp`: the paper's kernel, exact and grid Gaussian random fields, hyperparameters;
- :mod:`deformap.msm`: meshless shape matching and the β estimation;
- :mod:`deformap.mechanics`: contact mechanics (tactile contact, Hertz, hardness ↔ modulus);
- :mod:`deformap.environment`: the ``Environment`` protocol a world or a robot implements;
- :mod:`deformap.explore`: the mapper and its concepts, the loop, poke records, the journal;
- :mod:`deformap.world`: the simulated world (scenarios, foam FEM, depth camera, probe);
- :mod:`deformap.replay`: recorded sessions written, read back and fed to the mapper;
- :mod:`deformap.eval`: metrics against ground truth, studies, Table I, benchmarks;
- :mod:`deformap.viz`: figures and 3D recordings (a leaf that nothing in the core imports);
- :mod:`deformap.run`: the application layer (run configuration, folders, reports, workflows);
- :mod:`deformap.cli`: the ``deformap`` command over :mod:`deformap.run`;
- :mod:`deformap.testing`: fixtures and tolerance helpers for tests.
"""

from __future__ import annotations

__version__ = "0.1.0"

from deformap.errors import DeformapError

__all__ = ["DeformapError", "__version__"]
