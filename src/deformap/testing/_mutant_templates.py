"""The templates the reader mutants of :mod:`deformap.testing.mutants` are made from: a small
cloud in every file format, a three-poke session (folder, MCAP, sqlite3), a run configuration,
a scenario, and a raw robot bag (MCAP and sqlite3) with its settings YAML; no simulator needed.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["RAW_CHUNK_BYTES", "RAW_RATES_HZ", "make_templates"]

#: The raw template's rates [Hz] (camera, /tf, force sensor) and chunk size: a bag of a few
#: compressed chunks that reads in a few hundredths of a second.
RAW_RATES_HZ = (15.0, 25.0, 100.0)
RAW_CHUNK_BYTES = 16 * 1024


def _cloud(n: int = 120) -> Any:
    from deformap.cloud import PointCloud

    rng = np.random.default_rng(7)
    # On a 1 mm lattice, so that binary_compressed really compresses (LZF needs repeats).
    pts = np.round(rng.uniform([0.0, 0.0, 0.04], [0.3, 0.2, 0.06], (n, 3)), 3)
    return PointCloud(pts, rng.uniform(0, 1, (n, 3)).round(2))


def _session_parts() -> dict[str, Any]:
    """A flat foam top at 5 cm with a dent under each of three pokes (no simulator needed)."""
    from deformap.cloud import PointCloud
    from deformap.environment import ForceTravel, PressObservation, TactileContact, Workspace

    rng = np.random.default_rng(11)

    def surface(dents: list[tuple[np.ndarray, float]]) -> np.ndarray:
        xy = rng.uniform([0.0, 0.0], [0.6, 0.4], (300, 2))
        z = 0.05 + rng.normal(0, 5e-4, 300)
        for center, depth in dents:
            z -= depth * np.exp(-np.sum((xy - center) ** 2, axis=1) / 0.015**2)
        return np.column_stack([xy, z])

    presses = []
    for i in range(3):
        target, depth = np.array([0.1 + 0.2 * i, 0.2]), 0.004 + 0.002 * i
        tip = np.array([target[0], target[1], 0.05 - depth + 0.01])
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * 0.006
        robot = np.vstack([np.column_stack([tip[:2] + corners, np.full(4, z)])
                           for z in (tip[2], tip[2] + 0.25)])  # fmt: skip
        record = ForceTravel(travel_m=np.linspace(0.0, depth, 5), force_n=np.linspace(0.05, 1, 5))
        presses.append(PressObservation(
            cloud=PointCloud(np.vstack([surface([(target, depth)]), robot])),
            contact=TactileContact(tip_center=tip, force=np.array([0.0, 0.0, -1.0]),
                                   tip_radius_m=0.01),
            robot_points=robot, target_xy=target, force_n=1.0, force_travel=record))  # fmt: skip
    from deformap.replay import GroundTruth

    xs, ys = np.linspace(0.01, 0.59, 30), np.linspace(0.01, 0.39, 20)
    labels = np.repeat((xs > 0.3)[None, :], 20, axis=0).astype(np.int64)
    truth = GroundTruth(xs, ys, labels, np.where(labels == 1, np.inf, 80.0))
    return {"workspace": Workspace(), "observation": PointCloud(surface([])), "presses": presses,
            "ground_truth": truth}


def make_templates(root: Path) -> dict[str, Path]:
    """Write every template under ``root``: reader kind → file or session folder."""
    from deformap.cloud.io import write_npz, write_pcd, write_ply
    from deformap.replay import write_session

    cloud = _cloud()
    root.mkdir(parents=True, exist_ok=True)
    out: dict[str, Path] = {}
    for enc in ("ascii", "binary", "binary_compressed"):
        out[f"pcd-{enc}"] = root / f"t-{enc}.pcd"
        write_pcd(out[f"pcd-{enc}"], cloud, encoding=enc)
    assert b"DATA binary_compressed" in out["pcd-binary_compressed"].read_bytes()
    for fmt in ("ascii", "binary_little_endian"):
        key = "ply-" + fmt.split("_")[0]
        out[key] = root / f"t-{fmt}.ply"
        write_ply(out[key], cloud, format=fmt, extra_fields={"i": np.arange(len(cloud), dtype=np.int32)})
    out["npz"] = root / "t.npz"
    write_npz(out["npz"], cloud)
    out["session-folder"] = write_session(root / "session", **_session_parts()).parent
    from deformap.run import RunConfig, config_yaml
    from deformap.world import load_scenario, save_scenario

    out["config"] = root / "config.yaml"
    out["config"].write_text(config_yaml(RunConfig()))
    out["scenario"] = root / "scenario.yaml"
    save_scenario(load_scenario("heterogeneous-60-110-rigid"), out["scenario"])
    try:
        import rosbags  # noqa: F401
    except ImportError:
        return out
    for storage in ("mcap", "sqlite3"):
        out[f"session-{storage}"] = write_session(root / f"session-{storage}", format=storage,
                                                  **_session_parts()).parent  # fmt: skip
    try:
        import mcap_ros2.writer  # noqa: F401
    except ImportError:
        return out
    out["raw-mcap"], out["raw-db3"] = _raw_templates(root, out["session-folder"])
    return out


def _raw_templates(root: Path, session_folder: Path) -> tuple[Path, Path]:
    """The session's presses as a robot records them, and the same messages as a lone sqlite3
    ``.db3`` written by rosbags (not deformap), each with the settings YAML beside it."""
    import yaml

    from deformap.replay import load_session
    from deformap.testing.robotbag import copy_to_db3, raw_settings, write_raw_bag

    (root / "raw").mkdir()
    session = load_session(session_folder)
    camera_hz, tf_hz, wrench_hz = RAW_RATES_HZ
    bag = root / "raw" / "lab.mcap"
    write_raw_bag(bag, session, camera_hz=camera_hz, tf_hz=tf_hz, wrench_hz=wrench_hz,
                  chunk_size=RAW_CHUNK_BYTES)  # fmt: skip
    settings = yaml.safe_dump(raw_settings(session, force_n=1.0), sort_keys=False)
    (root / "raw" / "lab.deformap.yaml").write_text(settings)
    (root / "raw-db3").mkdir()
    shutil.copy(root / "raw" / "lab.deformap.yaml", root / "raw-db3")
    return bag, copy_to_db3(bag, root / "raw-db3" / "lab.db3")
