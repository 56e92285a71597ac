"""An ascii PCD or PLY cut inside its last number, or whose last row is short, is refused: the
body must end at a line break after a last row of every declared value."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.cloud.io import read_pcd, read_ply, write_pcd, write_ply
from deformap.errors import FileFormatError

Reader = Callable[..., Any]


def _ascii(tmp_path: Path, kind: str) -> tuple[Path, Reader]:
    cloud = PointCloud(np.random.default_rng(3).uniform(0.0, 1.0, (6, 3)))
    path = tmp_path / f"c.{kind}"
    if kind == "pcd":
        write_pcd(path, cloud, encoding="ascii")
        return path, read_pcd
    write_ply(path, cloud, format="ascii")
    return path, read_ply


@pytest.mark.parametrize("kind", ["pcd", "ply"])
def test_a_file_cut_inside_its_last_number_is_refused(tmp_path: Path, kind: str) -> None:
    path, read = _ascii(tmp_path, kind)
    whole = path.read_bytes()
    assert whole.endswith(b"\n") and len(read(path)[0]) == 6
    for cut in (2, 4, 6):  # inside the last number: "0.0477541" read as "0.047" before
        path.write_bytes(whole[:-cut])
        with pytest.raises(FileFormatError, match="does not end at a line break after its last "
                                                  "row") as exc:
            read(path)
        assert "\n" not in str(exc.value) and str(path) in str(exc.value)


@pytest.mark.parametrize("kind", ["pcd", "ply"])
def test_a_short_last_row_is_refused_in_one_line(tmp_path: Path, kind: str) -> None:
    path, read = _ascii(tmp_path, kind)
    whole = path.read_bytes().rstrip()
    path.write_bytes(whole[: whole.rfind(b" ")] + b"\n")  # the last value gone, the line ended
    with pytest.raises(FileFormatError, match=r"last\)? (row )?holds 2 values where the header "
                                              r"declares 3") as exc:
        read(path)
    assert "usecols" not in str(exc.value)


@pytest.mark.parametrize("kind", ["pcd", "ply"])
def test_trailing_blank_space_after_the_last_line_break_is_fine(tmp_path: Path, kind: str) -> None:
    path, read = _ascii(tmp_path, kind)
    if kind == "ply":
        path.write_bytes(path.read_bytes() + b"\n  \n")
    path.write_bytes(path.read_bytes().rstrip(b"\n") + b"\r\n")
    assert len(read(path)[0]) == 6


@pytest.mark.parametrize(("name", "kind"), [("session.yaml", "a YAML file"),
                                             ("robot.mcap", "a ROS 2 bag (MCAP"),
                                             ("robot.db3", "a ROS 2 bag (sqlite3")])
def test_a_session_or_bag_read_as_a_cloud_is_named_for_what_it_is(tmp_path: Path, name: str,
                                                                   kind: str) -> None:
    from deformap.cloud.io import read_cloud

    path = tmp_path / name
    path.write_bytes(b"x")
    with pytest.raises(FileFormatError, match=rf"{name}: {re.escape(kind)}.*, not a point cloud"):
        read_cloud(path)
