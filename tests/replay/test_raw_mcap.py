"""`deformap record-sim --format raw-mcap` → `deformap map robot.mcap`, with no bag setting.

A small seeded live run (coarse world, three presses: soft, rigid, soft) is recorded as a robot
records it: an organised PointCloud2 at 30 Hz in the camera's optical frame (NaN holes, packed
rgb), a WrenchStamped at 500 Hz in the F/T sensor's frame with 10 mN of noise per axis, /tf with
the tool moving, /tf_static, the tip frame named ``tool_tip``. Mapped with only the mapper's
settings (``--config``, ``--seed``: the live run's, so that β can be compared), every press is
used, β within 0.05 and E within 10 % of the live run. Then each imperfection of the rig, one
recording each: a force step instead of a ramp, a tip transform that does not move, other noise
per axis, other rates, a skewed sensor clock, other frame names, a sensor not zeroed; and the
refusals at open (a topic of another type, a tip frame that is not there, header stamps all
zero, a ROS 1 bag).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from deformap.cli import app

pytest.importorskip("rosbags")

SCENARIO, SEED = "heterogeneous-60-110-rigid", 3
WORLD = {"element_size_m": 0.02, "top_layer_m": 0.01, "camera": {"width": 128, "height": 96},
         "force_travel_levels": 16, "encoder_noise_m": 0.0, "force_travel_noise_rel": 0.0,
         "force_travel_noise_n": 0.0}  # fmt: skip
SMALL = {"world": WORLD, "exploration": {
    "max_pokes": 3, "surface": {"fit_hyperparameters": False}, "touch": {"roi_size_m": 0.06},
    "shape_matching": {"n_beta": 6, "refine": False, "max_iter": 200}}}
# a finer camera without disparity steps, that sees a dent of a few millimetres
FINE = {**SMALL, "world": {**WORLD, "element_size_m": 0.01,
                           "camera": {"width": 256, "height": 192, "noise": False}}}
runner = CliRunner()


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("rawmcap")


_RECORDED: dict[str, tuple[Path, dict[str, Any]]] = {}


def _record(root: Path, name: str, rig: dict[str, Any], config: dict[str, Any] = SMALL
            ) -> tuple[Path, dict[str, Any]]:  # fmt: skip
    """``robot.mcap`` and ``live.json`` of a recording with the rig ``rig`` (cached by name)."""
    if name not in _RECORDED:
        cfg = root / f"{name}.config.yaml"
        cfg.write_text(yaml.safe_dump(config))
        args = ["record-sim", "-s", SCENARIO, "--seed", str(SEED), "--config", str(cfg),
                "--format", "raw-mcap", "--out", str(root / name)]
        if rig:
            (root / f"{name}.rig.yaml").write_text(yaml.safe_dump(rig))
            args += ["--rig", str(root / f"{name}.rig.yaml")]
        result = runner.invoke(app, args)
        assert result.exit_code == 0, result.output
        live = json.loads((root / name / "live.json").read_text())
        _RECORDED[name] = (root / name / "robot.mcap", live)
    return _RECORDED[name]


def _map(bag: Path, out: Path, *args: str, config: Path | None = None
         ) -> tuple[int, str, dict[str, Any]]:  # fmt: skip
    """``deformap map BAG`` with the live run's mapper settings only (no bag setting)."""
    cfg = config or bag.parent.with_name(f"{bag.parent.name}.config.yaml")
    result = runner.invoke(app, ["map", str(bag), "--out", str(out), "--config", str(cfg),
                                 "--seed", str(SEED), "--no-figures",
                                 "--json", str(out.with_suffix(".json")), *args])  # fmt: skip
    report = json.loads(out.with_suffix(".json").read_text()) if result.exit_code == 0 else {}
    return result.exit_code, result.output, report


def _assert_like_live(report: dict[str, Any], live: dict[str, Any], *, moduli: bool = True) -> None:
    assert report["form"] == "raw" and report["skipped"] == []
    assert len(report["pokes"]) == len(live["pokes"]) == 3
    for poke, rec in zip(report["pokes"], live["pokes"], strict=True):
        np.testing.assert_allclose(poke["contact_xy"], rec["contact_xy"], atol=1e-3)
        assert poke["beta"] == pytest.approx(rec["beta"], abs=0.05)
        if not moduli:
            continue
        got = poke.get("stiffness")
        assert got is not None and got["rigid"] == rec["rigid"]
        if not rec["rigid"]:
            assert got["modulus_pa"] == pytest.approx(rec["modulus_pa"], rel=0.10)


def test_the_described_bag_maps_with_no_bag_setting(root: Path, tmp_path: Path) -> None:
    bag, live = _record(root, "base", {})
    assert [p["rigid"] for p in live["pokes"]] == [False, True, False]
    code, output, report = _map(bag, tmp_path / "map")
    assert code == 0, output
    _assert_like_live(report, live)
    found = report["source"]["found"]
    assert found["cloud_topic"]["value"] == "/camera/depth/color/points"
    assert found["wrench_topic"]["value"] == "/ft_sensor/wrench"
    assert found["tip_frame"]["value"] == "tool_tip" and "found" in found["tip_frame"]["from"]
    assert found["force_frame"]["value"] == "ft_sensor"
    assert found["world_frame"]["value"] == "world"
    # the noise floor from the quiet samples: 10 mN per axis; the threshold four times its rms
    np.testing.assert_allclose(found["force_noise_n"]["value"], [0.01] * 3, rtol=0.2)
    rms = float(np.linalg.norm(found["force_noise_n"]["value"]))
    assert found["contact_force_n"]["value"] == pytest.approx(4 * rms, rel=1e-3)
    # the workspace: around the presses, inside the camera's view, printed with why
    lower, upper = found["workspace"]["value"]
    xy = np.array([p["contact_xy"] for p in live["pokes"]])
    assert np.all(xy > np.array(lower)) and np.all(xy < np.array(upper))
    assert "presses" in found["workspace"]["from"]
    assert "tip_frame: tool_tip (found" in output and "contact_force_n:" in output


def test_a_force_step_keeps_the_cameras_beta_without_a_modulus(root: Path,
                                                               tmp_path: Path) -> None:  # fmt: skip
    import dataclasses

    from deformap.replay import load_raw_bag, map_session
    from deformap.run import load_run_config
    from deformap.run._config import run_generators

    bag, live = _record(root, "step", {"force_profile": "step"})
    code, output, report = _map(bag, tmp_path / "map")
    assert code == 0, output
    assert report["skipped"] == [] and len(report["pokes"]) == len(live["pokes"])
    for poke in report["pokes"]:
        assert poke.get("stiffness") is None  # E absent, the reason in the poke's own entry
        assert "force–travel record cannot be read" in poke["stiffness_error"]
        assert "β from the camera alone" in poke["stiffness_error"]
    # the camera's β: what the ramp's bag gives with its records left out
    ramp_bag, _ = _record(root, "base", {})
    session = load_raw_bag(ramp_bag, default_force_n=0.6)
    read = session.press_observation
    session.press_observation = lambda i: dataclasses.replace(  # type: ignore[method-assign]
        read(i), force_travel=None)
    cfg = load_run_config(root / "base.config.yaml")
    camera = map_session(session, cfg.exploration, rng=run_generators(SEED)[1])
    for poke, ref in zip(report["pokes"], camera.result.pokes, strict=True):
        assert poke["beta"] == pytest.approx(ref.record.beta, abs=0.05)
        np.testing.assert_allclose(poke["contact_xy"], ref.record.contact_xy, atol=1e-3)


def test_a_tip_that_does_not_move_warns_and_no_foam_reads_rigid(root: Path,
                                                                tmp_path: Path) -> None:  # fmt: skip
    bag, live = _record(root, "static", {"tip_moves": False}, FINE)
    code, output, report = _map(bag, tmp_path / "map")
    assert code == 0, output
    soft = [i for i, p in enumerate(live["pokes"]) if not p["rigid"]]
    assert soft and len(soft) < len(live["pokes"]), "the live run pressed no foam, or only foam"
    for i, poke in enumerate(report["pokes"]):
        # a still tip's record cannot tell rigid from soft: no press is read from it
        assert poke.get("stiffness") is None
        assert "did not move at all" in report["source"]["presses"][str(i + 1)]["disagreement"]
        assert f"poke {i + 1}: the tip frame 'tool_tip' did not move at all" in " ".join(
            report["warnings"])
    for i in soft:  # the camera alone reads the foam's dent
        assert report["pokes"][i]["beta"] > 0.3
    assert "did not move at all" in output


@pytest.mark.parametrize(("name", "rig"), [
    ("noise", {"force_noise_n": [0.002, 0.03, 0.005]}),
    ("rates", {"camera_hz": 15.0, "wrench_hz": 1000.0, "tf_hz": 100.0}),
    ("skew", {"stamp_skew_s": 0.0015}),
])  # fmt: skip
def test_each_imperfection_of_the_rig_maps_like_the_live_run(
    root: Path, tmp_path: Path, name: str, rig: dict[str, Any]
) -> None:
    bag, live = _record(root, name, rig)
    code, output, report = _map(bag, tmp_path / "map")
    assert code == 0, output
    _assert_like_live(report, live)
    if name == "noise":  # each axis's noise found on its own (the sensor's axes)
        np.testing.assert_allclose(report["source"]["found"]["force_noise_n"]["value"],
                                   rig["force_noise_n"], rtol=0.2)


def test_other_frame_names_are_found(root: Path, tmp_path: Path) -> None:
    rig = {"world_frame": "map", "base_frame": "ur_base", "tool_frame": "flange",
           "tip_frame": "probe", "sensor_frame": "optoforce", "camera_frame": "cam_optical",
           "cloud_topic": "/rs/points", "wrench_topic": "/optoforce/wrench"}
    bag, live = _record(root, "frames", rig)
    code, output, report = _map(bag, tmp_path / "map")
    assert code == 0, output
    _assert_like_live(report, live)
    found = {k: v["value"] for k, v in report["source"]["found"].items()}
    assert (found["tip_frame"], found["force_frame"], found["camera_frame"]) == (
        "probe", "optoforce", "cam_optical")
    assert found["world_frame"] == "map"  # the camera's root, said to be assumed
    assert "assumed" in report["source"]["found"]["world_frame"]["from"]
    assert (found["cloud_topic"], found["wrench_topic"]) == ("/rs/points", "/optoforce/wrench")
    # --force-frame beside --tip-frame: given, checked at open
    code, output, report = _map(bag, tmp_path / "given", "--tip-frame", "probe",
                                "--force-frame", "optoforce")
    assert code == 0, output
    assert report["source"]["found"]["tip_frame"]["from"] == "given"
    assert report["source"]["found"]["force_frame"]["from"] == "given"


def test_a_sensor_not_zeroed_is_refused_at_open(root: Path, tmp_path: Path) -> None:
    bag, _ = _record(root, "bias", {"force_bias_n": 0.3})
    code, output, _ = _map(bag, tmp_path / "map")
    assert code == 2
    assert "from its first sample" in output and "not zeroed" in output


@pytest.mark.parametrize(("option", "topic", "carries", "expected"), [
    ("--wrench-topic", "/tf", "tf2_msgs/msg/TFMessage", "geometry_msgs/msg/WrenchStamped"),
    ("--cloud-topic", "/ft_sensor/wrench", "geometry_msgs/msg/WrenchStamped",
     "sensor_msgs/msg/PointCloud2"),
])  # fmt: skip
def test_a_topic_of_another_type_is_named_with_both_types(
    root: Path, tmp_path: Path, option: str, topic: str, carries: str, expected: str
) -> None:
    bag, _ = _record(root, "base", {})
    code, output, _ = _map(bag, tmp_path / "map", option, topic)
    assert code == 2
    line = output.strip().splitlines()[-1]
    assert f"topic {topic!r} ({option}" in line and f"carries {carries}; expected {expected}" in line
    assert "Traceback" not in output and "has no messages" not in output


def test_a_tip_frame_not_there_is_refused_once_listing_the_frames(root: Path,
                                                                  tmp_path: Path) -> None:  # fmt: skip
    bag, _ = _record(root, "base", {})
    code, output, _ = _map(bag, tmp_path / "map", "--tip-frame", "tip")
    assert code == 2
    lines = [ln for ln in output.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and "'tip' (--tip-frame)" in lines[0]
    assert "'tool_tip'" in lines[0] and "press" not in lines[0]


def test_header_stamps_all_zero_are_named(tmp_path: Path, make_synthetic: Any) -> None:
    pytest.importorskip("mcap_ros2.writer")
    from mcap_ros2.writer import Writer

    from deformap.replay import RigConfig, raw_messages
    from deformap.testing.robotbag import MSGDEFS

    # a small bag: the observation and one press of a synthetic session, wrench stamps zeroed
    syn = make_synthetic(n_pokes=1)
    bag = tmp_path / "zero.mcap"
    writer = Writer(str(bag))
    schemas = {k: writer.register_msgdef(k, v) for k, v in MSGDEFS.items()}
    for msg in raw_messages(syn.observation, syn.presses, RigConfig()):
        if msg.topic == "/ft_sensor/wrench":
            msg.fields["header"]["stamp"] = {"sec": 0, "nanosec": 0}
        writer.write_message(msg.topic, schemas[msg.msgtype], msg.fields,
                             log_time=msg.log_time_ns)
    writer.finish()
    result = runner.invoke(app, ["map", str(bag), "--out", str(tmp_path / "map")])
    assert result.exit_code == 2
    assert "every header stamp" in result.output and "is zero" in result.output
    assert "not zeroed" not in result.output


def test_a_ros1_bag_is_refused_in_one_line(tmp_path: Path) -> None:
    bag = tmp_path / "lab.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n" + bytes(64))
    result = runner.invoke(app, ["map", str(bag), "--out", str(tmp_path / "map")])
    assert result.exit_code == 2
    assert "ROS 1" in result.output and "Traceback" not in result.output


@pytest.mark.slow
def test_the_described_bag_maps_with_nothing_but_its_path(root: Path, tmp_path: Path) -> None:
    """The done-when case whole: recorded with the default run configuration (a coarse world),
    mapped with no option at all but where to write (the defaults, seed 0, as the live run)."""
    cfg = root / "defaults.yaml"
    cfg.write_text(yaml.safe_dump({"world": WORLD}))
    result = runner.invoke(app, ["record-sim", "-s", SCENARIO, "--seed", "0", "--pokes", "3",
                                 "--config", str(cfg), "--format", "raw-mcap",
                                 "--out", str(root / "defaults")])  # fmt: skip
    assert result.exit_code == 0, result.output
    live = json.loads((root / "defaults" / "live.json").read_text())
    out = tmp_path / "map"
    result = runner.invoke(app, ["map", str(root / "defaults" / "robot.mcap"), "--out", str(out),
                                 "--no-figures"])  # fmt: skip
    assert result.exit_code == 0, result.output
    report = json.loads((out / "report.json").read_text())
    assert [p["rigid"] for p in live["pokes"]] == [False, True, False]
    _assert_like_live(report, live)


def test_a_stamp_tolerance_that_joins_presses_is_refused(root: Path, tmp_path: Path) -> None:
    bag, _ = _record(root, "base", {})
    code, output, _ = _map(bag, tmp_path / "map", "--stamp-tolerance", "1e9")
    assert code == 2
    assert "--stamp-tolerance 1e+09 s" in output and "would join the presses" in output
    code, output, report = _map(bag, tmp_path / "ok", "--stamp-tolerance", "0.1")
    assert code == 0 and len(report["pokes"]) == 3, output
