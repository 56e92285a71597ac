"""Every way a session can be broken gives a DeformapError naming the file, key or topic."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from deformap.cloud import PointCloud
from deformap.cloud.io import write_cloud
from deformap.errors import ConfigError, FileFormatError, InvalidArgumentError
from deformap.replay import load_session

Edit = Callable[[dict[str, Any]], None]


@pytest.fixture
def folder(tmp_path: Path, synthetic, write_synthetic) -> Path:  # type: ignore[no-untyped-def]
    return write_synthetic(tmp_path / "s", synthetic, sealed=False).parent  # type: ignore[no-any-return]


def _edit(folder: Path, change: Edit) -> None:
    file = folder / "session.yaml"
    doc = yaml.safe_load(file.read_text())
    change(doc)
    file.write_text(yaml.safe_dump(doc))


def _set(path: str, value: Any) -> Edit:
    def change(doc: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        node: Any = doc
        for key in parents:
            node = node[int(key)] if isinstance(node, list) else node[key]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value

    return change


def _drop(key: str) -> Edit:
    return lambda doc: doc.pop(key)


# -- the file as a whole: refused at load ------------------------------------------------------
@pytest.mark.parametrize(
    ("change", "match"),
    [
        (_set("colour", "red"), r"unknown key\(s\) \['colour'\]"),
        (_drop("workspace"), r"lacks required key\(s\) \['workspace'\]"),
        (_set("format", "pcl-session"), "`format` must be 'deformap-session'"),
        (_set("version", 2), "`version` must be 1"),
        (_set("version", True), "`version` must be 1"),
        (_set("bag", "bag"), "exactly one of `observation`"),
        (_drop("observation"), "exactly one of `observation`.*neither"),
        (_set("units", "cm"), "`units` must be one of"),
        (_set("frame", "camera"), "`cam2world`.*is required"),
        (_set("cam2world", np.eye(4).tolist()), "`cam2world` is given but `frame` is 'world'"),
        (_set("workspace.upper", [0.6]), r"`workspace.upper` must be a \(2,\) array"),
        (_set("workspace.upper", [-1.0, 0.4]), "`workspace`.*must exceed"),
        (_set("workspace.depth", 1.0), r"`workspace` has unknown key\(s\) \['depth'\]"),
        (_set("probe.tip_radius_m", -0.01), "`probe.tip_radius_m` must be >= 1e-06"),
        (_set("probe", 0.01), "`probe` must be a mapping"),
        (_set("pokes", {"a": 1}), "`pokes` must be a list"),
        (_set("pokes.0.colour", 1), r"`pokes\[0\]` has unknown key\(s\) \['colour'\]"),
        (lambda d: d["pokes"][1].pop("force"), r"`pokes\[1\]` lacks required key\(s\) \['force'\]"),
        (_set("source", [1, 2]), "`source` must be a mapping"),
    ],
)
def test_bad_session_yaml_is_refused_at_load(folder: Path, change: Edit, match: str) -> None:
    _edit(folder, change)
    with pytest.raises(ConfigError, match=match) as info:
        load_session(folder)
    assert "session.yaml" in str(info.value)


def test_cam2world_must_be_rigid(folder: Path) -> None:
    scaled = (np.eye(4) * 2.0).tolist()
    _edit(folder, lambda d: d.update(frame="cam", cam2world=scaled))
    with pytest.raises(ConfigError, match="`cam2world` must be a rigid transform"):
        load_session(folder)
    _edit(folder, lambda d: d.update(cam2world="tf_static"))
    with pytest.raises(ConfigError, match="'tf_static' needs the bag form"):
        load_session(folder)


@pytest.mark.parametrize(
    ("text", "error", "match"),
    [
        (b"format: [unclosed", ConfigError, "not valid YAML"),
        (b"\xff\xfe\x00garbage", ConfigError, "not UTF-8"),
        (b"- just\n- a list\n", ConfigError, "must be a mapping"),
        (b"", ConfigError, "must be a mapping"),
    ],
)
def test_unreadable_session_yaml(folder: Path, text: bytes, error: type, match: str) -> None:
    (folder / "session.yaml").write_bytes(text)
    with pytest.raises(error, match=match):
        load_session(folder)


def test_missing_session(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="no such session"):
        load_session(tmp_path / "nothing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileFormatError, match=r"has no session\.yaml"):
        load_session(tmp_path / "empty")
    with pytest.raises(InvalidArgumentError, match="`path`"):
        load_session(3)  # type: ignore[arg-type]


def test_missing_observation_file(folder: Path) -> None:
    (folder / "observation.pcd").unlink()
    with pytest.raises(FileFormatError, match=r"observation.pcd: no such file"):
        load_session(folder)


def test_missing_or_broken_ground_truth(folder: Path) -> None:
    (folder / "ground_truth.npz").write_bytes(b"PK\x03\x04 truncated")
    with pytest.raises(
        FileFormatError, match=r"ground_truth\.npz: could not read the ground-truth NPZ"
    ):
        load_session(folder)
    with open(folder / "ground_truth.npz", "wb") as fh:
        np.savez(fh, xs=np.arange(3.0))
    with pytest.raises(FileFormatError, match=r"lacks array\(s\) \['hardness', 'labels', 'ys'\]"):
        load_session(folder)
    (folder / "ground_truth.npz").unlink()
    with pytest.raises(FileFormatError, match="no such file"):
        load_session(folder)


# -- one poke broken: only that poke is refused ---------------------------------------------
def _only_poke_broken(folder: Path, broken: int, error: type, match: str) -> None:
    session = load_session(folder)
    for i in range(len(session)):
        if i == broken:
            with pytest.raises(error, match=match):
                session.press_observation(i)
        else:
            session.press_observation(i)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (_set("pokes.1.tip_center", [0.3, float("nan"), 0.06]), r"pokes\[1\].tip_center.*NaN"),
        (_set("pokes.1.force", [0.0, 0.0, 0.0]), r"pokes\[1\].force` must be non-zero"),
        (_set("pokes.1.target_xy", [0.3]), r"pokes\[1\].target_xy"),
        (_set("pokes.1.force_n", "one"), r"pokes\[1\].force_n` must be a real number"),
        (
            _set("pokes.1.robot_points", [[0, 0, 0]]),
            r"pokes\[1\].robot_points` must have at least 4",
        ),
        (_set("pokes.1.cloud", 5), r"pokes\[1\].cloud` must be a file name"),
    ],
)
def test_bad_poke_entry_breaks_only_that_poke(folder: Path, change: Edit, match: str) -> None:
    _edit(folder, change)
    _only_poke_broken(folder, 1, ConfigError, match)


def test_missing_poke_file(folder: Path) -> None:
    (folder / "poke-02.pcd").unlink()
    _only_poke_broken(folder, 1, FileFormatError, r"poke-02.pcd: no such file")
    (folder / "poke-03-robot.pcd").unlink()
    session = load_session(folder)
    with pytest.raises(FileFormatError, match=r"poke-03-robot.pcd: no such file"):
        session.press_observation(2)


_TOO_LONG = "a" * 300 + ".pcd"  # longer than any file name the system allows (NAME_MAX 255)


def test_file_names_the_system_refuses_are_file_format_errors(folder: Path) -> None:
    with pytest.raises(FileFormatError, match="File name too long"):
        load_session(folder / _TOO_LONG)
    _edit(folder, _set("pokes.1.cloud", _TOO_LONG))
    _only_poke_broken(folder, 1, FileFormatError, "File name too long")
    _edit(folder, _set("ground_truth", _TOO_LONG))
    with pytest.raises(FileFormatError, match="File name too long"):
        load_session(folder)
    _edit(folder, _set("observation", _TOO_LONG))
    with pytest.raises(FileFormatError, match="File name too long"):
        load_session(folder)


def test_truncated_poke_file(folder: Path) -> None:
    data = (folder / "poke-02.pcd").read_bytes()
    (folder / "poke-02.pcd").write_bytes(data[: len(data) // 2])
    _only_poke_broken(folder, 1, FileFormatError, r"poke-02.pcd")


def test_nan_and_empty_and_millimetre_clouds(folder: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    pts = synthetic.presses[1].cloud.points.copy()
    pts[5, 2] = np.nan
    with open(folder / "poke-02.npz", "wb") as fh:
        np.savez(fh, points=pts)
    _edit(folder, _set("pokes.1.cloud", "poke-02.npz"))
    _only_poke_broken(folder, 1, FileFormatError, r"poke-02.npz: 1 of \d+ points have a NaN")
    with open(folder / "poke-02.npz", "wb") as fh:
        np.savez(fh, points=np.zeros((0, 3)))
    _only_poke_broken(folder, 1, FileFormatError, r"poke-02.npz: the cloud is empty")
    write_cloud(folder / "poke-02.npz", PointCloud(synthetic.presses[1].cloud.points * 1e3))
    _only_poke_broken(folder, 1, FileFormatError, r"poke-02.npz: .*looks like millimetres")


def test_missing_xyz_field(folder: Path) -> None:
    (folder / "poke-02.ply").write_text(
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
        "end_header\n0 0\n"
    )
    _edit(folder, _set("pokes.1.cloud", "poke-02.ply"))
    _only_poke_broken(folder, 1, FileFormatError, r"poke-02.ply.*'z'")


def test_contact_far_from_any_point(folder: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    tip = synthetic.presses[1].contact.tip_center + np.array([0, 0, 0.5])
    _edit(folder, _set("pokes.1.tip_center", tip.tolist()))
    _only_poke_broken(folder, 1, FileFormatError,
                      r"poke 1: the contact point .* from the nearest surface point")  # fmt: skip


def synthetic_upper_x(folder: Path) -> float:
    return float(yaml.safe_load((folder / "session.yaml").read_text())["workspace"]["upper"][0])


def test_contact_outside_workspace(folder: Path) -> None:
    _edit(folder, _set("pokes.1.tip_center", [0.9, 0.2, 0.05]))
    _only_poke_broken(
        folder, 1, FileFormatError, r"poke 1: the contact point .* outside the workspace"
    )
    # just past the edge (2 cm, within the slack) and next to the surface: accepted
    _edit(folder, _set("pokes.1.tip_center", [0.62, 0.2, 0.06]))
    got = load_session(folder).press_observation(1)
    assert got.contact.contact_point[0] > synthetic_upper_x(folder)


def test_cloud_in_another_frame_is_caught_by_the_contact_check(folder: Path, synthetic) -> None:  # type: ignore[no-untyped-def]
    # A camera-frame cloud declared as world: the contact lands far from its points.
    cam = synthetic.presses[1].cloud.points + np.array([0.0, 0.0, 0.8])
    write_cloud(folder / "poke-02.pcd", PointCloud(cam))
    _only_poke_broken(folder, 1, FileFormatError, "different frames or units")


def test_poke_index_out_of_range(folder: Path) -> None:
    session = load_session(folder)
    with pytest.raises(InvalidArgumentError, match="`index` must be < 3"):
        session.press_observation(3)
    with pytest.raises(InvalidArgumentError, match="`index`"):
        session.press_observation(-1)


# -- the force–travel record of a poke -----------------------------------------------------------
_GOOD_TRAVEL = [0.0, 0.001, 0.002, 0.003, 0.004]
_GOOD_FORCE = [0.02, 0.25, 0.5, 0.75, 1.0]


def _record(travel: Any = None, force: Any = None) -> dict[str, Any]:
    return {"travel_m": _GOOD_TRAVEL if travel is None else travel,
            "force_n": _GOOD_FORCE if force is None else force}


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (_set("pokes.1.force_travel", [1.0, 2.0]), r"`pokes\[1\].force_travel` must be a mapping"),
        (_set("pokes.1.force_travel", {**_record(), "speed": [0, 1, 2, 3, 4]}),
         r"`pokes\[1\].force_travel` has unknown key\(s\) \['speed'\]"),
        (_set("pokes.1.force_travel", {**_record(), "hold": {"time_s": [5, 6]}}),
         r"`pokes\[1\].force_travel.hold` lacks required key\(s\) \['force_n', 'travel_m'\]"),
        (_set("pokes.1.force_travel", {"travel_m": _GOOD_TRAVEL}),
         r"`pokes\[1\].force_travel` lacks required key\(s\) \['force_n'\]"),
    ],
)
def test_force_travel_schema_is_refused_at_load(folder: Path, change: Edit, match: str) -> None:
    _edit(folder, change)
    with pytest.raises(ConfigError, match=match):
        load_session(folder)


@pytest.mark.parametrize(
    ("record", "match"),
    [
        (_record(travel=[0.0, float("nan"), 0.002, 0.003, 0.004]), "`travel_m`.*NaN or infinite"),
        (_record(force=[0.02, 0.25, float("inf"), 0.75, 1.0]), "`force_n`.*NaN or infinite"),
        (_record(travel=[0.0, 0.001], force=[0.02, 1.0]), "`travel_m` must have at least 3"),
        (_record(force=[0.02, 0.5, 1.0]), "`force_n` must have one sample per"),
        (_record(travel=[0.0, 0.003, 0.001, 0.003, 0.004]), "`travel_m` must not go backwards"),
        (_record(force=[1.0, 0.75, 0.5, 0.25, 0.02]), "`force_n` must rise"),
        (_record(force=[1.0, 1.0, 1.0, 1.0, 1.0]), "`force_n` must rise"),
        (_record(travel=[0.0, 1.0, 2.0, 3.0, 4.0]), "`travel_m` must be metres.*millimetres"),
        (_record(travel="0 1 2"), "`travel_m` must be a"),
    ],
)
def test_bad_force_travel_values_break_only_that_poke(folder: Path, record: dict[str, Any],
                                                      match: str) -> None:  # fmt: skip
    _edit(folder, _set("pokes.1.force_travel", record))
    _only_poke_broken(folder, 1, ConfigError, r"`pokes\[1\].force_travel`: " + match)


def test_force_travel_far_from_the_commanded_force_breaks_only_that_poke(folder: Path) -> None:
    _edit(folder, _set("pokes.1.force_travel", _record(force=[0.02, 0.1, 0.2, 0.3, 0.5])))
    _only_poke_broken(folder, 1, FileFormatError, "poke 1: `force_travel` must end at the "
                                                  "commanded force 1 N")


def test_a_good_record_added_by_hand_is_read(folder: Path) -> None:
    _edit(folder, _set("pokes.1.force_travel", _record()))
    got = load_session(folder).press_observation(1).force_travel
    assert got is not None
    assert got.travel_m.tolist() == _GOOD_TRAVEL and got.force_n.tolist() == _GOOD_FORCE


def test_a_session_without_records_loads_with_none(folder: Path) -> None:
    _edit(folder, lambda doc: [poke.pop("force_travel", None) for poke in doc["pokes"]])
    session = load_session(folder)
    assert all(session.press_observation(i).force_travel is None for i in range(len(session)))


@pytest.mark.parametrize(("force", "match"), [
    ([0.0, 0.0, 1.0], r"poke 1: `contact.force` must push into the surface"),
    ([0.0, 0.0, -1e6], r"poke 1: `contact.force` must be near the commanded force 1 N"),
])
def test_an_impossible_contact_force_breaks_only_that_poke(folder: Path, force: list[float],
                                                           match: str) -> None:
    _edit(folder, _set("pokes.1.force", force))
    _only_poke_broken(folder, 1, FileFormatError, match)
