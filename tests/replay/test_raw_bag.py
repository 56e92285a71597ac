"""`deformap map` on a bag recorded the way a ROS 2 robot records it (issue 15, items 1–2).

A small seeded live run (coarse world, four pokes) is recorded; its presses are then written as a
robot's drivers publish them, with the ``mcap`` and ``mcap-ros2-support`` packages (not deformap's
writer): an organised ``PointCloud2`` at 30 Hz in the camera's optical frame (NaN holes, packed
rgb, each pixel blanked in some frames), a ``WrenchStamped`` at 500 Hz in a rotated sensor frame
with the reaction force's sign, ``/tf`` at 50 Hz with the arm moving the tip along the press, and
``/tf_static`` for the camera mount; every stamp jittered. Mapped, the bag gives the live run's βs
and moduli within the stated tolerances: contacts within 0.1 mm, β within 0.02 (a tenth of the
test's β sweep step; measured: equal), β's σ within 5 % + 0.005, E within 10 % (measured: 2 %; the
bag's ramp is sampled at 500 Hz with the sensor's noise, the world's record at 16 levels), rigid
presses rigid. Then the refusals: a missing topic, a stamp gap, a force that never reaches the
command, a bad YAML key, a sensor whose sign is the other one.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from deformap.cli import app
from deformap.replay import RecordedSession, load_session
from deformap.run import load_run_config, record_simulation
from deformap.testing.robotbag import (
    APPROACH,
    FIRST_PRESS_S,
    HOLD,
    PAUSE,
    RAMP,
    RELEASE,
    raw_settings,
    write_raw_bag,
)

pytest.importorskip("mcap_ros2.writer")

SCENARIO, SEED, POKES = "heterogeneous-60-110-rigid", 3, 4
SMALL = {
    # the record's levels without sensor noise: the bag's ramp is sampled at 500 Hz along them, so
    # a noisy record would be refitted through other noise (the bag adds the sensor's own)
    "world": {"element_size_m": 0.02, "top_layer_m": 0.01, "camera": {"width": 128, "height": 96},
              "force_travel_levels": 16, "encoder_noise_m": 0.0, "force_travel_noise_rel": 0.0,
              "force_travel_noise_n": 0.0},
    "exploration": {
        "max_pokes": POKES,
        "surface": {"fit_hyperparameters": False},
        "touch": {"roi_size_m": 0.06},
        "shape_matching": {"n_beta": 6, "refine": False, "max_iter": 200},
    },
}  # fmt: skip
runner = CliRunner()


@pytest.fixture(scope="module")
def config_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("config") / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    return path


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory, config_file: Path
         ) -> tuple[RecordedSession, list[Any]]:  # fmt: skip
    """The live run's session (folder form) and its poke records, as estimated live."""
    from deformap.run import RunHooks

    cfg = dataclasses.replace(load_run_config(config_file), scenario=SCENARIO, seed=SEED)
    records: list[Any] = []
    out = record_simulation(cfg, tmp_path_factory.mktemp("live") / "session",
                            hooks=RunHooks(on_poke=records.append))  # fmt: skip
    return load_session(out.folder), records


@pytest.fixture(scope="module")
def raw_bag(tmp_path_factory: pytest.TempPathFactory,
            live: tuple[RecordedSession, list[Any]]) -> Path:  # fmt: skip
    bag = tmp_path_factory.mktemp("raw") / "lab.mcap"
    write_raw_bag(bag, live[0])
    bag.with_name("lab.deformap.yaml").write_text(yaml.safe_dump(raw_settings(live[0])))
    return bag


def _map(bag: Path, out: Path, config_file: Path, *args: str) -> tuple[int, str, dict[str, Any]]:
    result = runner.invoke(app, ["map", str(bag), "--out", str(out), "--config", str(config_file),
                                 "--seed", str(SEED), "--no-figures",
                                 "--json", str(out.with_suffix(".json")), *args])  # fmt: skip
    report = json.loads(out.with_suffix(".json").read_text()) if result.exit_code == 0 else {}
    return result.exit_code, result.output, report


def test_raw_bag_maps_to_the_live_betas_and_moduli(
    raw_bag: Path, live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    code, output, report = _map(raw_bag, tmp_path / "map", config_file)
    assert code == 0, output
    assert report["form"] == "raw" and report["skipped"] == []
    records = live[1]
    assert len(report["pokes"]) == len(records) == POKES
    for poke, rec in zip(report["pokes"], records, strict=True):
        np.testing.assert_allclose(poke["contact_xy"], rec.contact_xy, atol=1e-4)
        # the same clouds to float32 precision, the force's mean over the hold within its noise
        assert poke["beta"] == pytest.approx(rec.beta, abs=0.02)
        # β's σ carries σ(E) through the depth anchoring, and σ(E) its model-error term, read
        # from the record itself: 8 levels live, a 500 Hz ramp here (seed 0: σ(E) 16 % apart,
        # β's σ 12 %); before that term the two agreed within 5 %
        assert poke["beta_std"] == pytest.approx(rec.beta_std, rel=0.15, abs=0.005)
        live_e = rec.stiffness
        raw_e = poke.get("stiffness")
        assert (live_e is None) == (raw_e is None)
        if live_e is None:
            continue
        assert raw_e["rigid"] == live_e.rigid
        if not live_e.rigid and live_e.modulus_pa is not None:
            # 500 Hz samples along the ramp instead of the world's 8 levels
            assert raw_e["modulus_pa"] == pytest.approx(live_e.modulus_pa, rel=0.10)


def test_a_raw_press_record_has_its_times_and_its_hold(
        raw_bag: Path, live: tuple[RecordedSession, list[Any]]) -> None:
    from deformap.replay import load_raw_bag, load_raw_config

    force_n = live[0].press_observation(0).force_n
    session = load_raw_bag(raw_bag, load_raw_config(raw_bag), default_force_n=force_n)
    records = [session.press_observation(i).force_travel for i in range(len(session))]
    assert sum(r is not None for r in records) >= 2
    for record in records:
        if record is None:
            continue
        assert record.time_s is not None and record.time_s[0] == 0.0  # first contact
        assert record.time_s[-1] == pytest.approx(RAMP, rel=0.2)  # the robot's ramp takes RAMP s
        assert record.hold is not None and record.unloading is None
        assert record.hold.time_s[-1] - record.time_s[-1] == pytest.approx(HOLD, rel=0.2)
        # the world holds the force: the hold's force stays at the ramp's last within 5 %
        assert np.median(record.hold.force_n) == pytest.approx(record.force_n[-1], rel=0.05)


def test_missing_topic_is_named(raw_bag: Path, live: tuple[RecordedSession, list[Any]],
                                config_file: Path, tmp_path: Path) -> None:  # fmt: skip
    bag = tmp_path / "nowrench.mcap"
    write_raw_bag(bag, live[0], drop=("/ft_sensor/wrench",))
    bag.with_name("nowrench.deformap.yaml").write_text(yaml.safe_dump(raw_settings(live[0])))
    code, output, _ = _map(bag, tmp_path / "map", config_file)
    assert code == 2
    # the topic is found by its type: none carries it, and the error lists what the bag holds
    assert "0 topics carry geometry_msgs/msg/WrenchStamped" in output and "/tf_static" in output


def test_a_press_without_a_frame_in_tolerance_is_refused_naming_it(
    live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    bag = tmp_path / "gap.mcap"
    presses = write_raw_bag(bag, live[0], camera_gap_s=(presses_hold(live[0], 1)[0] - 0.3,
                                                        presses_hold(live[0], 1)[1] + 0.3))
    assert len(presses) == POKES
    bag.with_name("gap.deformap.yaml").write_text(yaml.safe_dump(raw_settings(live[0])))
    code, output, report = _map(bag, tmp_path / "map", config_file)
    assert code == 0, output
    assert [s["index"] for s in report["skipped"]] == [1]
    line = report["skipped"][0]["error"]
    # press and poke numbered alike, from 1
    assert "press 2" in line and "poke 2 skipped" in " ".join(report["warnings"])
    assert "'/camera/depth/color/points'" in line and "s away" in line
    assert len(report["pokes"]) == POKES - 1


def test_a_press_without_a_transform_in_tolerance_is_refused_naming_it(
    live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    bag = tmp_path / "tfgap.mcap"
    hold = presses_hold(live[0], 2)
    write_raw_bag(bag, live[0], tf_gap_s=(hold[0] - 0.2, hold[1] + 0.2))
    bag.with_name("tfgap.deformap.yaml").write_text(yaml.safe_dump(raw_settings(live[0])))
    code, output, report = _map(bag, tmp_path / "map", config_file)
    assert code == 0, output
    assert [s["index"] for s in report["skipped"]] == [2]
    line = report["skipped"][0]["error"]
    assert "press 3" in line and "'/tf'" in line and "'tool0'" in line and "s away" in line


def presses_hold(session: RecordedSession, index: int) -> tuple[float, float]:
    step = APPROACH + RAMP + HOLD + RELEASE + PAUSE
    start = FIRST_PRESS_S + index * step + APPROACH + RAMP
    return start, start + HOLD


def test_force_never_reaching_the_command_refuses_every_press_with_exit_2(
    raw_bag: Path, config_file: Path, tmp_path: Path
) -> None:
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--press-force", "2.0")
    assert code == 2, output
    assert "never reached the commanded 2 N" in output and "press 1 " in output
    assert "no poke of the session" in output


def test_a_sensor_of_the_other_sign_is_refused_not_taken(
    raw_bag: Path, live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    settings = tmp_path / "applied.yaml"
    settings.write_text(yaml.safe_dump(raw_settings(live[0], wrench_sign="applied")))
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--raw-config", str(settings))
    assert code == 2, output
    assert "points away from it" in output and "wrench_sign" in output


def test_a_tip_frame_whose_z_points_into_the_surface_is_named(
    raw_bag: Path, live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    # tool0's z points down the stick (the flange's convention): the press would go up; the
    # error names the frame, not the wrench's sign, which is right
    settings = tmp_path / "tool0.yaml"
    settings.write_text(yaml.safe_dump(raw_settings(live[0], tip_frame="tool0")))
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--raw-config", str(settings))
    assert code == 2, output
    assert "'tool0'" in output and "`tip_frame` must have z along the stick" in output
    assert not any("wrench_sign" in ln for ln in output.splitlines() if "press" in ln)


def test_a_bad_yaml_key_is_named(raw_bag: Path, config_file: Path, tmp_path: Path) -> None:
    settings = tmp_path / "bad.yaml"
    settings.write_text(yaml.safe_dump({"tip_frmae": "probe_tip"}))
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--raw-config", str(settings))
    assert code == 2
    assert "tip_frmae" in output and "unknown key" in output


def test_an_observation_picked_after_the_first_contact_is_refused(
    raw_bag: Path, live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    settings = tmp_path / "late.yaml"
    settings.write_text(yaml.safe_dump(raw_settings(live[0], observation_time_s=FIRST_PRESS_S + 1)))
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--raw-config", str(settings))
    assert code == 2
    assert "must all come before the first contact" in output and "observation_time_s" in output


def test_the_layout_is_told_apart_and_raw_options_are_refused_on_a_session(
    raw_bag: Path, live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    from deformap.replay import is_raw_bag

    folder = tmp_path / "rosbag2"
    folder.mkdir()
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    assert is_raw_bag(raw_bag) and is_raw_bag(folder)
    assert not is_raw_bag(live[0].path) and not is_raw_bag(live[0].path / "session.yaml")
    code, output, _ = _map(live[0].path, tmp_path / "map", config_file, "--cloud-topic", "/c")
    assert code == 2 and "--layout raw" in output


def test_a_sensor_not_zeroed_is_refused_when_the_bag_is_opened(
    live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    bag = tmp_path / "bias.mcap"
    write_raw_bag(bag, live[0], bias_n=0.3)
    bag.with_name("bias.deformap.yaml").write_text(yaml.safe_dump(raw_settings(live[0])))
    code, output, _ = _map(bag, tmp_path / "map", config_file)
    assert code == 2
    assert "from its first sample" in output and "not zeroed" in output


def test_more_presses_than_one_map_holds_are_refused_naming_the_bag(
    raw_bag: Path, config_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from deformap._validation import LIMITS

    monkeypatch.setitem(LIMITS["pokes"], "le", POKES - 1)  # the bag's presses, one too many
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file)
    assert code == 2
    assert f"{POKES:,} presses found" in output and "lab.mcap" in output
    assert "Traceback" not in output


def test_a_tip_radius_beyond_a_probe_is_refused_naming_the_setting() -> None:
    from deformap.errors import DeformapError
    from deformap.replay._rawconfig import RawBagConfig

    with pytest.raises(DeformapError, match="tip_radius_m"):
        RawBagConfig(tip_radius_m=1e-300)
