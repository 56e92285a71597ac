"""Figures (matplotlib) and 3D recordings (rerun, optional). A leaf: nothing in the core imports it.

The ``plot_*`` functions take their data first and an optional ``path`` last; each returns a
:class:`matplotlib.figure.Figure` and, given ``path``, also writes it there atomically (format from
the suffix). Importing this package and drawing with it never selects a matplotlib backend, imports
``pyplot`` or changes ``rcParams``: it is safe in notebooks and GUI applications.
:func:`plot_beta_curve` draws onto an ``Axes`` you provide.
"""

from __future__ import annotations

from deformap.viz._figures import plot_map
from deformap.viz._poke import plot_beta_curve, plot_error_curve, plot_poke
from deformap.viz._rerun import hull_mesh, record_run
from deformap.viz._studies import (
    plot_behaviour_study,
    plot_cluster_size_study,
    plot_hardness_study,
)
from deformap.viz._world import show_world
from deformap.viz._worlds import plot_world_curves

__all__ = ["hull_mesh", "plot_behaviour_study", "plot_beta_curve", "plot_cluster_size_study",
           "plot_error_curve", "plot_hardness_study", "plot_map", "plot_poke", "plot_world_curves",
           "record_run", "show_world"]
