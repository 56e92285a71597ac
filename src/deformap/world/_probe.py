"""The probe: a spherical tip (Optoforce-like) on a stick along the press normal, held by a
box-shaped hand on top of it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import NDArray

from deformap.world._raycast import frame_along

__all__ = ["ProbeGeometry"]


@dataclass(frozen=True, kw_only=True)
class ProbeGeometry:
    """Dimensions of the probe, metres."""

    tip_radius_m: float = 0.01
    stick_length_m: float = 0.10
    stick_radius_m: float = 0.006
    hand_size_m: tuple[float, float, float] = (0.08, 0.06, 0.10)

    def _parts(self) -> list[trimesh.Trimesh]:
        """Tip, stick and hand in the probe's frame (tip centre at the origin, stick along z)."""
        tip = trimesh.creation.icosphere(subdivisions=2, radius=self.tip_radius_m)
        stick = trimesh.creation.cylinder(radius=self.stick_radius_m, height=self.stick_length_m,
                                          sections=16)
        stick.apply_translation([0.0, 0.0, self.stick_length_m / 2])
        hand = trimesh.creation.box(extents=self.hand_size_m)
        hand.apply_translation([0.0, 0.0, self.stick_length_m + self.hand_size_m[2] / 2])
        return [tip, stick, hand]

    def part_faces(self) -> tuple[int, int, int]:
        """Triangles of the tip, the stick and the hand, in the order :meth:`mesh` stacks them."""
        tip, stick, hand = (len(p.faces) for p in self._parts())
        return tip, stick, hand

    def mesh(self, tip_center: NDArray[np.float64], normal: NDArray[np.float64]) -> trimesh.Trimesh:
        """Triangle mesh of tip, stick and hand (for the camera)."""
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = frame_along(normal).T, tip_center
        parts: trimesh.Trimesh = trimesh.util.concatenate(self._parts())  # type: ignore[assignment]
        parts.apply_transform(pose)
        return parts

    def robot_points(self, tip_center: NDArray[np.float64], normal: NDArray[np.float64]
                     ) -> NDArray[np.float64]:
        """``(m, 3)`` points whose convex hull covers the tip's upper half (the lower is in the
        dent), the stick and the hand."""
        rot = frame_along(normal).T
        r = self.tip_radius_m
        az = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
        circles = [np.column_stack([rad * np.cos(az), rad * np.sin(az), np.full_like(az, z)])
                   for rad, z in ((r, 0.0), (r * np.cos(np.pi / 6), r * np.sin(np.pi / 6)),
                                  (r * np.cos(np.pi / 3), r * np.sin(np.pi / 3)))]
        top = np.array([[0.0, 0.0, r]])
        hx, hy, hz = (s / 2 for s in self.hand_size_m)
        corners = np.array([[sx * hx, sy * hy, self.stick_length_m + h]
                            for sx in (-1, 1) for sy in (-1, 1) for h in (0.0, 2 * hz)])
        local = np.concatenate([*circles, top, corners])
        return np.asarray(local @ rot.T + tip_center)
