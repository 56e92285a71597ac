"""``map.npz`` carries the appearance prior's image and segments (NaN and -1 without a prior)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.explore._result import AppearanceOutcome
from deformap.run import RunConfig, explore_scenario
from deformap.run._export import _write_map_npz
from deformap.world import WorldConfig


def test_map_npz_holds_the_appearance_image_and_segments_or_nan_and_minus_one(
        tmp_path: Path) -> None:
    config = RunConfig(scenario="heterogeneous-60-150", seed=4, world=WorldConfig.coarse(),
                       exploration=ExplorationConfig(
                           max_pokes=1, surface=SurfaceGPConfig(fit_hyperparameters=False)))
    run = explore_scenario(config, tmp_path / "run", figures=False)
    image = run.result.appearance.image
    assert run.result.appearance.used and image is not None  # the scenario is painted
    with np.load(run.folder / "map.npz") as grids:  # no pickle needed
        ny, nx = grids["ys_m"].size, grids["xs_m"].size
        lab, segments = grids["appearance_lab"], grids["appearance_segments"]
        assert lab.shape == (ny, nx, 3) and segments.shape == (ny, nx)
        assert segments.dtype.kind == "i" and "CIELAB" in str(grids["units"])
    np.testing.assert_array_equal(lab, image.lab)
    np.testing.assert_array_equal(segments, image.segments)
    seen = segments >= 0
    assert seen.mean() > 0.5 and int(segments.max()) + 1 == image.n_segments >= 2
    assert np.all(np.isnan(lab[~seen])) and np.all(np.isfinite(lab[seen]))
    assert np.all((lab[seen][:, 0] >= 0) & (lab[seen][:, 0] <= 100))  # L*, not sRGB
    blind = replace(run.result, appearance=AppearanceOutcome(used=False, reason="off"))
    _write_map_npz(tmp_path / "blind.npz", blind)
    with np.load(tmp_path / "blind.npz") as grids:
        assert np.all(np.isnan(grids["appearance_lab"])) and grids["appearance_lab"].shape == (ny, nx, 3)
        assert np.all(grids["appearance_segments"] == -1)
