"""The map figure's behaviour panel: each region's class in its own colour, named on a categorical
colour bar and on the map."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from matplotlib.colors import to_hex

from deformap.errors import InvalidArgumentError
from deformap.viz import plot_map
from deformap.viz._figures import BEHAVIOUR_COLOURS

NAMES = ("elastic", "viscoelastic", "plastic", "unknown", "mixed")
XS, YS = np.linspace(0.0025, 0.5975, 120), np.linspace(0.0025, 0.3975, 80)
GX, _ = np.meshgrid(XS, YS)


def _kwargs(**extra: Any) -> dict[str, Any]:
    return {"beta": np.full(GX.shape, 0.5), "variance": np.full(GX.shape, 0.05),
            "contacts": np.array([[0.1, 0.2], [0.3, 0.2], [0.5, 0.2]]),
            "labels": np.digitize(GX, [0.2, 0.4]), **extra}


def test_the_behaviour_panel_colours_each_region_by_its_class() -> None:
    classes = np.choose(np.digitize(GX, [0.2, 0.4]), [0, 3, 2])  # elastic | unknown | plastic
    fig = plot_map(XS, YS, **_kwargs(behaviour_class=classes, behaviour_names=NAMES))
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert [ax.get_title() for ax in panels] == [
        "β-field, 3 region(s)", "behaviour by region (presses)",
        "β-field variance and contacts"]
    panel = panels[1]
    assert (panel.get_xlabel(), panel.get_ylabel()) == ("x [m]", "y [m]")
    image = panel.get_images()[0]
    shown = np.unique(np.ma.compressed(image.get_array()))
    colours = {to_hex(image.cmap(image.norm(v))) for v in shown}
    assert colours == {BEHAVIOUR_COLOURS[n] for n in ("elastic", "unknown", "plastic")}
    bar = next(ax for ax in fig.axes if ax.get_label() == "<colorbar>" and ax.get_yticklabels()
               and ax.get_yticklabels()[0].get_text() == "elastic")
    assert [t.get_text() for t in bar.get_yticklabels()] == ["elastic", "plastic", "unknown"]
    texts = sorted(t.get_text() for t in panel.texts if t.get_text().startswith("R"))
    assert texts == ["R1: elastic", "R2: unknown", "R3: plastic"]


def test_no_behaviour_panel_without_classes_and_bad_classes_are_refused() -> None:
    fig = plot_map(XS, YS, **_kwargs())
    assert len([ax for ax in fig.axes if ax.get_label() != "<colorbar>"]) == 2
    with pytest.raises(InvalidArgumentError, match="`behaviour_class`"):
        plot_map(XS, YS, **_kwargs(behaviour_class=np.zeros((3, 3), int), behaviour_names=NAMES))
    with pytest.raises(InvalidArgumentError, match="`behaviour_class`"):
        plot_map(XS, YS, **_kwargs(behaviour_class=np.full(GX.shape, 5), behaviour_names=NAMES))
    with pytest.raises(InvalidArgumentError, match="`behaviour_class`"):
        plot_map(XS, YS, **_kwargs(behaviour_class=np.zeros(GX.shape, int),
                                   behaviour_names=("rubbery",)))
