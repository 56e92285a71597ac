from __future__ import annotations

import numpy as np
from matplotlib.image import imread

from deformap.viz import plot_map, plot_poke


def test_map_figure_has_three_panels_and_is_written(tmp_path) -> None:
    xs, ys = np.linspace(0.0025, 0.5975, 120), np.linspace(0.0025, 0.3975, 80)
    gx, _ = np.meshgrid(xs, ys)
    beta = np.where(gx < 0.3, 0.8, 0.2)
    var = 0.05 + 0.04 * (gx / 0.6)
    hardness = np.where(gx < 0.3, 60.0, np.inf)
    path = plot_map(
        tmp_path / "map.png",
        xs,
        ys,
        beta=beta,
        variance=var,
        contacts=np.array([[0.3, 0.2], [0.1, 0.1], [0.5, 0.3]]),
        labels=(gx >= 0.3).astype(int),
        levels=np.array([0.5]),
        truth_hardness=hardness,
        threshold=0.06,
    )
    image = imread(path)
    assert image.shape[1] > 2.5 * image.shape[0]  # three panels side by side
    assert image[..., :3].std() > 0.05  # not a blank canvas


def test_poke_figure(tmp_path) -> None:
    xs = ys = np.linspace(-0.06, 0.06, 25)
    gx, gy = np.meshgrid(xs, ys)
    rest = np.full(gx.shape, 0.05)
    dent = rest - 0.005 * np.exp(-(gx**2 + gy**2) / 0.01**2)
    pts = np.column_stack([gx.ravel(), gy.ravel(), dent.ravel()])
    betas = np.linspace(0, 0.98, 50)
    path = plot_poke(
        tmp_path / "poke-01.png",
        roi_xs=xs,
        roi_ys=ys,
        rest_z=rest,
        deformed_z=dent,
        roi_points=pts,
        tactile=pts[:10],
        betas=betas,
        errors=(betas - 0.4) ** 2 + 1e-3,
        beta=0.4,
        beta_std=0.05,
        simulated_z=dent,
    )
    assert imread(path).shape[0] > 100
