"""The point cloud container every part of deformap passes around."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import check_array, check_points, check_rigid_transform
from deformap.errors import InvalidArgumentError

__all__ = ["PointCloud"]


@dataclass(frozen=True, eq=False)
class PointCloud:
    """``points`` (n, 3) in metres in the frame named ``frame`` (``"world"`` for clouds that leave
    an ``Environment``), with optional RGB ``colors`` (n, 3) in [0, 1] (integers in [0, 255] are
    scaled); validated on construction, NaN and infinities refused.

    The arrays are stored read-only float64; operations return new clouds. An empty cloud is valid.
    """

    points: NDArray[np.float64]
    colors: NDArray[np.float64] | None = None
    frame: str = field(default="world")

    def __post_init__(self) -> None:
        pts = check_points("points", self.points, min_rows=0)
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)
        if self.colors is not None:
            raw = np.asarray(self.colors)
            if np.issubdtype(raw.dtype, np.integer):
                if raw.size and (raw.min() < 0 or raw.max() > 255):
                    raise InvalidArgumentError(
                        "`colors` given as integers must lie in [0, 255]; "
                        f"got values from {raw.min()} to {raw.max()}")
                raw = raw / 255.0
            cols = check_array("colors", raw, (pts.shape[0], 3), what="RGB values in [0, 1]")
            if cols.size and (cols.min() < 0.0 or cols.max() > 1.0):
                raise InvalidArgumentError(
                    "`colors` must lie in [0, 1] (floats) or [0, 255] (integers); "
                    f"got values from {cols.min():g} to {cols.max():g}")
            cols.setflags(write=False)
            object.__setattr__(self, "colors", cols)
        if not isinstance(self.frame, str) or not self.frame:
            raise InvalidArgumentError(f"`frame` must be a non-empty string; got {self.frame!r}")

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @property
    def xy(self) -> NDArray[np.float64]:
        """``(n, 2)`` horizontal coordinates."""
        return self.points[:, :2]

    @property
    def z(self) -> NDArray[np.float64]:
        """``(n,)`` heights."""
        return self.points[:, 2]

    def select(self, mask: Any) -> PointCloud:
        """Return the cloud of the points where ``mask`` (``(n,)`` bool, or indices) selects."""
        index, n = np.asarray(mask), len(self)
        if index.dtype == np.bool_:
            if index.shape != (n,):
                raise InvalidArgumentError(
                    f"`mask` must be a ({n},) boolean array; got shape {index.shape}")
        elif not np.issubdtype(index.dtype, np.integer):
            raise InvalidArgumentError(
                f"`mask` must be booleans or integer indices; got dtype {index.dtype}")
        elif index.size and (index.min() < -n or index.max() >= n):
            raise InvalidArgumentError(f"`mask` indices must lie in [-{n}, {n - 1}]; got "
                                       f"{int(index.min())} to {int(index.max())}")
        colors = None if self.colors is None else self.colors[index]
        return PointCloud(self.points[index], colors, frame=self.frame)

    def transformed(self, a2b: Any, frame: str) -> PointCloud:
        """Apply the 4×4 rigid transform ``a2b`` and return the cloud in ``frame``."""
        mat = check_rigid_transform("a2b", a2b)
        pts = self.points @ mat[:3, :3].T + mat[:3, 3]
        return PointCloud(pts, self.colors, frame=frame)

    @staticmethod
    def concatenate(clouds: list[PointCloud]) -> PointCloud:
        """Stack clouds of the same frame; colours are kept only if every cloud has them."""
        if not clouds:
            raise InvalidArgumentError("`clouds` must hold at least one PointCloud; got none")
        frames = {c.frame for c in clouds}
        if len(frames) != 1:
            raise InvalidArgumentError(
                f"`clouds` must share one frame; got frames {sorted(frames)}")
        pts = np.concatenate([c.points for c in clouds])
        have_colors = all(c.colors is not None for c in clouds)
        cols = np.concatenate([c.colors for c in clouds]) if have_colors else None
        return PointCloud(pts, cols, frame=clouds[0].frame)
