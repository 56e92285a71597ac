"""A run on presses that hold and unload: each region in report.json gets the behaviour its pokes
agree on, map.npz the behaviour fields on the grid, map.png a behaviour panel."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.run import RunConfig, explore_scenario
from deformap.world import WorldConfig

KNOWN = ("elastic", "viscoelastic", "plastic")


pytestmark = pytest.mark.slow  # one run of three pokes that hold and unload: about 20 s


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("behaviour")
    scenario = folder / "elastic-and-clay.yaml"
    scenario.write_text(yaml.safe_dump({"name": "elastic-and-clay", "blocks": [
        {"name": "elastic", "rect": [0.0, 0.0, 0.3, 0.4], "hardness_n": 60},
        {"name": "clay", "rect": [0.3, 0.0, 0.6, 0.4], "hardness_n": 60,
         "plastic": {"yield_stress_pa": 1000, "hardening_pa": 2000}}]}))
    config = RunConfig(
        scenario=str(scenario), seed=1,
        world=WorldConfig.coarse(hold_s=2.0, unload=True),
        exploration=ExplorationConfig(max_pokes=3, threshold=1e-4, strategy="max-variance",
                                      surface=SurfaceGPConfig(fit_hyperparameters=False)))
    return explore_scenario(config, folder / "run").folder


def test_each_region_reports_the_behaviour_its_pokes_agree_on(run_folder: Path) -> None:
    report = json.loads((run_folder / "report.json").read_text())
    regions = report["regions"]
    read = {p["index"]: p["behaviour"]["behaviour"] for p in report["pokes"]}
    assert any(b in KNOWN for b in read.values())  # the presses held and unloaded
    n = len(regions["class_values"])
    assert len(regions["class_behaviours"]) == len(regions["class_behaviour_pokes"]) == n
    for k in range(n):
        mine = [read[i] for i, label in zip(regions["poke_indices"], regions["poke_labels"],
                                             strict=True) if label == k]
        known = {b for b in mine if b in KNOWN}
        assert len(known) <= 1  # never two known behaviours in one region
        assert regions["class_behaviours"][k] == (known.pop() if known else "unknown")
        kind = regions["class_behaviours"][k]
        assert regions["class_behaviour_pokes"][k] == mine.count(kind) * (kind in KNOWN)
        assert regions["class_n_pokes"][k] == len(mine)


def test_map_npz_holds_the_behaviour_by_region(run_folder: Path) -> None:
    report = json.loads((run_folder / "report.json").read_text())
    regions = report["regions"]
    with np.load(run_folder / "map.npz") as maps:
        names = [str(n) for n in maps["behaviour_names"]]
        labels, classes = maps["region_labels"], maps["behaviour_class"]
        assert classes.shape == labels.shape == (maps["ys_m"].size, maps["xs_m"].size)
        for k, kind in enumerate(regions["class_behaviours"]):
            assert np.all(classes[labels == k] == names.index(kind))
        dents = {p["index"]: p["behaviour"]["residual_dent_m"] for p in report["pokes"]}
        for k in range(len(regions["class_behaviours"])):
            mine = [dents[i] for i, label in zip(regions["poke_indices"], regions["poke_labels"],
                                                  strict=True) if label == k and dents[i] is not None]
            cells = maps["residual_dent_m"][labels == k]
            if mine:
                np.testing.assert_allclose(cells, np.median(mine))
            else:
                assert np.all(np.isnan(cells))
        assert {"relaxation", "relaxation_tau_s", "loss_ratio", "released_dent_m"} <= set(maps)
        assert "relaxation_tau_s: s" in str(maps["units"])
    assert (run_folder / "map.png").stat().st_size > 0
