"""The folder form of a session: a cloud file per observation, contacts in ``session.yaml``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud
from deformap.cloud.io import path_kind, read_cloud
from deformap.environment import ForceTravel
from deformap.errors import FileFormatError
from deformap.replay._format import PokeSpec, SessionHeader
from deformap.replay._manifest import verify_digest

__all__ = ["FolderReader", "PressParts"]


@dataclass(frozen=True)
class PressParts:
    """What one poke's files hold before it becomes a ``PressObservation`` (world frame, SI)."""

    cloud: PointCloud
    tip_center: NDArray[np.float64]
    force: NDArray[np.float64]
    robot_points: NDArray[np.float64] | tuple[NDArray[np.float64], ...]  # one hull, or per part
    force_travel: ForceTravel | None = None


def _to_world(cloud: PointCloud, header: SessionHeader) -> PointCloud:
    if header.frame == "world":
        return cloud
    assert isinstance(header.cam2world, np.ndarray)  # parse_session_yaml guarantees it
    return PointCloud(cloud.points, cloud.colors, frame=header.frame).transformed(
        header.cam2world, "world")


class FolderReader:
    """Reads the files a folder-form ``session.yaml`` names, one at a time."""

    def __init__(self, header: SessionHeader) -> None:
        self.header = header
        assert header.observation is not None
        if path_kind(header.observation) != "file":
            raise FileFormatError(
                f"{header.observation}: no such file (the session's `observation`)")

    def observation(self) -> PointCloud:
        return _to_world(read_cloud(self._path(self.header.observation), units=self.header.units),
                         self.header)  # fmt: skip

    def press_parts(self, spec: PokeSpec) -> PressParts:
        assert spec.cloud is not None and spec.tip_center is not None and spec.force is not None
        cloud = _to_world(read_cloud(self._path(spec.cloud), units=self.header.units), self.header)
        robot = spec.robot_points
        if isinstance(robot, Path):
            # Robot geometry comes from the robot model in the world (base) frame, not the camera's.
            robot = np.asarray(read_cloud(self._path(robot), units=self.header.units).points)
        assert robot is not None
        return PressParts(cloud, spec.tip_center, spec.force, robot, spec.force_travel)

    def _path(self, path: Path | None) -> Path:
        assert path is not None
        if path_kind(path) != "file":
            raise FileFormatError(f"{path}: no such file")
        verify_digest(self.header, path)
        return path
