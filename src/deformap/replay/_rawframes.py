"""A raw bag's camera frames averaged per group, pixel by pixel: the observation's still frames
and each press's (:class:`deformap.replay.RawBagReader` plans the groups)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud.io import (
    bag_error_text,
    bag_read_errors,
    iter_bag_messages,
    pointcloud2_colors,
    pointcloud2_structured,
    typestore,
    xyz_with_holes,
)
from deformap.errors import DeformapError, FileFormatError
from deformap.replay._rawfind import CLOUD_TYPE

__all__ = ["FrameGroup", "average_frames", "group_points"]


@dataclass
class FrameGroup:
    """Frames averaged into one cloud, with the per-pixel sums (``rgb`` None once a frame lacks
    colours) and counts."""

    frames: list[int]
    cam_stamp: int
    shape: tuple[int, int] | None = None
    total: NDArray[np.float64] | None = None
    count: NDArray[np.int64] | None = None
    rgb: NDArray[np.float64] | None = None


def average_frames(path: Path, topic: str, groups: list[FrameGroup], scale: float) -> None:
    """Sum each group's frames of ``topic`` in ``path`` pixel by pixel (points times ``scale``,
    metres), one pass over the bag; a frame of another layout than its group's first, or an
    unorganised one after it, is left out (no pixel to pair)."""
    wanted: dict[int, list[FrameGroup]] = {}
    for group in groups:
        for frame in group.frames:
            wanted.setdefault(frame, []).append(group)
    store, errors = typestore(), bag_read_errors()
    for raw in iter_bag_messages(path, {topic: CLOUD_TYPE}):
        number = raw.number - 1  # the frame index the groups name
        if number not in wanted:
            continue
        where = f"{path} [{topic} message {raw.number}]"
        try:
            msg = store.deserialize_cdr(bytes(raw.data), CLOUD_TYPE)
            xyz, rgb = _xyz(msg, where)
        except errors as exc:
            raise FileFormatError(f"{where}: could not be decoded: "
                                  f"{bag_error_text(exc, 120)}") from None  # fmt: skip
        xyz = xyz * scale
        shape = (int(msg.height), int(msg.width))
        ok = np.isfinite(xyz).all(axis=1)
        for group in wanted[number]:
            if group.total is None or group.count is None:
                group.shape, group.total = shape, np.zeros_like(xyz)
                group.count = np.zeros(xyz.shape[0], dtype=np.int64)
                group.rgb = None if rgb is None else np.zeros_like(xyz)
            elif shape != group.shape or shape[0] == 1:
                continue  # another layout, or an unorganised cloud: no pixel to average
            group.total[ok] += xyz[ok]
            group.count[ok] += 1
            if group.rgb is not None and rgb is not None:
                group.rgb[ok] += rgb[ok]
            else:
                group.rgb = None


def _xyz(msg: Any, where: str) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """The frame's points, NaN holes kept, and their colours (NaN at the holes) or None."""
    try:
        table = pointcloud2_structured(msg)
        xyz = xyz_with_holes(msg, table)
    except DeformapError as exc:
        raise FileFormatError(f"{where}: {str(exc).replace('`msg` ', '')}") from None
    rgb = pointcloud2_colors(msg, where=where, table=table, valid=np.isfinite(xyz).all(axis=1))
    return xyz, rgb


def group_points(group: FrameGroup, topic: str, where: str
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:  # fmt: skip
    """The group's mean point per pixel seen at least once (camera frame) and mean colour."""
    if group.total is None or group.count is None or not group.count.any():
        raise FileFormatError(f"{where}: topic {topic!r}: its frames hold no finite point")
    seen = group.count > 0
    cam = group.total[seen] / group.count[seen, None]
    rgb = None if group.rgb is None else np.clip(group.rgb[seen] / group.count[seen, None], 0, 1)
    return cam, rgb
