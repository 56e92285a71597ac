"""What a press records besides its ramp: the cloud after release (refused with the tip in view)
and the record's time, hold and unloading carried through sessions and bags."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import (
    TIP_IN_VIEW_RADII,
    ForceTravel,
    PressObservation,
    PressPhase,
    TactileContact,
)
from deformap.errors import InvalidArgumentError

TIP = np.array([0.3, 0.2, 0.056])
RADIUS = 0.01


def _surface(dent_m: float, n: int = 400, seed: int = 0) -> PointCloud:
    """A flat top at 5 cm with a Gaussian dent of ``dent_m`` under the tip."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform([0.25, 0.15], [0.35, 0.25], (n, 2))
    z = 0.05 - dent_m * np.exp(-np.sum((xy - TIP[:2]) ** 2, axis=1) / 0.01**2)
    return PointCloud(np.column_stack([xy, z + rng.normal(0, 2e-4, n)]))


def _tip_cap(n: int = 50) -> np.ndarray:
    """Points on the upper half of the tip, as a camera above sees it."""
    rng = np.random.default_rng(1)
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.2
    return TIP + RADIUS * d / np.linalg.norm(d, axis=1, keepdims=True)


def _press(released: object = None, record: ForceTravel | None = None) -> PressObservation:
    contact = TactileContact(tip_center=TIP, force=[0, 0, -0.6], tip_radius_m=RADIUS)
    robot = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    return PressObservation(cloud=_surface(0.004), contact=contact, robot_points=robot,
                            target_xy=TIP[:2], force_n=0.6, force_travel=record,
                            released=released)  # type: ignore[arg-type]


def test_a_release_observation_without_the_tip_is_kept() -> None:
    released = _surface(0.001)
    assert _press(released).released is released
    assert _press().released is None


def test_a_release_observation_with_the_tip_in_view_is_refused() -> None:
    cloud = PointCloud(np.vstack([_surface(0.001).points, _tip_cap()]))
    with pytest.raises(InvalidArgumentError, match="`released` must be seen once the tip has left"):
        _press(cloud)
    # one point on the tip's top is enough; one just outside the stated radius is not the tip
    top = TIP + np.array([0.0, 0.0, RADIUS])
    with pytest.raises(InvalidArgumentError, match=r"`released`.*1 of its points"):
        _press(PointCloud(np.vstack([_surface(0.001).points, top])))
    outside = TIP + np.array([0.0, 0.0, 1.05 * TIP_IN_VIEW_RADII * RADIUS])
    _press(PointCloud(np.vstack([_surface(0.001).points, outside])))


def test_a_deep_press_whose_surface_rebounds_above_the_tip_centre_is_kept() -> None:
    # the tip sank 1.7 radii: the surface it left (a 2 mm dent kept) lies above the tip's centre,
    # but does not stand above the surface around it as the tip's top would
    deep = _surface(0.002, n=2000).points + np.array([0.0, 0.0, TIP[2] + 0.7 * RADIUS - 0.05])
    assert np.any(deep[np.linalg.norm(deep - TIP, axis=1) < RADIUS, 2] > TIP[2] + RADIUS / 2)
    assert _press(PointCloud(deep)).released is not None


def test_a_release_observation_that_is_not_a_cloud_is_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="`released` must be a PointCloud"):
        _press(_surface(0.001).points)


# --- sessions carry the record's time, hold and unloading and the cloud after release ----------

def _phased(syn: object) -> list[PressObservation]:
    """The synthetic presses, each record given times, a hold and an unloading and the first
    press a cloud after release (the second keeps no record, as before)."""
    from dataclasses import replace

    out = []
    for i, obs in enumerate(syn.presses):  # type: ignore[attr-defined]
        record = obs.force_travel
        if record is not None:
            n, top = len(record), float(record.travel_m[-1])
            record = ForceTravel(
                travel_m=record.travel_m, force_n=record.force_n, time_s=np.linspace(0, 0.8, n),
                hold=PressPhase(time_s=[0.9, 1.4, 2.0, 3.1], travel_m=[top] * 4,
                                force_n=[1.0, 0.93, 0.9, 0.89]),
                unloading=None if i else PressPhase(time_s=[3.2, 3.3, 3.4],
                                                    travel_m=[top, top / 2, 1e-3],
                                                    force_n=[0.85, 0.3, 0.0]))
        released = None
        if i == 0:  # a 1 mm grid around the press, its dent 1 mm deep
            g = np.arange(-0.03, 0.03, 0.001)
            gx, gy = (a.ravel() + c for a, c in zip(np.meshgrid(g, g), obs.target_xy, strict=True))
            z = 0.05 - 0.001 * np.exp(-((gx - obs.target_xy[0]) ** 2
                                        + (gy - obs.target_xy[1]) ** 2) / 0.015**2)
            released = PointCloud(np.column_stack([gx, gy, z]))
        out.append(replace(obs, force_travel=record, released=released))
    return out


@pytest.mark.parametrize("form", ["folder", "mcap"])
def test_a_session_round_trips_the_phases_and_the_release(tmp_path, synthetic, form) -> None:
    from deformap.replay import load_session, write_session

    presses = _phased(synthetic)
    write_session(tmp_path / "s", workspace=synthetic.workspace,
                  observation=synthetic.observation, presses=presses, format=form)
    session = load_session(tmp_path / "s")
    for i, want in enumerate(presses):
        got = session.press_observation(i)
        assert got.force_travel == want.force_travel
        if want.released is None:
            assert got.released is None
        else:
            assert got.released is not None
            assert np.array_equal(got.released.points, want.released.points)
    assert presses[0].force_travel is not None and presses[0].force_travel.unloading is not None


@pytest.mark.parametrize("form", ["folder", "mcap"])
def test_a_session_without_phases_loads_as_before(tmp_path, synthetic, form) -> None:
    from deformap.replay import load_session, write_session

    write_session(tmp_path / "s", workspace=synthetic.workspace,
                  observation=synthetic.observation, presses=synthetic.presses, format=form)
    session = load_session(tmp_path / "s")
    for i, want in enumerate(synthetic.presses):
        got = session.press_observation(i)
        assert got.force_travel == want.force_travel and got.released is None
        if got.force_travel is not None:
            assert got.force_travel.time_s is None and got.force_travel.hold is None


def _edit(file, change) -> None:  # type: ignore[no-untyped-def]
    import yaml

    doc = yaml.safe_load(file.read_text())
    del doc["n_pokes"], doc["sha256"]
    change(doc["pokes"][0])
    file.write_text(yaml.safe_dump(doc, sort_keys=False))


@pytest.mark.parametrize(("change", "message"), [
    (lambda p: p["force_travel"].update(time_s=p["force_travel"]["time_s"][::-1]),
     r"pokes\[0\]\.force_travel`: `time_s` must increase"),
    (lambda p: p["force_travel"]["hold"].update(time_s=[], travel_m=[], force_n=[]),
     r"pokes\[0\]\.force_travel\.hold`: `travel_m` must have at least 2 rows"),
    (lambda p: p["force_travel"]["unloading"].update(force_n=[0.3, 0.85, 0.0]),
     r"pokes\[0\]\.force_travel`: `unloading\.force_n` must fall"),
    (lambda p: p["force_travel"]["hold"].update(force_n=[1.0, float("nan"), 0.9, 0.89]),
     r"pokes\[0\]\.force_travel\.hold`: `force_n`.*NaN"),
])
def test_a_session_with_an_impossible_phase_names_the_key(tmp_path, synthetic, change,
                                                          message) -> None:
    from deformap.errors import ConfigError
    from deformap.replay import load_session, write_session

    file = write_session(tmp_path / "s", workspace=synthetic.workspace,
                         observation=synthetic.observation, presses=_phased(synthetic))
    _edit(file, change)
    session = load_session(tmp_path / "s")
    with pytest.raises(ConfigError, match=message):
        session.press_observation(0)
    session.press_observation(2)  # one broken poke hides no other


def test_a_session_with_the_tip_in_the_release_cloud_names_the_poke(tmp_path, synthetic) -> None:
    from dataclasses import replace

    from deformap.cloud.io import write_cloud
    from deformap.errors import FileFormatError
    from deformap.replay import load_session, write_session

    presses = _phased(synthetic)
    file = write_session(tmp_path / "s", workspace=synthetic.workspace,
                         observation=synthetic.observation, presses=presses)
    first = presses[0]
    assert first.released is not None
    tip = first.contact.tip_center + np.array([0.0, 0.0, 0.9 * first.contact.tip_radius_m])
    write_cloud(tmp_path / "s" / "poke-01-released.pcd",
                PointCloud(np.vstack([first.released.points, tip])))
    _edit(file, lambda p: None)  # drop the manifest the edit broke
    with pytest.raises(FileFormatError, match=r"poke 0: `released` must be seen once the tip"):
        load_session(tmp_path / "s").press_observation(0)
    assert replace(first, released=None).released is None


def test_the_map_of_a_phased_session_says_each_pokes_behaviour(tmp_path, synthetic) -> None:
    import csv
    import json

    from typer.testing import CliRunner

    from deformap.cli import app
    from deformap.replay import write_session

    presses = _phased(synthetic)
    presses[2] = _ramp_only(presses[2])
    write_session(tmp_path / "s", workspace=synthetic.workspace,
                  observation=synthetic.observation, presses=presses)
    out = tmp_path / "map"
    result = CliRunner().invoke(app, ["map", str(tmp_path / "s"), "--out", str(out),
                                      "--no-figures"])
    assert result.exit_code == 0, result.output
    pokes = json.loads((out / "report.json").read_text())["pokes"]
    rows = list(csv.DictReader((out / "pokes.csv").open()))
    assert len(pokes) == len(rows) == 3
    first, second, third = (p["behaviour"] for p in pokes)
    # the first: a hold that relaxes 11 % in 2 s with an unloading; the camera sees its dent
    assert first["behaviour"] == "viscoelastic" and first["relaxation"] > 0.05
    assert first["loss_ratio"] is not None and first["released_dent_m"] is not None
    assert second["behaviour"] == "unknown" and second["evidence"] == "no force–travel record"
    assert third == {**third, "behaviour": "unknown", "evidence": "no hold or unloading recorded"}
    assert [r["behaviour"] for r in rows] == ["viscoelastic", "unknown", "unknown"]
    assert float(rows[0]["relaxation"]) == pytest.approx(first["relaxation"])
    assert rows[1]["relaxation"] == "" and rows[2]["loss_ratio"] == ""


def _ramp_only(obs: PressObservation) -> PressObservation:
    from dataclasses import replace

    record = obs.force_travel
    assert record is not None
    return replace(obs, force_travel=ForceTravel(travel_m=record.travel_m,
                                                 force_n=record.force_n))


@pytest.mark.parametrize("codes", [[0, 0, 0, 2, 2, 1, 1], [0, 0, 0, 1, 1, 3, 3],
                                   [1, 1, 0, 0, 0, 2, 2]])
def test_a_bag_record_whose_phases_are_out_of_order_is_refused(codes: list[int]) -> None:
    from deformap.errors import FileFormatError
    from deformap.replay._bagform import _phased_record

    rows = np.column_stack([np.arange(7) * 0.1, [0, 1e-3, 2e-3, 2e-3, 2e-3, 1e-3, 0],
                            [0.02, 0.5, 1.0, 1.0, 1.0, 0.4, 0.0], codes])
    with pytest.raises(FileFormatError, match=r"`phase` must be 0 \(ramp\), 1 \(hold\) or 2"):
        _phased_record(rows)
    good = rows.copy()
    good[:, 3] = [0, 0, 0, 1, 1, 2, 2]
    record = _phased_record(good)
    assert record.hold is not None and len(record.hold) == 2
    assert record.unloading is not None and record.unloading.force_n[-1] == 0.0
