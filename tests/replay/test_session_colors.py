"""Colour through every session form: a session recorded from a coloured world gives each press
cloud and the observation handed to the mapper their colours back (8-bit colours exactly), from
folder sessions (PCD, PLY, NPZ), bag sessions (MCAP, sqlite3) and raw robot bags; a colourless
session stays colourless."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from deformap.cloud import PointCloud
from deformap.environment import ForceTravel
from deformap.errors import FileFormatError
from deformap.replay import load_raw_bag, load_raw_config, load_session

FORMS = [("folder", "pcd"), ("folder", "ply"), ("folder", "npz"), ("mcap", "pcd"),
         ("sqlite3", "pcd")]  # fmt: skip


def _colour(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    """The cloud with 8-bit colours (k/255), as a camera gives them."""
    return PointCloud(cloud.points, rng.integers(0, 256, (len(cloud), 3)) / 255.0,
                      frame=cloud.frame)  # fmt: skip


@pytest.fixture(scope="module")
def coloured(make_synthetic: Any) -> Any:
    syn = make_synthetic(n_points=300)
    rng = np.random.default_rng(5)
    presses = [dataclasses.replace(p, cloud=_colour(p.cloud, rng)) for p in syn.presses]
    return dataclasses.replace(syn, observation=_colour(syn.observation, rng), presses=presses)


@pytest.mark.parametrize(("form", "cloud_format"), FORMS)
def test_every_session_form_gives_the_colours_back(tmp_path: Path, coloured: Any,
                                                   write_synthetic: Any, form: str,
                                                   cloud_format: str) -> None:  # fmt: skip
    if form != "folder":
        pytest.importorskip("rosbags")
    session = load_session(write_synthetic(tmp_path / "s", coloured, format=form,
                                           cloud_format=cloud_format).parent)  # fmt: skip
    np.testing.assert_array_equal(session.observation().colors, coloured.observation.colors)
    for i, want in enumerate(coloured.presses):
        got = session.press_observation(i)
        np.testing.assert_array_equal(got.cloud.points, want.cloud.points)
        np.testing.assert_array_equal(got.cloud.colors, want.cloud.colors)


def test_a_poke_file_with_nan_colours_is_refused_naming_file_and_field(
        tmp_path: Path, coloured: Any, write_synthetic: Any) -> None:  # fmt: skip
    file = write_synthetic(tmp_path / "s", coloured, cloud_format="npz", sealed=False)
    cloud = coloured.presses[0].cloud
    colors = np.array(cloud.colors)
    colors[7, 2] = np.nan
    np.savez(file.parent / "poke-01.npz", points=cloud.points, colors=colors)
    session = load_session(file.parent)
    with pytest.raises(FileFormatError) as info:
        session.press_observation(0)
    text = str(info.value)
    assert "poke-01.npz" in text and "colour field 'colors' of point 7" in text
    assert "\n" not in text
    assert session.press_observation(1).cloud.colors is not None  # the other pokes still read


@pytest.mark.parametrize(("form", "cloud_format"), FORMS)
def test_a_colourless_session_stays_colourless(tmp_path: Path, make_synthetic: Any,
                                               write_synthetic: Any, form: str,
                                               cloud_format: str) -> None:  # fmt: skip
    if form != "folder":
        pytest.importorskip("rosbags")
    syn = make_synthetic(n_points=200, n_pokes=2)
    session = load_session(write_synthetic(tmp_path / "s", syn, format=form,
                                           cloud_format=cloud_format).parent)  # fmt: skip
    assert session.observation().colors is None
    assert all(session.press_observation(i).cloud.colors is None for i in range(len(session)))


def _with_records(syn: Any) -> Any:
    """Every press with a force–travel record (a raw bag's ramp is drawn along it)."""
    record = ForceTravel(travel_m=np.linspace(0.0, 0.006, 9), force_n=np.linspace(0.02, 1.0, 9))
    return dataclasses.replace(syn, presses=[p if p.force_travel is not None else
                                             dataclasses.replace(p, force_travel=record)
                                             for p in syn.presses])  # fmt: skip


def _raw(folder: Path, session: Any, **kwargs: Any) -> Any:
    pytest.importorskip("mcap_ros2.writer")
    from deformap.testing.robotbag import raw_settings, write_raw_bag

    bag = folder / "lab.mcap"
    write_raw_bag(bag, session, camera_hz=15.0, tf_hz=25.0, wrench_hz=100.0, **kwargs)
    bag.with_name("lab.deformap.yaml").write_text(yaml.safe_dump(raw_settings(session, force_n=1.0)))
    return load_raw_bag(bag, load_raw_config(bag), default_force_n=1.0)


def test_a_raw_bag_averages_each_pixel_colour_over_its_frames(tmp_path: Path, coloured: Any,
                                                              write_synthetic: Any) -> None:  # fmt: skip
    # the organised frames have NaN holes and pixels blanked in some frames: each point's colour
    # is the mean over the frames that saw it, which is its colour (it does not change)
    recorded = load_session(write_synthetic(tmp_path / "s", _with_records(coloured),
                                            cloud_format="npz").parent)  # fmt: skip
    raw = _raw(tmp_path, recorded, colors=True)
    got = raw.observation()
    np.testing.assert_allclose(got.points, coloured.observation.points, atol=1e-6)
    np.testing.assert_allclose(got.colors, coloured.observation.colors, atol=1e-12)  # type: ignore[arg-type]
    assert len(raw) == len(coloured.presses)
    for i, want in enumerate(coloured.presses):
        cloud = raw.press_observation(i).cloud
        np.testing.assert_allclose(cloud.colors, want.cloud.colors, atol=1e-12)  # type: ignore[arg-type]


def test_a_raw_bag_in_one_grey_gives_a_valid_constant_colour(
        tmp_path: Path, make_synthetic: Any, write_synthetic: Any) -> None:  # fmt: skip
    syn = _with_records(make_synthetic(n_points=200, n_pokes=2))
    recorded = load_session(write_synthetic(tmp_path / "s", syn, cloud_format="npz").parent)
    colors = _raw(tmp_path, recorded).observation().colors
    assert colors is not None
    np.testing.assert_allclose(colors, 0x80 / 255, atol=1e-12)
