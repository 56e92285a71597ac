"""A 3D recording of a run for the rerun viewer (extra ``rerun``): ``run.rrd``.

Timelines ``poke`` and ``time`` (seconds since the run began: each poke's compute and the
environment's time, summed from its timings), in a Z-up world frame: step 0 holds the first
observation, the surface GP's heightmap and the ground truth; step k the k-th press (cloud with the
robot removed, tactile points, dent, the robot's hull), the β-field as a coloured surface, and the
maps and scalars as they evolve; the last step the regions. The maps are values, not colours:
``maps/beta``, ``maps/variance`` (of the map field), ``maps/modulus_kpa`` (median E) and
``maps/truth_hardness_n`` (NaN where rigid or bare table) are ``(ny, nx)`` :class:`rerun.Tensor`
grids, ``maps/regions`` a :class:`rerun.SegmentationImage` whose annotation context names each
region with its mean β; every grid is stored top row first (the largest y), so that it shows with y
up as in ``map.png``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import colormaps
from numpy.typing import NDArray
from scipy.spatial import ConvexHull

from deformap._files import atomic_path
from deformap.errors import missing_extra

__all__ = ["hull_mesh", "record_run"]


def _heightmap_mesh(xs: NDArray, ys: NDArray, z: NDArray) -> tuple[NDArray, NDArray[np.int64]]:
    """Vertices ``(ny*nx, 3)`` and triangles ``(2*(ny-1)*(nx-1), 3)`` of a heightmap grid."""
    gx, gy = np.meshgrid(xs, ys)
    vertices = np.column_stack([gx.ravel(), gy.ravel(), np.asarray(z).ravel()])
    nx, ny = xs.size, ys.size
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return vertices, triangles


def _colors(values: NDArray, cmap: str, lo: float, hi: float) -> NDArray[np.uint8]:
    scaled = np.clip((np.asarray(values, float) - lo) / max(hi - lo, 1e-12), 0.0, 1.0)
    return (colormaps[cmap](np.nan_to_num(scaled))[..., :3] * 255).astype(np.uint8)


def record_run(path: str | Path, result: Any, *, initial_points: NDArray,
               truth_hardness: NDArray | None = None,
               robot_points: Sequence[NDArray | None] | None = None) -> Path:
    """Write the ``.rrd`` file ``path`` atomically for an ``ExplorationResult``; returns ``path``.

    Parameters
    ----------
    initial_points : (n, 3) float, metres
        The first observation, as the camera saw it.
    truth_hardness : (ny, nx) float, optional
        Ground-truth hardness in newtons on the map's grid (``inf`` rigid, ``nan`` bare table).
    robot_points : sequence of (m, 3) float or None, optional
        Per poke, points whose convex hull covers the robot at the press (``None``: no hull).
    """
    try:
        import rerun as rr
    except ImportError:
        raise missing_extra("rerun-sdk", "rerun", "writing 3D recordings") from None
    out = Path(path)
    with atomic_path(out) as tmp:
        rec = rr.RecordingStream("deformap")
        rec.save(tmp, default_blueprint=_blueprint())
        times = _poke_times(result)
        _log_run(rec, result, np.asarray(initial_points), times)
        if truth_hardness is not None:
            _at(rec, 0, times)
            truth = np.where(np.isinf(truth_hardness), np.nan, truth_hardness)
            rec.log("maps/truth_hardness_n", rr.Tensor(truth[::-1], dim_names=("y", "x")))
        for k, points in enumerate(robot_points or (), start=1):
            if points is not None:
                _at(rec, k, times)
                vertices, triangles = hull_mesh(np.asarray(points, dtype=float))
                rec.log("world/press/robot_hull", rr.Mesh3D(
                    vertex_positions=vertices, triangle_indices=triangles,
                    albedo_factor=[120, 120, 120, 110]))  # fmt: skip
        _log_regions(rec, result, times)
        rec.flush()
        rec.disconnect()  # closes the file
    return out


def _poke_times(result: Any) -> list[float]:
    """Seconds since the run began at each step: 0 for the observation, then after each poke."""
    times = [0.0]
    for poke in getattr(result, "pokes", ()):
        t = getattr(poke.record, "timings", None)
        times.append(times[-1] + (0.0 if t is None else t.compute_s + (t.environment_s or 0.0)))
    return times


def _at(rec: Any, k: int, times: Sequence[float]) -> None:
    """Log what follows at step ``k`` of both timelines."""
    rec.set_time("poke", sequence=k)
    rec.set_time("time", duration=times[min(k, len(times) - 1)])


def hull_mesh(points: NDArray) -> tuple[NDArray, NDArray[np.int64]]:
    """Vertices ``(v, 3)`` and triangles ``(t, 3)`` of the convex hull of ``points (m, 3)``."""
    hull = ConvexHull(points)
    index = np.full(len(points), -1, dtype=np.int64)
    index[hull.vertices] = np.arange(hull.vertices.size)
    return points[hull.vertices], index[hull.simplices]


def _blueprint() -> Any:
    """The layout the viewer opens on: the 3D scene; beside it the maps above the scalars."""
    import rerun.blueprint as rrb

    maps = [rrb.TensorView(origin=f"maps/{name}", name=title) for name, title in (
        ("beta", "β-field"), ("variance", "map field variance"),
        ("modulus_kpa", "E [kPa]"), ("truth_hardness_n", "ground truth H [N]"))]  # fmt: skip
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="world", name="surface, presses and β-field"),
            rrb.Vertical(
                rrb.Grid(*maps, rrb.Spatial2DView(origin="maps/regions", name="regions")),
                rrb.TimeSeriesView(origin="metrics", name="β, E and max variance per poke"),
                row_shares=[2, 1],
            ),
            column_shares=[3, 2],
        ),
    )  # the side and time panels stay open: the time panel steps through the pokes


def _log_run(rec: Any, result: Any, pts: NDArray, times: Sequence[float]) -> None:
    import rerun as rr

    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    _at(rec, 0, times)
    rec.log("world/observation",
            rr.Points3D(pts, radii=0.0015, colors=_colors(pts[:, 2], "viridis", 0.0, 0.08)))
    surface_mesh = None
    if result.surface is not None:
        surface_mesh = _heightmap_mesh(result.xs, result.ys, result.surface.height)
        vertices, triangles = surface_mesh
        rec.log("world/surface", rr.Mesh3D(
            vertex_positions=vertices, triangle_indices=triangles,
            vertex_colors=_colors(vertices[:, 2], "viridis", 0, 0.08)))
    for k, poke in enumerate(result.pokes, start=1):
        _at(rec, k, times)
        dent = poke.dent
        if dent is not None:
            rec.log("world/press/cloud",
                    rr.Points3D(dent.roi_points, radii=0.001, colors=[200, 200, 200]))
            rec.log("world/press/tactile",
                    rr.Points3D(dent.tactile, radii=0.002, colors=[230, 40, 40]))
            v, t = _heightmap_mesh(dent.roi_xs, dent.roi_ys, dent.deformed_z)
            rec.log("world/press/dent",
                    rr.Mesh3D(vertex_positions=v, triangle_indices=t, vertex_colors=[60, 120, 230]))
        field = result.beta_field_after(k)
        mean = field.mean
        if surface_mesh is not None:
            v, t = surface_mesh
            rec.log("world/beta_field", rr.Mesh3D(
                vertex_positions=v, triangle_indices=t,
                vertex_colors=_colors(mean.ravel(), "magma", 0, 1)))
        rec.log("maps/beta", rr.Tensor(mean[::-1], dim_names=("y", "x"), value_range=(0.0, 1.0)))
        rec.log("metrics/beta", rr.Scalars(poke.record.beta))
        var = _map_variance(result, k, field.variance)
        rec.log("maps/variance", rr.Tensor(var[::-1], dim_names=("y", "x")))
        rec.log("metrics/max_variance", rr.Scalars(float(var.max())))
        _log_modulus(rec, result, k)


def _map_variance(result: Any, k: int, beta_variance: NDArray) -> NDArray:
    """The variance of the map field after ``k`` pokes (the modulus field's once it holds one)."""
    if getattr(getattr(result, "config", None), "field", "beta") == "modulus":
        field = result.modulus_field_after(k)
        if len(field.pokes):
            return np.asarray(field.variance)
    return np.asarray(beta_variance)


def _log_regions(rec: Any, result: Any, times: Sequence[float]) -> None:
    """The final regions as a segmentation image, each named R1, R2, … with its mean β."""
    import rerun as rr

    regions = getattr(result, "regions", None)
    if regions is None:
        return
    _at(rec, len(result.pokes), times)
    labels = np.asarray(regions.labels)
    mean = np.asarray(result.beta_field.mean)
    infos = []
    for k in np.unique(labels[labels >= 0]):
        colour = (np.array(colormaps["tab10"](int(k) % 10)[:3]) * 255).astype(np.uint8)
        infos.append(rr.AnnotationInfo(id=int(k) + 1, color=colour,
                                       label=f"R{k + 1}: β = {mean[labels == k].mean():.2f}"))
    rec.log("maps/regions", rr.AnnotationContext(infos), static=True)
    # ids from 1: 0 is the "no class" of a segmentation image (cells without a region, -1)
    rec.log("maps/regions", rr.SegmentationImage((labels + 1)[::-1].astype(np.uint16)))


def _log_modulus(rec: Any, result: Any, k: int) -> None:
    """The modulus field after ``k`` pokes (median E in kPa), the poke's E and the field's largest
    variance of ln E; nothing while no poke has a modulus."""
    import rerun as rr

    field = result.modulus_field_after(k)
    if not len(field.pokes):
        return
    kpa = np.asarray(field.median_pa) / 1e3
    rec.log("maps/modulus_kpa", rr.Tensor(kpa[::-1], dim_names=("y", "x")))
    reading = field.readings[-1]
    if reading.log_modulus is not None:
        rec.log("metrics/modulus_kpa", rr.Scalars(float(np.exp(reading.log_modulus) / 1e3)))
    rec.log("metrics/modulus_max_variance", rr.Scalars(float(field.variance.max())))
