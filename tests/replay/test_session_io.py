"""Sessions written and read back: folder (PCD, PLY, NPZ) and bag (MCAP, sqlite3) forms."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from deformap.cloud import PointCloud
from deformap.cloud.io import write_cloud
from deformap.errors import InvalidArgumentError
from deformap.replay import (
    FORMAT_NAME,
    FORMAT_VERSION,
    GroundTruth,
    RecordedSession,
    RecordingEnvironment,
    load_session,
    read_ground_truth,
    write_ground_truth,
    write_session,
)

FORMS = [("folder", "pcd"), ("folder", "ply"), ("folder", "npz")]
BAGS = ["mcap", "sqlite3"]


def _assert_same(session: RecordedSession, syn) -> None:  # type: ignore[no-untyped-def]
    assert np.array_equal(session.observation().points, syn.observation.points)
    assert len(session) == len(syn.presses)
    for i, want in enumerate(syn.presses):
        got = session.press_observation(i)
        assert np.array_equal(got.cloud.points, want.cloud.points)
        assert got.cloud.frame == "world"
        assert np.array_equal(got.robot_points, want.robot_points)
        assert np.array_equal(got.contact.tip_center, want.contact.tip_center)
        assert np.array_equal(got.contact.force, want.contact.force)
        assert got.contact.tip_radius_m == want.contact.tip_radius_m
        assert np.array_equal(got.target_xy, want.target_xy)
        assert got.force_n == want.force_n
        assert got.force_travel == want.force_travel  # bit for bit, or both None
    truth = session.ground_truth
    assert truth is not None
    for name in ("xs", "ys", "labels", "hardness"):
        assert np.array_equal(getattr(truth, name), getattr(syn.truth, name))


@pytest.mark.parametrize(("form", "cloud_format"), FORMS)
def test_folder_round_trip_is_exact(tmp_path: Path, synthetic, write_synthetic, form: str,
                                    cloud_format: str) -> None:  # fmt: skip
    file = write_synthetic(tmp_path / "s", synthetic, format=form, cloud_format=cloud_format,
                           source={"scenario": "synthetic", "seed": 3})  # fmt: skip
    session = load_session(file.parent)
    assert session.form == "folder"
    assert session.source == {"scenario": "synthetic", "seed": 3}
    assert session.workspace == synthetic.workspace
    _assert_same(session, synthetic)
    # the session.yaml path itself is accepted too
    assert len(load_session(file)) == len(synthetic.presses)


@pytest.mark.parametrize("storage", BAGS)
def test_bag_round_trip_is_exact(tmp_path: Path, synthetic, write_synthetic, storage: str) -> None:
    pytest.importorskip("rosbags")
    file = write_synthetic(tmp_path / "s", synthetic, format=storage)
    session = load_session(file.parent)
    assert session.form == "bag"
    assert (tmp_path / "s" / "bag" / "metadata.yaml").is_file()
    _assert_same(session, synthetic)


def test_session_yaml_is_documented_shape(tmp_path: Path, synthetic, write_synthetic) -> None:
    file = write_synthetic(tmp_path / "s", synthetic)
    doc = yaml.safe_load(file.read_text())
    assert doc["format"] == FORMAT_NAME and doc["version"] == FORMAT_VERSION
    keys = ["cloud", "tip_center", "force", "target_xy", "force_n", "robot_points"]
    assert list(doc["pokes"][1]) == keys  # a press without a force–travel record
    assert list(doc["pokes"][0]) == [*keys, "force_travel"]
    assert list(doc["pokes"][0]["force_travel"]) == ["travel_m", "force_n"]
    assert len(doc["pokes"][0]["force_travel"]["travel_m"]) == 9
    assert doc["ground_truth"] == "ground_truth.npz"


def test_camera_frame_folder_is_mapped_to_world(tmp_path: Path, synthetic, write_synthetic) -> None:
    file = write_synthetic(tmp_path / "s", synthetic, sealed=False)
    rng = np.random.default_rng(4)
    cam2world = np.eye(4)
    cam2world[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    cam2world[:3, 3] = [0.3, -0.2, 0.9]
    world2cam = np.linalg.inv(cam2world)
    folder = file.parent
    write_cloud(folder / "observation.pcd", synthetic.observation.transformed(world2cam, "world"))
    for i, press in enumerate(synthetic.presses, start=1):
        write_cloud(folder / f"poke-{i:02d}.pcd", press.cloud.transformed(world2cam, "world"))
    doc = yaml.safe_load(file.read_text())
    doc["frame"] = "camera_depth_optical_frame"
    doc["cam2world"] = cam2world.tolist()
    file.write_text(yaml.safe_dump(doc))
    session = load_session(folder)
    np.testing.assert_allclose(session.observation().points, synthetic.observation.points,
                               atol=1e-12)  # fmt: skip
    got = session.press_observation(1)
    np.testing.assert_allclose(got.cloud.points, synthetic.presses[1].cloud.points, atol=1e-12)
    # robot points and contacts stay in the world frame
    assert np.array_equal(got.robot_points, synthetic.presses[1].robot_points)


def test_inline_robot_points(tmp_path: Path, synthetic, write_synthetic) -> None:
    file = write_synthetic(tmp_path / "s", synthetic, sealed=False)
    doc = yaml.safe_load(file.read_text())
    doc["pokes"][0]["robot_points"] = synthetic.presses[0].robot_points.tolist()
    file.write_text(yaml.safe_dump(doc))
    got = load_session(file).press_observation(0)
    assert np.array_equal(got.robot_points, synthetic.presses[0].robot_points)


def test_millimetre_session(tmp_path: Path, synthetic, write_synthetic) -> None:
    file = write_synthetic(tmp_path / "s", synthetic, sealed=False)
    folder = file.parent
    mm = PointCloud(synthetic.presses[0].cloud.points * 1e3)
    write_cloud(folder / "poke-01.pcd", mm)
    write_cloud(folder / "observation.pcd", PointCloud(synthetic.observation.points * 1e3))
    write_cloud(folder / "poke-01-robot.pcd", PointCloud(synthetic.presses[0].robot_points * 1e3))
    doc = yaml.safe_load(file.read_text())
    doc["units"] = "mm"
    doc["pokes"] = doc["pokes"][:1]
    file.write_text(yaml.safe_dump(doc))
    session = load_session(folder)
    np.testing.assert_allclose(session.press_observation(0).cloud.points,
                               synthetic.presses[0].cloud.points, rtol=1e-12)  # fmt: skip


def test_ground_truth_lookup_and_round_trip(tmp_path: Path, synthetic) -> None:
    truth = synthetic.truth
    write_ground_truth(tmp_path / "t.npz", truth)
    back = read_ground_truth(tmp_path / "t.npz")
    for name in ("xs", "ys", "labels", "hardness"):
        np.testing.assert_array_equal(getattr(back, name), getattr(truth, name))
    assert set(np.unique(back.hardness).tolist()) == {80.0, np.inf}
    xs, ys = np.array([0.1, 0.29, 0.31, 0.59]), np.array([0.0, 0.2])
    labels = back.ground_truth_labels(xs, ys)
    assert labels.shape == (2, 4)
    assert labels[0].tolist() == [0, 0, 1, 1]
    assert np.isinf(back.ground_truth_hardness(xs, ys)[:, 2:]).all()


def test_ground_truth_refuses_nonconstant_hardness() -> None:
    xs, ys = np.array([0.0, 1.0]), np.array([0.0])
    with pytest.raises(InvalidArgumentError, match="constant over each label"):
        GroundTruth(xs, ys, np.array([[0, 0]]), np.array([[1.0, 2.0]]))


def test_write_session_refuses_bad_arguments(tmp_path: Path, synthetic) -> None:
    kw = {"workspace": synthetic.workspace, "observation": synthetic.observation,
          "presses": synthetic.presses}  # fmt: skip
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("x")
    with pytest.raises(InvalidArgumentError, match="not an empty folder"):
        write_session(tmp_path / "full", **kw)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`format`"):
        write_session(tmp_path / "a", format="rosbag1", **kw)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="`cloud_format`"):
        write_session(tmp_path / "b", cloud_format="las", **kw)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="tip_radius_m"):
        write_session(tmp_path / "c", tip_radius_m=0.02, **kw)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match=r"presses\[1\]"):
        write_session(tmp_path / "d", workspace=synthetic.workspace,
                      observation=synthetic.observation, presses=[synthetic.presses[0], "x"])  # type: ignore[list-item]  # fmt: skip


class _FakeEnv:
    def __init__(self, syn) -> None:  # type: ignore[no-untyped-def]
        self.syn, self.n, self.released = syn, 0, 0
        self.workspace = syn.workspace

    def observe(self):  # type: ignore[no-untyped-def]
        return self.syn.observation

    def press(self, target_xy, force_n):  # type: ignore[no-untyped-def]
        self.n += 1
        return self.syn.presses[self.n - 1]

    def release(self) -> None:
        self.released += 1


def test_recording_environment_keeps_what_passed(synthetic) -> None:
    env = RecordingEnvironment(_FakeEnv(synthetic))
    assert env.workspace == synthetic.workspace
    assert env.observe() is synthetic.observation
    for _ in synthetic.presses:
        env.press([0.1, 0.1], 1.0)
        env.release()
    assert env.observation is synthetic.observation
    assert env.presses == synthetic.presses
    assert env._env.released == len(synthetic.presses)  # type: ignore[attr-defined]
    with pytest.raises(InvalidArgumentError, match="Environment protocol"):
        RecordingEnvironment(object())  # type: ignore[arg-type]
