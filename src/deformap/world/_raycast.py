"""Ray casting: Embree through trimesh when ``embreex`` is installed, else a pure-numpy caster for
rays of one origin, which bins the rays on a grid of the image plane, pairs each projected
triangle with the rays of the cells its box covers, and runs the Möller–Trumbore test on them.

References
----------
Möller, T., Trumbore, B. (1997). Fast, minimum storage ray-triangle intersection. JGT 2(1).
"""

from __future__ import annotations

import numpy as np
import trimesh
from numpy.typing import NDArray

__all__ = ["cast_rays", "frame_along"]

Hits = tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]


def cast_rays(mesh: trimesh.Trimesh, origins: NDArray[np.float64], directions: NDArray[np.float64],
              *, use_embree: bool = True) -> Hits:
    """First hits of ``(n, 3)`` rays (origins in metres, unit directions; one shared origin
    without Embree) on a mesh: ray index ``(k,)`` sorted, triangle index ``(k,)``, location
    ``(k, 3)``."""
    if use_embree:
        try:
            from trimesh.ray.ray_pyembree import RayMeshIntersector
        except ImportError:
            pass
        else:
            tri, ray, loc = RayMeshIntersector(mesh).intersects_id(
                origins, directions, multiple_hits=False, return_locations=True)
            order = np.argsort(ray, kind="stable")
            return np.asarray(ray[order]), np.asarray(tri[order]), np.asarray(loc[order])
    if not np.all(origins == origins[0]):
        raise NotImplementedError("the numpy ray caster needs rays with one shared origin")
    return _pinhole_hits(np.asarray(mesh.triangles), origins[0], directions)


def frame_along(axis: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(3, 3)`` rows of a right-handed orthonormal frame whose third axis is along ``axis``."""
    z = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def _pinhole_hits(triangles: NDArray[np.float64], origin: NDArray[np.float64],
                  directions: NDArray[np.float64]) -> Hits:
    basis = frame_along(directions.mean(axis=0))
    d = directions @ basis.T
    uv = d[:, :2] / d[:, 2:3]
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    n_cells = max(1, int(np.sqrt(len(uv) / 4)))
    size = (hi - lo) / n_cells + 1e-12
    cell_ij = np.clip(((uv - lo) / size).astype(np.int64), 0, n_cells - 1)
    cell = cell_ij[:, 0] * n_cells + cell_ij[:, 1]
    ray_order = np.argsort(cell, kind="stable")
    starts = np.searchsorted(cell[ray_order], np.arange(n_cells * n_cells + 1))

    v = (triangles - origin) @ basis.T  # (T, 3, 3) in the camera frame
    front = np.all(v[:, :, 2] > 1e-9, axis=1)
    tri_ids = np.flatnonzero(front)
    puv = v[front, :, :2] / v[front, :, 2:3]
    c0 = np.floor((puv.min(axis=1) - lo) / size).astype(np.int64)
    c1 = np.floor((puv.max(axis=1) - lo) / size).astype(np.int64)
    keep = np.all(c1 >= 0, axis=1) & np.all(c0 < n_cells, axis=1)
    tri_ids = tri_ids[keep]
    c0, c1 = np.clip(c0[keep], 0, n_cells - 1), np.clip(c1[keep], 0, n_cells - 1)
    # expand triangle -> covered cells -> rays in those cells
    ni, nj = c1[:, 0] - c0[:, 0] + 1, c1[:, 1] - c0[:, 1] + 1
    per_tri = ni * nj
    t_rep = np.repeat(np.arange(len(tri_ids)), per_tri)
    local = np.arange(per_tri.sum()) - np.repeat(np.cumsum(per_tri) - per_tri, per_tri)
    ci = c0[t_rep, 0] + local // nj[t_rep]
    cj = c0[t_rep, 1] + local % nj[t_rep]
    cells = ci * n_cells + cj
    counts = starts[cells + 1] - starts[cells]
    pair_tri = np.repeat(t_rep, counts)
    offs = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    pair_ray = ray_order[np.repeat(starts[cells], counts) + offs]
    return _moller_trumbore(triangles, tri_ids[pair_tri], pair_ray, origin, directions)


def _moller_trumbore(triangles: NDArray[np.float64], tri: NDArray[np.int64], ray: NDArray[np.int64],
                     origin: NDArray[np.float64], directions: NDArray[np.float64]) -> Hits:
    a, b, c = triangles[tri, 0], triangles[tri, 1], triangles[tri, 2]
    d = directions[ray]
    e1, e2 = b - a, c - a
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-15
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - a
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    w = np.einsum("ij,ij->i", d, q) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 0)
    ray, tri, t = ray[hit], tri[hit], t[hit]
    order = np.lexsort((t, ray))
    ray, tri, t = ray[order], tri[order], t[order]
    first = np.ones(len(ray), dtype=bool)
    first[1:] = ray[1:] != ray[:-1]
    ray, tri, t = ray[first], tri[first], t[first]
    return ray, tri, origin + directions[ray] * t[:, None]
