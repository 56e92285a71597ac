"""Recorded sessions mapped offline: parity with the live run, broken pokes, ``estimate``.

A coarse world and a short β sweep keep each exploration to seconds; the settings are the same for
the live and the offline side, so every comparison is exact.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from deformap.cli import app
from deformap.cloud import PointCloud
from deformap.cloud.io import write_cloud
from deformap.explore import Mapper, measure_press
from deformap.replay import load_session, map_session, write_session
from deformap.run import explore_scenario, load_run_config
from deformap.run._report import SHARED_KEYS

SCENARIO = "heterogeneous-150-rigid"
SEED = 3
N_BETA = 6
SMALL = {
    "world": {"element_size_m": 0.02, "top_layer_m": 0.01,
              "camera": {"width": 128, "height": 96}},
    "exploration": {
        "max_pokes": 3,
        "surface": {"fit_hyperparameters": False},
        "touch": {"roi_size_m": 0.06},
        "shape_matching": {"n_beta": N_BETA, "refine": False, "max_iter": 200},
    },
}  # fmt: skip
runner = CliRunner()


def _cli(*args: str) -> Any:
    result = runner.invoke(app, list(args))
    return result


def _betas(report: dict[str, Any]) -> list[float]:
    return [p["beta"] for p in report["pokes"]]


@pytest.fixture(scope="module")
def config_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("config") / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    return path


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory, config_file: Path) -> dict[str, Any]:
    """The live run, exactly as `deformap explore --config small.yaml --seed 3` makes it."""
    import dataclasses

    cfg = dataclasses.replace(load_run_config(config_file), scenario=SCENARIO, seed=SEED)
    out = explore_scenario(cfg, tmp_path_factory.mktemp("live") / "run", figures=False)
    return out.report


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory, config_file: Path) -> Path:
    folder = tmp_path_factory.mktemp("rec") / "session"
    result = _cli("record-sim", "--scenario", SCENARIO, "--out", str(folder), "--seed", str(SEED),
                  "--config", str(config_file))  # fmt: skip
    assert result.exit_code == 0, result.output
    return folder


def test_offline_map_gives_the_live_betas(recorded: Path, live: dict[str, Any],
                                          tmp_path: Path) -> None:  # fmt: skip
    out = tmp_path / "map"
    result = _cli("map", str(recorded), "--out", str(out), "--no-figures")
    assert result.exit_code == 0, result.output
    report = json.loads((out / "report.json").read_text())
    assert len(live["pokes"]) >= 2
    assert _betas(report) == _betas(live)
    assert [p["beta_std"] for p in report["pokes"]] == [p["beta_std"] for p in live["pokes"]]
    assert [p["contact_xy"] for p in report["pokes"]] == [p["contact_xy"] for p in live["pokes"]]
    # what record-sim saw live is in the session too
    assert load_session(recorded).source["live_betas"] == _betas(live)
    assert report["warnings"] == [] and report["skipped"] == []
    # ground truth present: the same metrics as the live run
    for key in ("accuracy", "mean_iou", "kendall_tau", "found", "true"):
        assert report["regions"][key] == live["regions"][key]
    assert report["true_regions"] == live["true_regions"]
    assert report["max_variance"] == live["max_variance"]
    assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "map.npz", "pokes.csv",
                                                     "report.json"]


def test_live_and_map_reports_share_one_schema(recorded: Path, live: dict[str, Any],
                                               tmp_path: Path) -> None:  # fmt: skip
    out = tmp_path / "map"
    result = _cli("map", str(recorded), "--out", str(out), "--no-figures", "--json", "-")
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)  # --json - : the report alone on stdout
    assert report == json.loads((out / "report.json").read_text())
    # the keys other tools read, in the order they were always written
    head = ["deformap", "seed", "config"]
    core = [*SHARED_KEYS[:-1], "true_regions", SHARED_KEYS[-1]]
    assert list(live) == ["deformap", "scenario", "seed", "config", *core]
    assert list(report) == ["deformap", "session", "form", "source", "seed", "config", *core,
                            "skipped", "warnings"]  # fmt: skip
    assert set(head) <= set(live) and set(head) <= set(report)
    assert list(live["regions"]) == list(report["regions"])
    assert set(live["timings"]) - set(report["timings"]) == {"world_build_s"}
    for live_poke, mapped_poke in zip(live["pokes"], report["pokes"], strict=True):
        # the live loop adds why it chose the target and how long choosing took
        assert set(live_poke) - set(mapped_poke) <= {"purpose", "planned_after"}
        assert set(mapped_poke) <= set(live_poke)
        assert set(mapped_poke["timings"]) == set(live_poke["timings"]) - {"target_s"}


def test_bag_form_maps_like_the_folder_form(recorded: Path, live: dict[str, Any],
                                           tmp_path: Path) -> None:  # fmt: skip
    pytest.importorskip("rosbags")
    folder = load_session(recorded)
    presses = [folder.press_observation(i) for i in range(2)]
    bag = tmp_path / "bag-session"
    write_session(bag, workspace=folder.workspace, observation=folder.observation(),
                  presses=presses, ground_truth=folder.ground_truth, source=folder.source,
                  format="mcap")  # fmt: skip
    assert load_session(bag).form == "bag"
    result = _cli("map", str(bag), "--out", str(tmp_path / "map"), "--no-figures")
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "map" / "report.json").read_text())
    assert _betas(report) == _betas(live)[:2]


def test_record_sim_writes_a_bag(config_file: Path, tmp_path: Path) -> None:
    pytest.importorskip("rosbags")
    folder = tmp_path / "bag-session"
    result = _cli("record-sim", "--scenario", SCENARIO, "--out", str(folder), "--seed", str(SEED),
                  "--config", str(config_file), "--format", "sqlite3", "--pokes", "1")  # fmt: skip
    assert result.exit_code == 0, result.output
    session = load_session(folder)
    assert session.form == "bag" and len(session) == 1
    assert session.source["seed"] == SEED and session.ground_truth is not None
    assert session.press_observation(0).contact.tip_radius_m > 0
    record = session.press_observation(0).force_travel  # the world's record, through the bag
    assert record is not None and len(record) >= 9


def test_broken_poke_is_reported_and_skipped(recorded: Path, live: dict[str, Any],
                                             tmp_path: Path) -> None:  # fmt: skip
    session = tmp_path / "session"
    shutil.copytree(recorded, session)
    data = (session / "poke-02.pcd").read_bytes()
    (session / "poke-02.pcd").write_bytes(data[: len(data) // 2])
    result = _cli("map", str(session), "--out", str(tmp_path / "map"), "--no-figures")
    assert result.exit_code == 0, result.output
    assert "poke 2 skipped" in result.output and "poke-02.pcd" in result.output
    report = json.loads((tmp_path / "map" / "report.json").read_text())
    assert len(report["warnings"]) == 1 and "poke-02.pcd" in report["warnings"][0]
    assert report["skipped"][0]["index"] == 1
    # the other pokes still count, with the β they had live
    want = [b for i, b in enumerate(_betas(live)) if i != 1]
    assert _betas(report) == want
    assert [p["index"] for p in report["pokes"]] == [i for i in range(len(live["pokes"])) if i != 1]


def test_session_without_ground_truth_has_no_metrics(recorded: Path, tmp_path: Path) -> None:
    session = tmp_path / "session"
    shutil.copytree(recorded, session)
    (session / "ground_truth.npz").unlink()
    doc = yaml.safe_load((session / "session.yaml").read_text())
    del doc["ground_truth"], doc["n_pokes"], doc["sha256"]  # edited by hand: 1 poke, no truth
    doc["pokes"] = doc["pokes"][:1]
    (session / "session.yaml").write_text(yaml.safe_dump(doc))
    result = _cli("map", str(session), "--out", str(tmp_path / "map"))
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "map" / "report.json").read_text())
    assert "accuracy" not in report["regions"] and "true_regions" not in report
    names = sorted(p.name for p in (tmp_path / "map").iterdir())
    assert names == ["config.yaml", "map.npz", "map.png", "poke-01.png", "pokes.csv",
                     "report.json"]


def test_map_session_api_skips_every_broken_poke(recorded: Path, config_file: Path,
                                                  tmp_path: Path) -> None:  # fmt: skip
    broken = tmp_path / "all-broken"
    shutil.copytree(recorded, broken)
    for name in ("poke-01.pcd", "poke-02.pcd", "poke-03.pcd"):
        (broken / name).write_bytes(b"")
    cfg = load_run_config(config_file)
    replay = map_session(load_session(broken), cfg.exploration, rng=np.random.default_rng(0))
    assert replay.result.pokes == ()
    assert [s["index"] for s in replay.skipped] == [0, 1, 2]
    assert [f"poke-0{i + 1}.pcd" in w for i, w in enumerate(replay.warnings)] == [True] * 3


def test_map_refuses_bad_arguments(recorded: Path, tmp_path: Path) -> None:
    result = _cli("map", str(tmp_path / "none"))
    assert result.exit_code == 2 and "no such session" in result.output
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("x")
    result = _cli("map", str(recorded), "--out", str(tmp_path / "full"))
    assert result.exit_code == 2 and "exists and is not empty" in result.output
    result = _cli("record-sim", "--scenario", SCENARIO, "--out", str(tmp_path / "r"),
                  "--format", "rosbag1")  # fmt: skip
    assert result.exit_code == 2 and "--format must be one of" in result.output
    (tmp_path / "file").write_text("x")
    for args in (["map", str(recorded), "--out", str(tmp_path / "file" / "sub")],
                 ["record-sim", "--scenario", SCENARIO, "--out", str(tmp_path / "file" / "r")]):
        result = _cli(*args)  # refused before any work, not after it
        assert result.exit_code == 2 and "cannot create" in result.output, result.output
    too_long = str(tmp_path / ("a" * 300))  # longer than any file name the system allows
    for args in (["map", too_long], ["explore", "--resume", too_long]):
        result = _cli(*args)
        assert result.exit_code == 2 and "File name too long" in result.output, result.output


def test_estimate_agrees_with_the_mapper(recorded: Path, live: dict[str, Any], config_file: Path,
                                         tmp_path: Path) -> None:  # fmt: skip
    session = load_session(recorded)
    press = session.press_observation(0)
    write_cloud(tmp_path / "before.ply", session.observation())
    write_cloud(tmp_path / "after.npz", press.cloud)
    write_cloud(tmp_path / "hull.pcd", PointCloud(press.robot_points))
    c = press.contact
    result = _cli("estimate", "--before", str(tmp_path / "before.ply"),
                  "--after", str(tmp_path / "after.npz"),
                  "--contact", *map(repr, c.tip_center.tolist()),
                  "--force", *map(repr, c.force.tolist()),
                  "--tip-radius", repr(c.tip_radius_m), "--robot-hull", str(tmp_path / "hull.pcd"),
                  "--config", str(config_file), "--out", str(tmp_path / "est"))  # fmt: skip
    assert result.exit_code == 0, result.output
    est = json.loads((tmp_path / "est" / "estimate.json").read_text())
    # `estimate` takes no force–travel record: it reads the dent against the tip, as the mapper
    # does a press without one (with the record the mapper anchors the dent to it instead).
    # The surface fit covers only the poke's surroundings here, so β may move by one sweep step.
    cfg = load_run_config(config_file).exploration
    surface = Mapper(session.workspace, cfg).initialise(session.observation(),
                                                        np.random.default_rng(0))
    bare = dataclasses.replace(press, force_travel=None)
    camera_only = measure_press(bare, 0, surface, cfg).record
    assert camera_only.depth_anchored is False and live["pokes"][0]["depth_anchored"] is True
    assert abs(est["beta"] - camera_only.beta) <= 1.0 / N_BETA + 1e-12
    assert len(est["betas"]) == len(est["errors"]) == N_BETA
    assert np.allclose(est["contact_point"], c.contact_point)
    assert (tmp_path / "est" / "beta-curve.png").stat().st_size > 0
    assert (tmp_path / "est" / "poke.png").stat().st_size > 0
    assert sorted(p.name for p in (tmp_path / "est").iterdir()) == [
        "beta-curve.png", "estimate.json", "poke.png"]  # fmt: skip


def _write_record(path: Path, travel_m: Any, force_n: Any, header: str = "time_s,travel_mm,force_n"
                  ) -> Path:  # fmt: skip
    rows = [header] + [f"{0.01 * i:.2f},{1e3 * float(t)!r},{float(f)!r}" for i, (t, f) in
                       enumerate(zip(travel_m, force_n, strict=True))]  # fmt: skip
    path.write_text("\n".join(rows) + "\n")
    return path


def test_estimate_with_a_force_travel_record_gives_the_mappers_modulus(
        recorded: Path, live: dict[str, Any], config_file: Path, tmp_path: Path) -> None:
    session = load_session(recorded)
    press = session.press_observation(0)
    assert press.force_travel is not None
    write_cloud(tmp_path / "before.ply", session.observation())
    write_cloud(tmp_path / "after.npz", press.cloud)
    record = _write_record(tmp_path / "press.csv", press.force_travel.travel_m,
                           press.force_travel.force_n)  # fmt: skip
    c = press.contact
    args = ["estimate", "--before", str(tmp_path / "before.ply"),
            "--after", str(tmp_path / "after.npz"), "--contact", *map(repr, c.tip_center.tolist()),
            "--force", *map(repr, c.force.tolist()), "--tip-radius", repr(c.tip_radius_m),
            "--config", str(config_file)]  # fmt: skip
    result = _cli(*args, "--record", str(record), "--json", str(tmp_path / "e.json"))
    assert result.exit_code == 0, result.output
    est = json.loads((tmp_path / "e.json").read_text())
    mapped = live["pokes"][0]
    # the same record read as the mapper reads it; the layer's thickness comes from a surface fit
    # over the poke's surroundings only, so E agrees to the thickness's effect, not to the bit
    assert est["depth_anchored"] is True and est["stiffness"]["rigid"] is False
    assert est["stiffness"]["modulus_pa"] == pytest.approx(mapped["stiffness"]["modulus_pa"], rel=0.02)
    assert est["layer_thickness_m"] == pytest.approx(mapped["layer_thickness_m"], abs=1e-3)
    assert abs(est["beta"] - mapped["beta"]) <= 1.0 / N_BETA + 1e-12
    assert "E = " in result.output and "kPa" in result.output
    # without the record: no modulus, said so in the report
    result = _cli(*args, "--json", str(tmp_path / "b.json"))
    bare = json.loads((tmp_path / "b.json").read_text())
    assert result.exit_code == 0 and bare["stiffness"] is None and bare["depth_anchored"] is False
    # a record of another press (ending far from --force) is refused naming both options
    result = _cli(*args, "--record", str(_write_record(
        tmp_path / "other.csv", press.force_travel.travel_m, 2.0 * press.force_travel.force_n)))
    assert result.exit_code == 2 and "--record/--force" in result.output, result.output


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("travel_m,force\n0,0\n", "must name one travel column (travel_m or travel_mm) and force_n"),
        ("travel_m,force_n\n", "no samples below the header"),
        ("travel_m,force_n\n0,0\n0.001,x\n", "row 3 must hold a number"),
        ("travel_m,force_n\n0,0\n0.001,nan\n", "row 3 holds a NaN"),
        ("travel_m,force_n\n0,0\n0.002,0.3\n0.001,0.6\n", "`travel_m` must not go back"),
        ("\xff\xfe", "cannot read this force–travel record"),
    ],
)
def test_estimate_refuses_a_bad_force_travel_record(tmp_path: Path, text: str, match: str) -> None:
    write_cloud(tmp_path / "c.pcd", PointCloud(np.random.default_rng(0).uniform(0, 0.3, (50, 3))))
    (tmp_path / "r.csv").write_bytes(text.encode("latin-1"))
    result = _cli("estimate", "--before", str(tmp_path / "c.pcd"), "--after",
                  str(tmp_path / "c.pcd"), "--contact", "0.1", "0.1", "0.05", "--force", "0", "0",
                  "-0.6", "--tip-radius", "0.01", "--record", str(tmp_path / "r.csv"))  # fmt: skip
    assert result.exit_code == 2, result.output
    assert "r.csv" in result.output and match in " ".join(result.output.split()), result.output


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--force", "0", "0", "0"], "--contact/--force/--tip-radius: `force` must be a non-zero"),
        (["--tip-radius", "-1"], "`tip_radius_m` must be > 0"),
        (["--before", "missing.pcd"], "missing.pcd: no such file"),
        (["--contact", "0.1", "0.1", "0.9"], "`after` and `contact`: the contact point"),
    ],
)
def test_estimate_refuses_bad_input(tmp_path: Path, args: list[str], match: str) -> None:
    write_cloud(tmp_path / "c.pcd", PointCloud(np.random.default_rng(0).uniform(0, 0.3, (50, 3))))
    base = {"--before": [str(tmp_path / "c.pcd")], "--after": [str(tmp_path / "c.pcd")],
            "--contact": ["0.1", "0.1", "0.05"], "--force": ["0", "0", "-1"],
            "--tip-radius": ["0.01"]}  # fmt: skip
    base[args[0]] = [a if not a.endswith(".pcd") else str(tmp_path / a) for a in args[1:]]
    flat = [x for key, values in base.items() for x in (key, *values)]
    result = _cli("estimate", *flat)
    assert result.exit_code == 2, result.output
    assert match in " ".join(result.output.split())


def test_estimate_refuses_an_out_folder_it_cannot_create(tmp_path: Path) -> None:
    cloud = tmp_path / "c.pcd"
    write_cloud(cloud, PointCloud(np.random.default_rng(0).uniform(0, 0.3, (50, 3))))
    result = _cli("estimate", "--before", str(cloud), "--after", str(cloud), "--contact", "0.1",
                  "0.1", "0.05", "--force", "0", "0", "-1", "--tip-radius", "0.01",
                  "--out", str(cloud))  # fmt: skip
    assert result.exit_code == 2, result.output
    assert "cannot create" in result.output


def test_tip_sphere_points_lie_on_the_tip() -> None:
    from deformap.replay import tip_sphere_points

    center = np.array([0.1, 0.2, 0.06])
    pts = tip_sphere_points(center, 0.01)
    assert pts.shape == (6, 3)
    np.testing.assert_allclose(np.linalg.norm(pts - center, axis=1), 0.01)
    np.testing.assert_allclose(pts.mean(axis=0), center)


def test_record_sim_keeps_each_press_force_travel_record(recorded: Path) -> None:
    session = load_session(recorded)
    text = (recorded / "session.yaml").read_text()
    assert text.count("force_travel:") == len(session) >= 2
    for i in range(len(session)):
        obs = session.press_observation(i)
        assert obs.force_travel is not None and len(obs.force_travel) >= 9
        assert obs.force_travel.force_n[-1] == pytest.approx(obs.force_n, rel=0.1)


@pytest.mark.parametrize("form", ["folder", "mcap"])
def test_recorded_world_presses_read_back_identical(tmp_path: Path, form: str) -> None:
    if form != "folder":
        pytest.importorskip("rosbags")
    from deformap.replay import RecordingEnvironment
    from deformap.world import SimulatedWorld, WorldConfig, load_scenario

    world = SimulatedWorld(load_scenario(SCENARIO), config=WorldConfig.coarse(),
                           rng=np.random.default_rng(SEED))
    env = RecordingEnvironment(world)
    env.observe()
    for xy in ((0.1, 0.2), (0.5, 0.2)):  # a foam and the rigid board
        env.press(xy, 0.6)
        env.release()
    write_session(tmp_path / "s", workspace=world.workspace, observation=env.observation,
                  presses=env.presses, format=form)  # fmt: skip
    session = load_session(tmp_path / "s")
    for i, want in enumerate(env.presses):
        got = session.press_observation(i)
        assert want.force_travel is not None
        assert got.force_travel == want.force_travel
        assert np.array_equal(got.cloud.points, want.cloud.points)


def test_map_rerun_writes_the_recording_of_the_mapped_session(recorded: Path, tmp_path: Path
                                                              ) -> None:  # fmt: skip
    pytest.importorskip("rerun")
    from rerun.chunk import RrdReader

    result = _cli("map", str(recorded), "--out", str(tmp_path / "m"), "--no-figures", "--rerun")
    assert result.exit_code == 0, result.output
    chunks = list(RrdReader(tmp_path / "m" / "run.rrd").stream())
    entities = {str(c.entity_path) for c in chunks}
    assert {"/world", "/world/observation", "/world/press/dent", "/maps/beta"} <= entities
    beta = [c.to_record_batch() for c in chunks if str(c.entity_path) == "/metrics/beta"]
    assert sum(b.num_rows for b in beta) == len(load_session(recorded))  # one row a poke
    assert all({"poke", "time"} <= set(b.schema.names) for b in beta)
