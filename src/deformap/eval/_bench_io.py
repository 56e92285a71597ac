"""Benchmark of the recorded-data path: reading a large PCD file and a large PointCloud2 message,
everything a user waits for included (parsing, the checks, the :class:`~deformap.cloud.PointCloud`).
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from deformap._validation import check_int
from deformap.cloud import PointCloud
from deformap.errors import InvalidArgumentError

__all__ = ["IO_GOAL_S", "bench_io"]

IO_GOAL_S = 0.5
"""The budget for reading one 300,000-point cloud, seconds."""


def _best_of(repeats: int, run: Callable[[], Any]) -> tuple[float, float]:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return float(min(times)), float(np.median(times))


def _scene(n_points: int, rng: np.random.Generator) -> PointCloud:
    """A depth-camera-like cloud with colours over the 0.6 × 0.4 m workspace."""
    xy = rng.uniform((0.0, 0.0), (0.6, 0.4), (n_points, 2))
    z = 0.05 + 0.01 * np.sin(20 * xy[:, 0]) + rng.normal(0, 5e-4, n_points)
    return PointCloud(np.column_stack([xy, z]), rng.integers(0, 256, (n_points, 3)) / 255.0)


def bench_io(*, n_points: int = 300_000, rng: np.random.Generator, repeats: int = 3
             ) -> dict[str, Any]:
    """Time reading a binary PCD file and decoding one PointCloud2 message of ``n_points`` drawn
    with ``rng``, each read ``repeats`` times: ``pcd_read_s`` / ``pcd_read_median_s`` (best and
    median), ``pointcloud2_read_s`` / ``pointcloud2_read_median_s`` (CDR to PointCloud),
    ``bag_read_s`` (a one-message MCAP bag; these three ``None`` without the ``ros`` extra),
    ``goal_s`` and ``n_points``."""
    from deformap.cloud.io import read_cloud, write_pcd

    n = check_int("n_points", n_points, minimum=1)
    reps = check_int("repeats", repeats, minimum=1)
    if not isinstance(rng, np.random.Generator):
        raise InvalidArgumentError(
            f"`rng` must be a numpy.random.Generator; got {type(rng).__name__}")
    cloud = _scene(n, rng)
    result: dict[str, Any] = {"n_points": n, "goal_s": IO_GOAL_S}
    with tempfile.TemporaryDirectory(prefix="deformap-bench-io-") as tmp:
        pcd = Path(tmp) / "cloud.pcd"
        write_pcd(pcd, cloud, encoding="binary", dtype="float32")
        result["pcd_read_s"], result["pcd_read_median_s"] = _best_of(reps, lambda: read_cloud(pcd))
        result.update(_bench_pointcloud2(cloud, Path(tmp), reps))
    return result


def _bench_pointcloud2(cloud: PointCloud, tmp: Path, repeats: int) -> dict[str, Any]:
    try:
        from deformap.cloud.io import (
            array_to_pointcloud2,
            pointcloud2_to_array,
            read_bag_clouds,
            typestore,
            write_bag,
        )

        store = typestore()
    except ImportError:  # MissingDependencyError is an ImportError too
        return {"pointcloud2_read_s": None, "pointcloud2_read_median_s": None, "bag_read_s": None}
    msgtype = "sensor_msgs/msg/PointCloud2"
    msg = array_to_pointcloud2(cloud.points, colors=cloud.colors, frame_id="camera")
    raw = store.serialize_cdr(msg, msgtype)

    def decode() -> PointCloud:
        return PointCloud(pointcloud2_to_array(store.deserialize_cdr(raw, msgtype)))

    best, median = _best_of(repeats, decode)
    bag = tmp / "bag"
    write_bag(bag, clouds={"/camera/points": [(0, cloud.transformed(np.eye(4), "camera"))]})
    bag_best, _ = _best_of(repeats, lambda: read_bag_clouds(bag, "/camera/points"))
    return {"pointcloud2_read_s": best, "pointcloud2_read_median_s": median, "bag_read_s": bag_best}
