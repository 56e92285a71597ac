"""One way to vary the exploration in a benchmark: ``--set key=value`` read as a configuration
file's ``exploration`` section, recorded as the settings that differ from the defaults."""

from __future__ import annotations

from dataclasses import replace

import pytest

from deformap._config import config_from_dict
from deformap.errors import ConfigError
from deformap.explore import ExplorationConfig
from deformap.run import exploration_with, parse_assignments
from deformap.run._worlds_config import exploration_changes
from deformap.run._worlds_engines import _task, task_data


def test_assignments_are_yaml_scalars_under_dotted_keys() -> None:
    assert parse_assignments(["merge_seams=false", "beta_field.signal_std=0.25",
                              "beta_field.noise_floor=null", "region_labels= nearest",
                              "first_target="]) == {
        "merge_seams": False, "beta_field.signal_std": 0.25, "beta_field.noise_floor": None,
        "region_labels": "nearest", "first_target": None}
    for item, why in (("merge_seams", "must be key=value"), ("=1", "must be key=value"),
                      ("threshold=[1, 2]", "must be a scalar"),
                      ("threshold={a: 1}", "must be a scalar")):
        with pytest.raises(ConfigError, match=why):
            parse_assignments([item])
    with pytest.raises(ConfigError, match="--set threshold is given twice"):
        parse_assignments(["threshold=0.1", "threshold=0.2"])


def test_settings_go_through_the_config_files_reader_and_back() -> None:
    changes = {"merge_seams": False, "beta_field.signal_std": 0.25, "touch.model": "height"}
    config = exploration_with(changes)
    nested = {"merge_seams": False, "beta_field": {"signal_std": 0.25},
              "touch": {"model": "height"}}
    assert config == config_from_dict(ExplorationConfig, nested, where="exploration")
    assert config.beta_field == replace(ExplorationConfig().beta_field, signal_std=0.25)
    assert exploration_changes(config) == changes
    assert exploration_with({}) == ExplorationConfig() and exploration_changes(config) != {}
    assert exploration_changes(ExplorationConfig()) == {}
    for changes, why in (({"merge_seam": True}, r"`exploration.merge_seam` is no setting"),
                         ({"beta_field.sigma": 1.0}, r"`exploration.beta_field.sigma` is no "),
                         ({"threshold.x": 1.0}, r"`exploration.threshold` is no group"),
                         ({"threshold": -1.0}, r"`exploration.threshold` must be"),
                         ({"beta_field": 1.0}, r"`exploration.beta_field` must be a mapping")):
        with pytest.raises(ConfigError, match=why) as caught:
            exploration_with(changes)
        assert len(str(caught.value).splitlines()) == 1


def test_a_task_crosses_the_process_boundary_as_plain_data_and_back() -> None:
    import json

    from deformap.run import WorldsBenchConfig

    config = WorldsBenchConfig(seed=4, max_pokes=3, coarse=True,
                               exploration=exploration_with({"split_by_place": False}))
    task = config.task(7)
    data = json.loads(json.dumps(task_data(task)))
    assert data["exploration"] == {"split_by_place": False}
    assert _task(data) == task
