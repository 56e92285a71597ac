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
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from deformap.cli import app
from deformap.environment import PressObservation
from deformap.replay import RecordedSession, load_session
from deformap.run import load_run_config, record_simulation

mcap_ros2_writer = pytest.importorskip("mcap_ros2.writer")

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
T0_NS = 1_700_000_000 * 10**9  # a realistic epoch stamp
#: Timeline of one press [s]: approach, ramp from contact to the force, hold, release, pause.
APPROACH, RAMP, HOLD, RELEASE, PAUSE = 0.2, 0.4, 0.3, 0.15, 0.15
FIRST_PRESS_S = 0.3
runner = CliRunner()

# -- message definitions, as ROS 2 ships them (dependencies after the ==== lines) -----------------
_SEP = "\n" + "=" * 80 + "\n"
_HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id" + _SEP + \
    "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec"
_VECTOR = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z"
MSGDEFS = {
    "sensor_msgs/msg/PointCloud2": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n"
        "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense"
        + _SEP + _HEADER + _SEP + "MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\n"
        "uint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\n"
        "uint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count"),
    "geometry_msgs/msg/WrenchStamped": (
        "std_msgs/Header header\ngeometry_msgs/Wrench wrench" + _SEP + _HEADER + _SEP
        + "MSG: geometry_msgs/Wrench\ngeometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque"
        + _SEP + _VECTOR),
    "tf2_msgs/msg/TFMessage": (
        "geometry_msgs/TransformStamped[] transforms" + _SEP
        + "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/Transform transform" + _SEP + _HEADER + _SEP
        + "MSG: geometry_msgs/Transform\ngeometry_msgs/Vector3 translation\n"
        "geometry_msgs/Quaternion rotation" + _SEP + _VECTOR + _SEP
        + "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w"),
}  # fmt: skip


def _header(t_s: float, frame: str) -> dict[str, Any]:
    ns = T0_NS + round(t_s * 1e9)
    return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": frame}


def _pose(rot: np.ndarray, trans: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rot, trans
    return m


def _tf(t_s: float, parent: str, child: str, m: np.ndarray) -> dict[str, Any]:
    x, y, z, w = Rotation.from_matrix(m[:3, :3]).as_quat()
    tx, ty, tz = m[:3, 3]
    return {"header": _header(t_s, parent), "child_frame_id": child,
            "transform": {"translation": {"x": tx, "y": ty, "z": tz},
                          "rotation": {"x": x, "y": y, "z": z, "w": w}}}  # fmt: skip


# -- the rig: camera mount, arm base, tool, tip and sensor --------------------------------------
def _camera_optical2world() -> np.ndarray:
    eye, target = np.array([0.30, -0.35, 0.65]), np.array([0.30, 0.20, 0.0])
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return _pose(np.column_stack([x, np.cross(z, x), z]), eye)


OPTICAL2LINK = _pose(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), [0, 0, 0])
BASE2WORLD = _pose(Rotation.from_euler("z", 180, degrees=True).as_matrix(), [0.3, 0.7, 0.0])
TIP2TOOL = _pose(Rotation.from_euler("x", 180, degrees=True).as_matrix(), [0.0, 0.0, 0.15])
SENSOR2TIP = _pose(Rotation.from_euler("zx", [90, 180], degrees=True).as_matrix(), [0, 0, 0.1])
TIP_YAW = Rotation.from_euler("z", 30, degrees=True).as_matrix()  # the tip's z stays up


@dataclasses.dataclass
class Press:
    obs: PressObservation
    start_s: float

    @property
    def contact_s(self) -> float:
        return self.start_s + APPROACH

    @property
    def hold_s(self) -> tuple[float, float]:
        return self.contact_s + RAMP, self.contact_s + RAMP + HOLD

    def lift(self) -> float:
        assert self.obs.force_travel is not None
        return float(self.obs.force_travel.travel_m[-1] - self.obs.force_travel.travel_m[0])


def _timeline(session: RecordedSession) -> list[Press]:
    step = APPROACH + RAMP + HOLD + RELEASE + PAUSE
    return [Press(session.press_observation(i), FIRST_PRESS_S + i * step)
            for i in range(len(session))]


def _ramp_u(press: Press, t: np.ndarray) -> np.ndarray:
    """Position in the force–travel record (sample index, fractional) at times within the ramp."""
    assert press.obs.force_travel is not None
    n = len(press.obs.force_travel)
    return np.clip((t - press.contact_s) / RAMP, 0.0, 1.0) * (n - 1)


def _tip_position(presses: list[Press], t: float) -> np.ndarray:
    """The tip's centre: over each target, down 5 cm, along the record's travel, hold, up."""
    up = np.array([0.0, 0.0, 1.0])
    for k, p in enumerate(presses):
        hold = p.obs.contact.tip_center
        contact = hold + p.lift() * up
        above = contact + 0.05 * up
        if t < p.start_s:  # moving from the last press to above this one
            if k == 0:
                return above
            prev = presses[k - 1]
            prev_above = prev.obs.contact.tip_center + (prev.lift() + 0.05) * up
            w = np.clip((t - prev.hold_s[1] - RELEASE) / PAUSE, 0.0, 1.0)
            return prev_above + w * (above - prev_above)
        if t < p.contact_s:
            return above + (t - p.start_s) / APPROACH * (contact - above)
        if t < p.hold_s[0]:
            record = p.obs.force_travel
            assert record is not None
            u = _ramp_u(p, np.array([t]))
            travel = np.interp(u, np.arange(len(record)), record.travel_m)[0]
            return contact - (travel - record.travel_m[0]) * up
        if t <= p.hold_s[1]:
            return hold
        if t <= p.hold_s[1] + RELEASE:
            return hold + (t - p.hold_s[1]) / RELEASE * (above - hold)
    last = presses[-1]
    return last.obs.contact.tip_center + (last.lift() + 0.05) * up


def _force_on_surface(presses: list[Press], t: np.ndarray) -> np.ndarray:
    """``(n, 3)`` world force the probe exerts on the surface at the times."""
    out = np.zeros((t.size, 3))
    for p in presses:
        f = p.obs.contact.force
        unit = f / np.linalg.norm(f)
        record = p.obs.force_travel
        assert record is not None
        ramp = (t >= p.contact_s) & (t < p.hold_s[0])
        mags = np.interp(_ramp_u(p, t[ramp]), np.arange(len(record)), record.force_n)
        out[ramp] = mags[:, None] * unit
        out[(t >= p.hold_s[0]) & (t <= p.hold_s[1])] = f
        rel = (t > p.hold_s[1]) & (t < p.hold_s[1] + RELEASE)
        out[rel] = (1 - (t[rel] - p.hold_s[1]) / RELEASE)[:, None] * f
    return out


def _organised(points_world: np.ndarray, optical2world: np.ndarray, pixels: np.ndarray,
               shape: tuple[int, int]) -> np.ndarray:  # fmt: skip
    """``(h·w, 3)`` float32 camera-frame points on the given (sorted) pixels, NaN elsewhere."""
    cam = (points_world - optical2world[:3, 3]) @ optical2world[:3, :3]
    grid = np.full((shape[0] * shape[1], 3), np.nan, dtype=np.float32)
    grid[pixels] = cam.astype(np.float32)
    return grid


def _cloud_msg(t_s: float, grid: np.ndarray, shape: tuple[int, int]) -> dict[str, Any]:
    table = np.zeros(grid.shape[0], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                           ("rgb", "<f4")])  # fmt: skip
    for i, a in enumerate("xyz"):
        table[a] = grid[:, i]
    table["rgb"] = np.full(grid.shape[0], 0x808080, dtype=np.uint32).view(np.float32)
    fields = [{"name": a, "offset": 4 * i, "datatype": 7, "count": 1}
              for i, a in enumerate(["x", "y", "z", "rgb"])]  # fmt: skip
    return {"header": _header(t_s, "camera_depth_optical_frame"), "height": shape[0],
            "width": shape[1], "fields": fields, "is_bigendian": False, "point_step": 16,
            "row_step": 16 * shape[1], "data": table.tobytes(), "is_dense": False}  # fmt: skip


def write_raw_bag(path: Path, session: RecordedSession, *, seed: int = 0,
                  drop: tuple[str, ...] = (), camera_gap_s: tuple[float, float] | None = None,
                  tf_gap_s: tuple[float, float] | None = None, bias_n: float = 0.0,
                  ) -> list[Press]:  # fmt: skip
    """Write ``session``'s presses as a robot's drivers record them; return the timeline."""
    rng = np.random.default_rng(seed)
    presses = _timeline(session)
    end_s = presses[-1].hold_s[1] + RELEASE + PAUSE
    optical2world = _camera_optical2world()
    observation = session.observation().points
    clouds = [observation] + [p.obs.cloud.points for p in presses]
    width = 128
    height = -(-max(len(c) for c in clouds) * 5 // 4 // width)  # a quarter more pixels: holes
    shape = (height, width)
    layouts = [np.sort(rng.choice(height * width, len(c), replace=False)) for c in clouds]
    grids = [_organised(c, optical2world, px, shape) for c, px in zip(clouds, layouts, strict=True)]
    writer = mcap_ros2_writer.Writer(str(path))
    schemas = {name: writer.register_msgdef(name, text) for name, text in MSGDEFS.items()}

    def put(topic: str, kind: str, msg: dict[str, Any], t_s: float) -> None:
        if topic not in drop:
            writer.write_message(topic, schemas[kind], msg, log_time=T0_NS + round(t_s * 1e9))

    static = [_tf(0.0, "world", "camera_link", optical2world @ np.linalg.inv(OPTICAL2LINK)),
              _tf(0.0, "camera_link", "camera_depth_optical_frame", OPTICAL2LINK),
              _tf(0.0, "world", "base_link", BASE2WORLD),
              _tf(0.0, "tool0", "probe_tip", TIP2TOOL),
              _tf(0.0, "probe_tip", "ft_sensor", SENSOR2TIP)]  # fmt: skip
    put("/tf_static", "tf2_msgs/msg/TFMessage", {"transforms": static}, 0.0)
    # the camera, 30 Hz: the observation, or from contact to release the press's cloud (each
    # pixel blanked in one frame of nine at most, so the per-pixel mean gives every point back)
    for n, t in enumerate(np.arange(0.0, end_s, 1 / 30)):
        stamp = t + rng.uniform(-0.003, 0.003)
        if camera_gap_s is not None and camera_gap_s[0] <= stamp <= camera_gap_s[1]:
            continue
        held = [k for k, p in enumerate(presses) if p.contact_s <= stamp <= p.hold_s[1] + RELEASE]
        grid = grids[held[0] + 1].copy() if held else grids[0].copy()
        blank = layouts[held[0] + 1 if held else 0]
        grid[blank[(np.arange(blank.size) * 7 + n) % 9 == 0][::3]] = np.nan
        put("/camera/depth/color/points", "sensor_msgs/msg/PointCloud2",
            _cloud_msg(stamp, grid, shape), stamp)
    # the arm, 50 Hz: base_link -> tool0 carries the tip along the press
    for t in np.arange(0.0, end_s, 1 / 50):
        stamp = t + rng.uniform(-0.002, 0.002)
        if tf_gap_s is not None and tf_gap_s[0] <= stamp <= tf_gap_s[1]:
            continue
        tip2world = _pose(TIP_YAW, _tip_position(presses, stamp))
        tool2base = np.linalg.inv(BASE2WORLD) @ tip2world @ np.linalg.inv(TIP2TOOL)
        put("/tf", "tf2_msgs/msg/TFMessage",
            {"transforms": [_tf(stamp, "base_link", "tool0", tool2base)]}, stamp)
    # the force sensor, 500 Hz: the reaction (the surface on the probe) in its own frame
    times = np.arange(0.0, end_s, 1 / 500)
    times = times + rng.uniform(-4e-4, 4e-4, times.size)
    force = _force_on_surface(presses, times) + rng.normal(0.0, 0.002, (times.size, 3))
    force[:, 2] -= bias_n  # a sensor not zeroed
    sensor2world = TIP_YAW @ SENSOR2TIP[:3, :3]
    reaction = -force @ sensor2world  # = (sensor2world.T @ -f) row by row
    for t, f in zip(times, reaction, strict=True):
        put("/ft_sensor/wrench", "geometry_msgs/msg/WrenchStamped", {
            "header": _header(t, "ft_sensor"),
            "wrench": {"force": dict(zip("xyz", f.tolist(), strict=True)),
                       "torque": {"x": 0.0, "y": 0.0, "z": 0.0}}}, t)  # fmt: skip
    writer.finish()
    return presses


def _settings(session: RecordedSession, **extra: Any) -> dict[str, Any]:
    """The YAML beside the bag: this rig's frames, the live run's workspace, the world's probe."""
    ws = session.workspace
    return {"tip_frame": "probe_tip", "observation_frames": 3,
            "workspace_lower": list(ws.lower), "workspace_upper": list(ws.upper),
            "hull": [{"shape": "cap", "size_m": [0.02, 0.02, 0.02]},
                     {"shape": "cylinder", "center_m": [0, 0, 0.05], "size_m": [0.016, 0.016, 0.1]},
                     {"shape": "box", "center_m": [0, 0, 0.15], "size_m": [0.085, 0.065, 0.105]}],
            **extra}  # fmt: skip


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
    bag.with_name("lab.deformap.yaml").write_text(yaml.safe_dump(_settings(live[0])))
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
        assert poke["beta_std"] == pytest.approx(rec.beta_std, rel=0.05, abs=0.005)
        live_e = rec.stiffness
        raw_e = poke.get("stiffness")
        assert (live_e is None) == (raw_e is None)
        if live_e is None:
            continue
        assert raw_e["rigid"] == live_e.rigid
        if not live_e.rigid and live_e.modulus_pa is not None:
            # 500 Hz samples along the ramp instead of the world's 8 levels
            assert raw_e["modulus_pa"] == pytest.approx(live_e.modulus_pa, rel=0.10)


def test_missing_topic_is_named(raw_bag: Path, live: tuple[RecordedSession, list[Any]],
                                config_file: Path, tmp_path: Path) -> None:  # fmt: skip
    bag = tmp_path / "nowrench.mcap"
    write_raw_bag(bag, live[0], drop=("/ft_sensor/wrench",))
    bag.with_name("nowrench.deformap.yaml").write_text(yaml.safe_dump(_settings(live[0])))
    code, output, _ = _map(bag, tmp_path / "map", config_file)
    assert code == 2
    assert "'/ft_sensor/wrench'" in output and "no topic" in output


def test_a_press_without_a_frame_in_tolerance_is_refused_naming_it(
    live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    bag = tmp_path / "gap.mcap"
    presses = write_raw_bag(bag, live[0], camera_gap_s=(presses_hold(live[0], 1)[0] - 0.3,
                                                        presses_hold(live[0], 1)[1] + 0.3))
    assert len(presses) == POKES
    bag.with_name("gap.deformap.yaml").write_text(yaml.safe_dump(_settings(live[0])))
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
    bag.with_name("tfgap.deformap.yaml").write_text(yaml.safe_dump(_settings(live[0])))
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
    settings.write_text(yaml.safe_dump(_settings(live[0], wrench_sign="applied")))
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--raw-config", str(settings))
    assert code == 2, output
    assert "points away from it" in output and "wrench_sign" in output


def test_a_tip_frame_whose_z_points_into_the_surface_is_named(
    raw_bag: Path, live: tuple[RecordedSession, list[Any]], config_file: Path, tmp_path: Path
) -> None:
    # tool0's z points down the stick (the flange's convention): the press would go up; the
    # error names the frame, not the wrench's sign, which is right
    settings = tmp_path / "tool0.yaml"
    settings.write_text(yaml.safe_dump(_settings(live[0], tip_frame="tool0")))
    code, output, _ = _map(raw_bag, tmp_path / "map", config_file, "--raw-config", str(settings))
    assert code == 2, output
    assert "'tool0'" in output and "`tip_frame` must have z along the stick" in output
    assert "wrench_sign" not in output


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
    settings.write_text(yaml.safe_dump(_settings(live[0], observation_time_s=FIRST_PRESS_S + 1)))
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
    bag.with_name("bias.deformap.yaml").write_text(yaml.safe_dump(_settings(live[0])))
    code, output, _ = _map(bag, tmp_path / "map", config_file)
    assert code == 2
    assert "from its first sample" in output and "not zeroed" in output
