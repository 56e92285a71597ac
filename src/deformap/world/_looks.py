"""The light that reaches the colour sensor from each surface the camera's rays hit.

Every triangle of the scene has an owner: a block (its index), the table, or a part of the probe.
The albedo at a hit is the owner's :class:`~deformap.world._appearance.Appearance` at the hit's
surface coordinates, or the probe part's plain colour, shaded by
:func:`~deformap.world._appearance.lambert` with the face's normal turned toward the camera (no
shadows, no inter-reflections).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap.world._appearance import (
    DEFAULT_APPEARANCE,
    DEFAULT_TABLE_APPEARANCE,
    lambert,
    srgb_to_linear,
)
from deformap.world._config import WorldConfig
from deformap.world._scenario import Scenario

__all__ = ["HAND", "STICK", "TABLE", "TIP", "SceneLooks"]

#: Owners of triangles that are no block (blocks own their index, 0 and up).
TABLE, TIP, STICK, HAND = -1, -2, -3, -4


def surface_uv(hit: NDArray[np.float64], normal: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(n, 2)`` texture coordinates in metres of hits ``(n, 3)`` on faces of unit ``normal``."""
    uv = hit[:, :2].copy()
    side = np.abs(normal[:, 2]) < 0.5
    if np.any(side):
        along = np.column_stack([-normal[side, 1], normal[side, 0]])
        along /= np.linalg.norm(along, axis=1, keepdims=True)
        uv[side, 0] = np.einsum("ij,ij->i", hit[side, :2], along)
        uv[side, 1] = hit[side, 2]
    return uv


class SceneLooks:
    """The looks of a scenario's blocks and table and of the probe, lit as ``config`` says."""

    def __init__(self, scenario: Scenario, config: WorldConfig) -> None:
        self.blocks = tuple(b.appearance or DEFAULT_APPEARANCE for b in scenario.blocks)
        self.table = scenario.table_appearance or DEFAULT_TABLE_APPEARANCE
        self.solid = {TIP: srgb_to_linear(np.array(config.tip_color)),
                      STICK: srgb_to_linear(np.array(config.stick_color)),
                      HAND: srgb_to_linear(np.array(config.hand_color))}
        light = np.asarray(config.light_direction, dtype=float)
        self.light = light / np.linalg.norm(light)
        self.ambient = config.ambient

    def radiance(self, owner: NDArray[np.int64], hit: NDArray[np.float64],
                 normal: NDArray[np.float64], eye: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n, 3)`` linear light from hits ``(n, 3)`` of ``owner`` on faces of unit ``normal``
        (either orientation), seen from ``eye``."""
        toward = np.where((np.einsum("ij,ij->i", normal, hit - eye) > 0)[:, None], -normal, normal)
        uv = surface_uv(hit, toward)
        albedo = np.zeros((len(owner), 3))
        looks = [(k, look) for k, look in enumerate(self.blocks)] + [(TABLE, self.table)]
        for k, look in looks:
            mine = owner == k
            if np.any(mine):
                albedo[mine] = look.albedo(hit[mine, :2], uv[mine])
        for k, colour in self.solid.items():
            albedo[owner == k] = colour
        return np.asarray(albedo * lambert(toward, self.light, self.ambient)[:, None])
