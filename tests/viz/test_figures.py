"""Figures: each plot function returns its Figure, writes it only when given a path, atomically,
and nothing in deformap.viz touches matplotlib's global state (backend, rcParams, pyplot)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.image import imread
from matplotlib.text import Text

from deformap.errors import InvalidArgumentError
from deformap.viz import (
    plot_cluster_size_study,
    plot_error_curve,
    plot_hardness_study,
    plot_map,
    plot_poke,
    show_world,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _map_args(truth: bool = True) -> tuple[tuple[Any, ...], dict[str, Any]]:
    xs, ys = np.linspace(0.0025, 0.5975, 120), np.linspace(0.0025, 0.3975, 80)
    gx, _ = np.meshgrid(xs, ys)
    kwargs = {
        "beta": np.where(gx < 0.3, 0.8, 0.2),
        "variance": 0.05 + 0.04 * (gx / 0.6),
        "contacts": np.array([[0.3, 0.2], [0.1, 0.1], [0.5, 0.3]]),
        "labels": (gx >= 0.3).astype(int),
        "levels": np.array([0.5]),
        "truth_hardness": np.where(gx < 0.3, 60.0, np.inf) if truth else None,
        "threshold": 0.06,
        "title": "two blocks",
    }
    return (xs, ys), kwargs


def _poke_kwargs() -> dict[str, Any]:
    xs = ys = np.linspace(-0.06, 0.06, 25)
    gx, gy = np.meshgrid(xs, ys)
    rest = np.full(gx.shape, 0.05)
    dent = rest - 0.005 * np.exp(-(gx**2 + gy**2) / 0.01**2)
    pts = np.column_stack([gx.ravel(), gy.ravel(), dent.ravel()])
    betas = np.linspace(0, 0.98, 50)
    return {
        "roi_xs": xs, "roi_ys": ys, "rest_z": rest, "deformed_z": dent, "roi_points": pts,
        "tactile": pts[:10], "betas": betas, "errors": (betas - 0.4) ** 2 + 1e-3, "beta": 0.4,
        "beta_std": 0.05, "simulated_z": dent, "title": "poke 1",
    }  # fmt: skip


def _hardness_study() -> dict[str, Any]:
    rows = [
        {"protocol": protocol, "hardness_n": h, "beta": b + shift, "beta_std": 0.03}
        for protocol, shift in (("paper", 0.0), ("force", 0.05))
        for h, b in ((None, 0.02), (150.0, 0.3), (110.0, 0.45), (60.0, 0.7))
    ]
    return {"rows": rows, "monotone": {"paper": True, "force": False}}


def _cluster_size_study() -> dict[str, Any]:
    rows = [
        {"cluster_size": k, "hardness_n": h, "fit_error_m": 0.0005 * k}
        for k in (2, 3, 4, 5, 6)
        for h in (60.0, 150.0, None)
    ]
    return {"rows": rows}


def _panels(fig: Figure) -> list[Any]:
    return [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]


def _colorbar_labels(fig: Figure) -> list[str]:
    return [ax.get_ylabel() for ax in fig.axes if ax.get_label() == "<colorbar>"]


# every public plot function, called with its data and a path
CALLS = {
    "map": lambda path: plot_map(*_map_args()[0], **_map_args()[1], path=path),
    "poke": lambda path: plot_poke(**_poke_kwargs(), path=path),
    "error_curve": lambda path: plot_error_curve(
        np.linspace(0, 0.98, 50), np.linspace(0.002, 0.001, 50), 0.4, 0.05, path=path
    ),
    "hardness": lambda path: plot_hardness_study(_hardness_study(), path=path),
    "cluster_size": lambda path: plot_cluster_size_study(_cluster_size_study(), path=path),
}


@pytest.fixture(autouse=True)
def _no_pyplot_figure_left_open() -> Any:
    import matplotlib.pyplot as plt  # here, not at the top: the subprocess below imports this module

    plt.close("all")
    yield
    assert plt.get_fignums() == []


@pytest.mark.parametrize("name", sorted(CALLS))
def test_returns_a_figure_and_writes_a_png_only_when_given_a_path(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # a stray write to a relative default name would land here
    fig = CALLS[name](None)
    assert isinstance(fig, Figure)
    assert list(tmp_path.iterdir()) == []
    path = tmp_path / f"{name}.png"
    fig = CALLS[name](path)
    assert isinstance(fig, Figure)
    assert sorted(tmp_path.iterdir()) == [path]  # no temporary file left beside it
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC
    image = imread(path)
    assert image[..., :3].std() > 0.05  # not a blank canvas
    width, height = fig.get_size_inches()
    dpi = 100 if name == "poke" else 110
    assert image.shape[:2] == (round(height * dpi), round(width * dpi))


def test_path_may_be_a_string_and_the_format_follows_the_suffix(tmp_path: Path) -> None:
    path = tmp_path / "curve.svg"
    plot_error_curve(np.array([0.0, 0.5, 0.9]), np.array([2e-3, 1e-3, 3e-3]), 0.5, 0.1,
                     path=str(path))  # fmt: skip
    assert path.read_text().lstrip().startswith("<?xml")


def test_map_figure_panels_labels_and_colour_bars() -> None:
    args, kwargs = _map_args()
    fig = plot_map(*args, **kwargs)
    panels = _panels(fig)
    assert [ax.get_title() for ax in panels] == [
        "ground truth",
        "β-field, 2 region(s)",
        "β-field variance and contacts",
    ]
    assert all((ax.get_xlabel(), ax.get_ylabel()) == ("x [m]", "y [m]") for ax in panels)
    assert _colorbar_labels(fig) == [
        "true E [kPa] (log scale; grey: rigid)",
        "β (deformability) [–]; 1 soft, 0 stiff",
        "var(β)",
    ]
    assert fig.get_suptitle() == "two blocks"
    # without ground truth: two panels
    args, kwargs = _map_args(truth=False)
    fig = plot_map(*args, **kwargs)
    assert [ax.get_title() for ax in _panels(fig)] == [
        "β-field, 2 region(s)",
        "β-field variance and contacts",
    ]


def test_map_figure_gains_a_modulus_panel_in_kpa_on_a_log_scale() -> None:
    from matplotlib.colors import LogNorm

    args, kwargs = _map_args()
    gx, _ = np.meshgrid(*args)
    modulus = np.where(gx < 0.3, 6e3, 2e4)
    fig = plot_map(*args, **kwargs, modulus_pa=modulus)
    panels = _panels(fig)
    assert [ax.get_title() for ax in panels] == [
        "ground truth",
        "β-field, 2 region(s)",
        "modulus field",
        "β-field variance and contacts",
    ]
    assert _colorbar_labels(fig)[2] == "Young's modulus E [kPa] (log scale)"
    image = panels[2].get_images()[0]
    assert isinstance(image.norm, LogNorm)
    assert image.get_array().max() == pytest.approx(20.0)  # kPa
    assert image.norm.vmax / image.norm.vmin >= 10.0
    # regions cut from the modulus field: its panel has them and the variance is of ln E
    kwargs.update(levels=np.array([np.log(1.1e4)]), variance=kwargs["variance"] * 30)
    fig = plot_map(*args, **kwargs, modulus_pa=modulus, region_field="modulus")
    assert [ax.get_title() for ax in _panels(fig)][1:] == [
        "β-field",
        "modulus field, 2 region(s)",
        "modulus-field variance and contacts",
    ]
    assert _colorbar_labels(fig)[-1] == "var(ln E)"
    with pytest.raises(ValueError, match="modulus_pa"):
        plot_map(*args, **kwargs, region_field="modulus")


def test_poke_figure_panels_and_labels() -> None:
    fig = plot_poke(**_poke_kwargs())
    panels = _panels(fig)
    assert [ax.get_title() for ax in panels] == [
        "ROI before (surface GP)",
        "cloud pressed, robot removed",
        "observed dent (touch GP)",
        "shape matching at β̂ = 0.400",
        "section through the contact (y = 0 mm)",
        "shape-matching error ε(β)",
        "force–travel record",
    ]
    # every panel names its axes with units, every length in millimetres
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in panels] == [
        *[("x [mm]", "y [mm]")] * 4, ("x [mm]", "z [mm]"),
        ("β [–]", "shape-matching error ε(β) [mm]"),
        ("travel since first contact [mm]", "force [N]"),
    ]  # fmt: skip
    assert _colorbar_labels(fig) == ["z [mm] (own scale)", "z [mm]", "z [mm]", "z [mm]"]
    section = panels[4].get_legend()
    assert [t.get_text() for t in section.get_texts()] == [
        "before (surface GP)",
        "observed dent (touch GP)",
        "shape matching at β̂",
        "cloud points on the section",
    ]
    # the legends sit below their axes, where they cover no data (the dent is mid-section)
    for ax in (panels[1], panels[4]):
        assert ax.get_legend()._loc == 9 and ax.get_legend().get_bbox_to_anchor().y1 < \
            ax.get_window_extent().y0 + 1
    # the simulated dent is drawn beside the observed one, on the same colour scale
    observed, simulated = panels[2].get_images()[0], panels[3].get_images()[0]
    assert observed.get_clim() == simulated.get_clim()
    assert np.allclose(simulated.get_array(), _poke_kwargs()["simulated_z"] * 1e3)
    # the suptitle sits above every panel's title
    fig.canvas.draw()
    (top,) = [t.get_window_extent() for t in fig.findobj(Text) if t.get_text() == "poke 1"]
    assert all(ax.title.get_window_extent().y1 < top.y0 for ax in panels)
    # without a record, the force panel says so
    assert "no force–travel record" in [t.get_text() for t in panels[6].texts]


def test_poke_figure_draws_the_force_travel_record_and_its_fit() -> None:
    travel = np.linspace(0.0, 0.004, 8)
    fit = np.vstack([np.linspace(0.0, 0.004, 30), 40.0 * np.linspace(0.0, 0.004, 30) ** 1.5])
    fig = plot_poke(**_poke_kwargs(), force_travel=(travel, 40.0 * travel**1.5), force_fit=fit,
                    reading="E = 9.7 ± 0.7 kPa")  # fmt: skip
    press = _panels(fig)[6]
    record, curve = press.get_lines()
    assert np.allclose(record.get_xdata(), travel * 1e3)  # millimetres
    assert np.allclose(curve.get_ydata(), fit[1])
    assert [t.get_text() for t in press.get_legend().get_texts()] == [
        "record", "contact model fitted: E = 9.7 ± 0.7 kPa"]
    # a rigid reading has no fit: the record and the reading
    fig = plot_poke(**_poke_kwargs(), force_travel=(travel * 0, travel * 100), reading="rigid")
    assert [t.get_text() for t in _panels(fig)[6].get_legend().get_texts()] == ["record", "rigid"]


def test_poke_figure_shows_the_surface_before_on_its_own_scale() -> None:
    kwargs = _poke_kwargs()
    xs = kwargs["roi_xs"]
    kwargs["rest_z"] = 0.05 + 0.02 * (xs[None, :] + 0.06) + 0 * kwargs["rest_z"]  # 2.4 mm slope
    fig = plot_poke(**kwargs)
    before = _panels(fig)[0].get_images()[0]
    low, high = before.get_clim()
    assert (low, high) == pytest.approx((kwargs["rest_z"].min() * 1e3,
                                         kwargs["rest_z"].max() * 1e3))  # fmt: skip
    # a flat surface: at least a millimetre of scale, not its round-off blown up
    kwargs["rest_z"] = np.full_like(kwargs["rest_z"], 0.05)
    low, high = _panels(plot_poke(**kwargs))[0].get_images()[0].get_clim()
    assert high - low == pytest.approx(1.0)
    # without a simulation, its panel says so
    kwargs["simulated_z"] = None
    texts = [t.get_text() for t in _panels(plot_poke(**kwargs))[3].texts]
    assert texts == ["not simulated"]


def test_map_figure_legend_threshold_label_and_region_values() -> None:
    args, kwargs = _map_args()
    fig = plot_map(*args, **kwargs, purposes=["first", "variance", "boundary"])
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == [
        "first poke", "later pokes", "boundary pokes", "region boundary",
        "variance = T_h (0.06)",
    ]  # fmt: skip
    panels = _panels(fig)
    variance = panels[-1]
    assert [t.get_text() for t in variance.texts if t.get_text() == "T_h"] == ["T_h"]
    # each region named at a cell inside it with its mean β
    names = sorted(t.get_text() for t in panels[1].texts if t.get_text().startswith("R"))
    assert names == ["R1: β = 0.80", "R2: β = 0.20"]
    # without boundary pokes, no boundary entry; marks per purpose
    fig = plot_map(*args, **kwargs)
    assert "boundary pokes" not in [t.get_text() for t in fig.legends[0].get_texts()]
    # the modulus panel names each region's E
    gx, _ = np.meshgrid(*args)
    fig = plot_map(*args, **kwargs, modulus_pa=np.where(gx < 0.3, 6e3, 2e4))
    names = sorted(t.get_text() for t in _panels(fig)[2].texts if t.get_text().startswith("R"))
    assert names == ["R1: E = 6 kPa", "R2: E = 20 kPa"]
    with pytest.raises(InvalidArgumentError, match="purposes"):
        plot_map(*args, **kwargs, purposes=["first"])


def test_map_figure_draws_stiffness_one_way_and_the_truth_on_the_maps_scale() -> None:
    from matplotlib.colors import LogNorm

    args, kwargs = _map_args()
    gx, _ = np.meshgrid(*args)
    fig = plot_map(*args, **kwargs, modulus_pa=np.where(gx < 0.3, 6e3, 2e4))
    truth, beta, modulus = (ax.get_images()[0] for ax in _panels(fig)[:3])
    # the truth is E in kPa (60 N is 4.64 kPa), on the modulus panel's scale and colour map
    assert np.nanmax(truth.get_array()) == pytest.approx(60.0 / 0.0323 / 0.4 / 1e3)
    assert isinstance(truth.norm, LogNorm)
    assert (truth.norm.vmin, truth.norm.vmax) == (modulus.norm.vmin, modulus.norm.vmax)
    assert truth.norm.vmin <= 4.64 and modulus.norm.vmax >= 20.0
    # soft is the dark end everywhere: low E, and high β (the reversed map)
    dark = np.mean(modulus.cmap(0.0)[:3])
    assert np.mean(modulus.cmap(1.0)[:3]) > dark
    assert np.allclose(beta.cmap(1.0), modulus.cmap(0.0)) and truth.cmap.name == modulus.cmap.name
    assert "rigid" in [t.get_text() for t in _panels(fig)[0].texts]


def test_map_figure_names_regions_with_the_reports_values_and_rigid_as_rigid() -> None:
    args, kwargs = _map_args()
    gx, _ = np.meshgrid(*args)
    fig = plot_map(*args, **kwargs, modulus_pa=np.where(gx < 0.3, 6e3, 6e5),
                   class_betas=[0.83, 0.01], class_modulus_pa=[5.1e3, 6.3e5],
                   rigid_classes={1})  # fmt: skip
    names = [sorted(t.get_text() for t in ax.texts if t.get_text().startswith("R"))
             for ax in _panels(fig)[1:3]]  # fmt: skip
    assert names == [["R1: β = 0.83", "R2: rigid"], ["R1: E = 5.1 kPa", "R2: rigid"]]


def test_map_figure_says_when_the_variance_never_crosses_t_h() -> None:
    args, kwargs = _map_args()
    for threshold, side in ((0.5, "below"), (0.01, "above")):
        fig = plot_map(*args, **{**kwargs, "threshold": threshold})
        texts = [t.get_text() for t in fig.legends[0].get_texts()]
        assert f"variance {side} T_h ({threshold:g}) everywhere: no T_h contour" in texts
        assert not any(t.startswith("variance = T_h") for t in texts)
        assert "T_h" not in [t.get_text() for t in _panels(fig)[-1].texts]


def test_map_figure_keeps_region_labels_clear_of_the_pokes() -> None:
    args, kwargs = _map_args()
    # a poke at each region's deepest cell, where the label went before
    contacts = np.array([[0.15, 0.2], [0.45, 0.2], [0.1, 0.1]])
    fig = plot_map(*args, **{**kwargs, "contacts": contacts})
    fig.canvas.draw()
    ax = _panels(fig)[1]
    boxes = [t.get_window_extent() for t in ax.texts if t.get_text().startswith("R")]
    marks = ax.transData.transform(contacts)
    assert len(boxes) == 2
    for box in boxes:
        for mx, my in marks:
            inside = box.x0 - 8 < mx < box.x1 + 8 and box.y0 - 8 < my < box.y1 + 8
            assert not inside, (box, (mx, my))


def test_map_figure_variance_scale_can_be_fixed_so_runs_compare() -> None:
    args, kwargs = _map_args()
    own = _panels(plot_map(*args, **kwargs))[-1].get_images()[0]
    assert own.get_clim() == pytest.approx((0.0, kwargs["variance"].max()))
    fig = plot_map(*args, **kwargs, variance_max=0.5)
    fixed = _panels(fig)[-1].get_images()[0]
    assert fixed.get_clim() == (0.0, 0.5)
    assert _colorbar_labels(fig)[-1] == "var(β) (fixed scale)"
    with pytest.raises(InvalidArgumentError, match="variance_max"):
        plot_map(*args, **kwargs, variance_max=0.0)


def test_error_curve_figure() -> None:
    betas = np.array([0.9, 0.0, 0.5])  # any order: drawn sorted
    fig = plot_error_curve(betas, np.array([3e-3, 2e-3, 1e-3]), 0.5, 0.1)
    (ax,) = fig.axes
    assert (ax.get_title(), ax.get_xlabel(), ax.get_ylabel()) == (
        "shape-matching error ε(β)",
        "β [–]",
        "shape-matching error ε(β) [mm]",
    )
    curve = ax.get_lines()[0]
    assert np.array_equal(curve.get_xdata(), [0.0, 0.5, 0.9])
    assert np.allclose(curve.get_ydata(), [2.0, 1.0, 3.0])  # millimetres
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["β̂ = 0.500 ± 0.100"]


def test_study_figures() -> None:
    fig = plot_hardness_study(_hardness_study())
    (ax,) = fig.axes
    assert ax.get_ylabel() == "estimated β [–]"
    assert ax.get_xlabel().startswith("hardness H [N]")
    assert ax.get_xscale() == "log" and ax.xaxis_inverted()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "rigid board (filled ◆, its own tick)",
        "paper ✓ monotone",
        "force ✗ not monotone",
    ]
    # ticks at the tested hardnesses and one for rigid, nothing else
    fig.canvas.draw()
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert sorted(labels) == sorted(["60", "110", "150", "rigid"])
    assert ax.get_xticklabels(minor=True) == [] or all(
        t.get_text() == "" for t in ax.get_xticklabels(minor=True))
    # every protocol visible where they read alike: a little apart in x, own marker
    lines = [line for line in ax.get_lines()
             if len(line.get_xdata()) == 3 and line.get_linestyle() != "None"]  # not the caps
    assert len(lines) == 2
    assert lines[0].get_marker() != lines[1].get_marker()
    assert not np.allclose(np.asarray(lines[0].get_xdata(), dtype=float),
                           np.asarray(lines[1].get_xdata(), dtype=float))
    fig = plot_cluster_size_study(_cluster_size_study())
    (ax,) = fig.axes
    assert (ax.get_xlabel(), ax.get_ylabel()) == (
        "cluster size k (k×k particles)",
        "fit error min ε(β) [mm]",
    )
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["60 N", "150 N", "rigid"]
    assert np.allclose(ax.get_lines()[0].get_ydata(), [1.0, 1.5, 2.0, 2.5, 3.0])
    ticks = [t for t in ax.get_xticks() if 2 <= t <= 6]
    assert ticks == [2, 3, 4, 5, 6]  # whole cluster sizes only


def test_hardness_figure_puts_e_beside_beta_and_its_conditions_in_the_title() -> None:
    study = _hardness_study()
    for r in study["rows"]:
        h = r["hardness_n"]
        r.update(rigid=h is None, modulus_pa=None if h is None else h / 0.0323 / 0.4 * 1.2,
                 modulus_std_pa=None if h is None else 100.0,
                 true_modulus_pa=None if h is None else h / 0.0323 / 0.4)  # fmt: skip
    study.update(force_n=0.6, thickness_m=0.05, camera="primesense", physics="linear-fem")
    fig = plot_hardness_study(study)
    beta, modulus = fig.axes
    assert fig.get_suptitle() == ("β and E against hardness (force 0.6 N, foam 5 cm thick, "
                                  "camera primesense, physics linear-fem)")
    assert (beta.get_ylabel(), modulus.get_ylabel()) == (
        "estimated β [–]", "Young's modulus E [kPa] (log scale)")
    assert modulus.get_yscale() == "log" and modulus.get_xlim() == beta.get_xlim()
    assert [t.get_text() for t in modulus.get_legend().get_texts()] == [
        "true E (from H, ISO 2439)", "E read from the force–travel record (± claimed σ)"]
    read, true = (line for line in modulus.get_lines()
                  if len(line.get_xdata()) == 3 and line.get_linestyle() != "None")  # no caps
    assert np.allclose(np.asarray(true.get_ydata(), dtype=float),
                       np.array([150, 110, 60]) / 0.0323 / 0.4 / 1e3)
    assert np.allclose(np.asarray(read.get_ydata(), dtype=float),
                       np.asarray(true.get_ydata(), dtype=float) * 1.2)  # fmt: skip
    assert "read rigid" in [t.get_text() for t in modulus.texts]


def test_show_world_writes_four_pictures_and_nothing_else(tmp_path: Path) -> None:
    from deformap.testing import coarse_world

    out = tmp_path / "new" / "folder"
    paths = show_world(coarse_world("heterogeneous-150-rigid"), str(out), force_n=0.6)
    assert paths == [out / "layout.png", out / "rgb.png", out / "cloud.png", out / "dent.png"]
    assert sorted(out.iterdir()) == sorted(paths)
    for path in paths:
        assert path.read_bytes()[:8] == PNG_MAGIC


def test_rgb_figure_shows_the_camera_image_and_the_cloud_in_its_own_colours() -> None:
    from deformap.testing import coarse_world
    from deformap.viz._world import _rgb_figure

    image = coarse_world("heterogeneous-60-110-rigid").rgb_image()
    fig = _rgb_figure(coarse_world("heterogeneous-60-110-rigid"))  # the same seed, a fresh world
    view, top = fig.axes
    shown = np.asarray(view.images[0].get_array())
    assert shown.shape == image.shape
    assert np.array_equal(shown, np.nan_to_num(image, nan=1.0))  # no return: white
    assert np.ptp(shown[~np.isnan(image).any(axis=2)], axis=0).max() > 0.2  # blocks and table differ
    assert "heterogeneous-60-110-rigid" in view.get_title()
    assert (view.get_xlabel(), view.get_ylabel()) == ("image column [px]", "image row [px]")
    assert (top.get_xlabel(), top.get_ylabel()) == ("x [m]", "y [m]")
    assert top.get_aspect() == 1.0
    colours = top.collections[0].get_facecolors()[:, :3]
    assert len(np.unique(colours.round(2), axis=0)) > 10  # each point its own colour


def test_world_pictures_have_a_stiffness_colour_bar_and_one_unit_per_figure() -> None:
    from matplotlib.colors import to_rgba

    from deformap.testing import coarse_world
    from deformap.viz._world import _dent_figure, _layout_figure

    world = coarse_world("heterogeneous-60-110-rigid")
    fig = _layout_figure(world)
    ax = _panels(fig)[0]
    assert _colorbar_labels(fig) == ["Young's modulus E [kPa] (log scale)"]
    (bar,) = [a for a in fig.axes if a.get_label() == "<colorbar>"]
    fig.canvas.draw()
    assert [t.get_text() for t in bar.get_yticklabels()] == ["4.6", "8.5"]
    (side,) = bar.child_axes  # hardness beside E, at the blocks' values
    assert side.get_ylabel() == "hardness H [N]"
    assert [t.get_text() for t in side.get_yticklabels()] == ["60", "110"]
    # soft darker than stiff, rigid grey; names without an index
    soft, stiff, rigid = (p.get_facecolor() for p in ax.patches[:3])
    assert np.mean(soft[:3]) < np.mean(stiff[:3]) and rigid == to_rgba("0.55")
    assert [t.get_text().split("\n")[0] for t in ax.texts[:3]] == ["foam-60", "foam-110", "rigid"]
    fig = _dent_figure(world, 0.6)
    assert [(a.get_xlabel(), a.get_ylabel()) for a in _panels(fig)] == [
        ("x [mm]", "y [mm]"), ("x [mm]", "y [mm]"), ("x [mm]", "z [mm]")]
    assert _colorbar_labels(fig) == ["z [mm]", "z [mm]"]


def test_a_failed_write_keeps_the_previous_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "map.png"
    path.write_bytes(b"the previous figure")

    def broken_savefig(self: Figure, fname: Any, **kwargs: Any) -> None:
        if isinstance(fname, (str, os.PathLike)):
            with open(fname, "wb") as fh:
                fh.write(PNG_MAGIC + b"half an image")
        else:
            fname.write(PNG_MAGIC + b"half an image")
        raise OSError("killed mid-write")

    monkeypatch.setattr(Figure, "savefig", broken_savefig)
    with pytest.raises(OSError, match="killed mid-write"):
        CALLS["map"](path)
    assert path.read_bytes() == b"the previous figure"
    assert sorted(tmp_path.iterdir()) == [path]


def test_an_existing_file_is_replaced(tmp_path: Path) -> None:
    path = tmp_path / "map.png"
    path.write_bytes(b"the previous figure")
    CALLS["map"](path)
    assert path.read_bytes()[:8] == PNG_MAGIC
    assert sorted(tmp_path.iterdir()) == [path]


@pytest.mark.parametrize(
    ("name", "match"),
    [("map.unknown", r"`path` must end in a figure format .*\.png.*map\.unknown"),
     ("map", r"`path` must end in a figure format"),
     ("missing/map.png", r"`path` must be in an existing folder.*missing")],
)  # fmt: skip
def test_a_bad_path_is_refused_before_anything_is_written(
    tmp_path: Path, name: str, match: str
) -> None:
    with pytest.raises(InvalidArgumentError, match=match):
        CALLS["map"](tmp_path / name)
    assert list(tmp_path.iterdir()) == []


def test_importing_and_drawing_leave_matplotlib_global_state_alone(tmp_path: Path) -> None:
    # a fresh interpreter with a backend that is not Agg: the old module called
    # matplotlib.use("Agg") at import, which switched every user's backend
    script = textwrap.dedent(
        f"""
        import sys
        from pathlib import Path

        import matplotlib

        backend = matplotlib.get_backend()
        assert backend == "svg", backend
        rc = dict(matplotlib.rcParams)

        import deformap.viz
        assert matplotlib.get_backend() == backend, ("after import", matplotlib.get_backend())
        assert dict(matplotlib.rcParams) == rc, "rcParams changed by the import"

        sys.path.insert(0, {str(Path(__file__).parent)!r})
        import test_figures

        out = Path({str(tmp_path)!r})
        for name, call in sorted(test_figures.CALLS.items()):
            call(out / (name + ".png"))
        from deformap.testing import coarse_world
        deformap.viz.show_world(coarse_world("heterogeneous-150-rigid"), out / "world", force_n=0.6)
        assert matplotlib.get_backend() == backend, ("after drawing", matplotlib.get_backend())
        assert dict(matplotlib.rcParams) == rc, "rcParams changed by drawing"
        assert "matplotlib.pyplot" not in sys.modules, "pyplot imported"
        print("ok")
        """
    )
    env = {**os.environ, "MPLBACKEND": "svg"}
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
    assert len(list(tmp_path.glob("*.png"))) == len(CALLS)
    assert len(list((tmp_path / "world").glob("*.png"))) == 4


def _matrix_study(element_size_m: float) -> dict[str, Any]:
    rows = [{"protocol": "force/quadratic", "physics": "linear-fem", "camera": "primesense",
             "thickness_m": 0.05, "modulus_pa": e * 1.05, "modulus_std_pa": 0.1 * e,
             "true_modulus_pa": e} for e in (1.0e4, 3.0e4)]
    return {"matrix": {"element_size_m": element_size_m}, "rows": rows, "summary": [],
            "overall": []}


def test_the_hardness_matrix_names_its_world_mesh() -> None:
    for size, text in ((0.00375, "3.75"), (0.0075, "7.5")):
        fig = plot_hardness_study(_matrix_study(size))
        assert fig._supxlabel is not None  # type: ignore[attr-defined]
        assert fig._supxlabel.get_text() == (  # type: ignore[attr-defined]
            f"world mesh: {text} mm elements in plane")
    assert "\n" in fig._suptitle.get_text()  # type: ignore[attr-defined]  # one panel: two lines
    study = _matrix_study(0.0075)
    del study["matrix"]["element_size_m"]  # a study written before the mesh was recorded
    assert plot_hardness_study(study)._supxlabel is None  # type: ignore[attr-defined]


def _world_curves(n_worlds: int, families: tuple[str, ...]) -> dict[str, dict[str, Any]]:
    names = [f"{s}/{f}/{c}" for s in ("paper", "planned", "max-variance")
             for f in ("beta", "modulus") for c in ("nearest", "isopleth")]  # fmt: skip
    rng = np.random.default_rng(0)
    # planned/modulus/* best, then planned/beta/*; the paper's own combination among the worst
    level = {n: 0.9 if n.startswith("planned/modulus") else 0.7 if n.startswith("planned") else
             0.5 for n in names}  # fmt: skip
    level["planned/modulus/nearest"], level["planned/beta/isopleth"] = 0.95, 0.75
    return {family: {n: np.clip(level[n] + rng.normal(0, 0.02, (n_worlds, 5)), 0, 1)
                     for n in names} for family in ("all", *families)}  # fmt: skip


def test_world_curves_draw_the_best_few_and_the_papers() -> None:
    from deformap.viz._worlds import plot_world_curves

    fig = plot_world_curves(_world_curves(3, ("cuts", "insert")))
    panels = [ax for ax in fig.axes if ax.axison]
    assert [ax.get_title() for ax in panels] == [
        "all (3 worlds, too few for a band)", "cuts (3 worlds, too few for a band)",
        "insert (3 worlds, too few for a band)"]  # fmt: skip
    labels = [ln.get_label() for ln in panels[0].get_lines()]
    assert labels == ["1. planned/modulus/nearest", "2. planned/modulus/isopleth",
                      "3. planned/beta/isopleth", "paper/beta/isopleth (the paper's)",
                      "accuracy 0.9 (a good map)"]  # fmt: skip
    assert all(not ax.collections for ax in panels)  # no band over three worlds
    # twelve worlds: bands; without the paper's combination, its strategy's best stands in
    curves = _world_curves(12, ())
    del curves["all"]["paper/beta/isopleth"]
    fig = plot_world_curves(curves, best=2)
    (ax,) = fig.axes
    assert len(ax.collections) == 3
    assert [ln.get_label() for ln in ax.get_lines()][2].endswith("(the paper's strategy)")


def test_world_curves_leave_no_panel_empty() -> None:
    from deformap.viz._worlds import plot_world_curves

    for families, spare in ((("a", "b", "c"), 0), (("a", "b", "c", "d"), 1), (("a",), 0)):
        fig = plot_world_curves(_world_curves(2, families))
        off = [ax for ax in fig.axes if not ax.axison]
        assert len(off) == spare
        # a slot the families leave holds the legend; else it is below the panels
        assert [ax.get_legend() is not None for ax in off] == [True] * spare
        assert len(fig.legends) == (0 if spare else 1)


def test_a_runs_poke_figure_draws_its_force_travel_record_and_the_fit(tmp_path: Path) -> None:
    from deformap.explore import ExplorationConfig, SurfaceGPConfig, explore
    from deformap.run._figures import write_poke_figure
    from deformap.testing import coarse_world

    config = ExplorationConfig(max_pokes=1, surface=SurfaceGPConfig(fit_hyperparameters=False))
    result = explore(coarse_world("homogeneous-60"), config, rng=np.random.default_rng(0))
    (poke,) = result.pokes
    dent = poke.dent
    assert dent is not None and dent.force_travel is not None and dent.force_fit is not None
    # the fitted model runs through the record: within 15 % of each sample's force above 0.1 N
    travel, force = dent.force_travel.travel_m, dent.force_travel.force_n
    model = np.interp(travel, dent.force_fit[0], dent.force_fit[1])
    strong = force > 0.1
    assert np.all(np.abs(model[strong] - force[strong]) < 0.15 * force[strong])
    path = write_poke_figure(tmp_path, poke)
    assert path == tmp_path / "poke-01.png" and path.read_bytes()[:8] == PNG_MAGIC
