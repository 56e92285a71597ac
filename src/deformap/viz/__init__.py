"""Figures (matplotlib) and 3D recordings (rerun, optional). A leaf: nothing in the core imports it."""

from __future__ import annotations

from deformap.viz._figures import plot_beta_curve, plot_map, plot_poke

__all__ = ["plot_beta_curve", "plot_map", "plot_poke"]
