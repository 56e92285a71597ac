"""A 3D recording of a run for the rerun viewer (extra ``rerun``): ``run.rrd``.

Timeline ``poke``: step 0 holds the first observation and the surface GP's heightmap; step k holds
the k-th press (cloud with the robot removed, tactile points, reconstructed dent), the β-field as a
coloured surface and its variance, and the scalars (β, max variance) as they evolve.
Open it with ``rerun run.rrd``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._files import atomic_path
from deformap.errors import missing_extra

__all__ = ["heightmap_mesh", "record_run"]


def heightmap_mesh(
    xs: NDArray[np.float64], ys: NDArray[np.float64], z: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Vertices ``(ny*nx, 3)`` and triangles ``(2*(ny-1)*(nx-1), 3)`` of a heightmap grid."""
    gx, gy = np.meshgrid(xs, ys)
    vertices = np.column_stack([gx.ravel(), gy.ravel(), np.asarray(z).ravel()])
    nx, ny = xs.size, ys.size
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return vertices, triangles


def _colors(values: NDArray[np.float64], cmap: str, lo: float, hi: float) -> NDArray[np.uint8]:
    from matplotlib import colormaps

    scaled = np.clip((np.asarray(values, float) - lo) / max(hi - lo, 1e-12), 0.0, 1.0)
    return (colormaps[cmap](np.nan_to_num(scaled))[..., :3] * 255).astype(np.uint8)


def record_run(path: str | Path, result: Any, *, initial_points: NDArray[np.float64]) -> Path:
    """Write ``run.rrd`` for an :class:`~deformap.explore.ExplorationResult`.

    Parameters
    ----------
    path : str or Path
        The ``.rrd`` file to write, atomically (under a temporary name, renamed once complete).
    result : ExplorationResult
        A finished exploration (its surface model, every poke and the β-field after each).
    initial_points : (n, 3) float, metres
        The first observation, as the camera saw it.
    """
    try:
        import rerun as rr
    except ImportError:
        raise missing_extra("rerun-sdk", "rerun", "writing 3D recordings") from None
    out = Path(path)
    with atomic_path(out) as tmp:
        rec = rr.RecordingStream("deformap")
        rec.save(tmp)
        _log_run(rec, result, np.asarray(initial_points))
        rec.flush()
        rec.disconnect()  # closes the file
    return out


def _log_run(rec: Any, result: Any, pts: NDArray[np.float64]) -> None:
    import rerun as rr

    rec.set_time("poke", sequence=0)
    rec.log(
        "world/observation",
        rr.Points3D(pts, radii=0.0015, colors=_colors(pts[:, 2], "viridis", 0.0, 0.08)),
    )
    surface_mesh = None
    if result.surface is not None:
        surface_mesh = heightmap_mesh(result.xs, result.ys, result.surface.height)
        vertices, triangles = surface_mesh
        rec.log(
            "world/surface",
            rr.Mesh3D(
                vertex_positions=vertices,
                triangle_indices=triangles,
                vertex_colors=_colors(vertices[:, 2], "viridis", 0, 0.08),
            ),
        )
    for k, poke in enumerate(result.pokes, start=1):
        rec.set_time("poke", sequence=k)
        dent = poke.dent
        if dent is not None:
            rec.log(
                "world/press/cloud",
                rr.Points3D(dent.roi_points, radii=0.001, colors=[200, 200, 200]),
            )
            rec.log(
                "world/press/tactile", rr.Points3D(dent.tactile, radii=0.002, colors=[230, 40, 40])
            )
            v, t = heightmap_mesh(dent.roi_xs, dent.roi_ys, dent.deformed_z)
            rec.log(
                "world/press/dent",
                rr.Mesh3D(vertex_positions=v, triangle_indices=t, vertex_colors=[60, 120, 230]),
            )
        field = result.field_after(k)
        mean, var = field.mean, field.variance
        if surface_mesh is not None:
            v, t = surface_mesh
            rec.log(
                "world/beta_field",
                rr.Mesh3D(
                    vertex_positions=v,
                    triangle_indices=t,
                    vertex_colors=_colors(mean.ravel(), "magma", 0, 1),
                ),
            )
        rec.log("maps/beta", rr.Image(_colors(mean[::-1], "magma", 0.0, 1.0)))
        rec.log("maps/variance", rr.Image(_colors(var[::-1], "Blues", 0.0, float(var.max()))))
        rec.log("metrics/beta", rr.Scalars(poke.record.beta))
        rec.log("metrics/max_variance", rr.Scalars(float(var.max())))
        _log_modulus(rec, result, k)


def _log_modulus(rec: Any, result: Any, k: int) -> None:
    """The modulus field after ``k`` pokes: ``maps/modulus_kpa`` (log₁₀ E in kPa coloured over
    0.1 kPa – 10 MPa: soft foams to stiff rubbers), ``metrics/modulus_kpa`` (the poke's E, or
    its detection bound when rigid) and ``metrics/modulus_max_variance`` (of ln E); nothing while
    no poke has a modulus."""
    import rerun as rr

    field = result.modulus_field_after(k)
    if not len(field.pokes):
        return
    log_kpa = np.log10(field.median_pa / 1e3)
    rec.log("maps/modulus_kpa", rr.Image(_colors(log_kpa[::-1], "viridis", -1.0, 4.0)))
    reading = field.readings[-1]
    if reading.log_modulus is not None:
        rec.log("metrics/modulus_kpa", rr.Scalars(float(np.exp(reading.log_modulus) / 1e3)))
    rec.log("metrics/modulus_max_variance", rr.Scalars(float(field.variance.max())))
