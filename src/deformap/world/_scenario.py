"""Scenarios: which foam blocks lie where on the table.

A scenario is a list of blocks on the rigid table. Each block is a simple polygon in the table plane
(convex or not, with holes where another block is inserted), extruded to its own thickness, made of
foam of a given hardness (or Young's modulus) or ``rigid`` (a board). What no block covers is the
bare table at ``z = 0``. Blocks may touch but never overlap; each is bonded to the table, not glued
to its neighbours, as in the paper's experiments.

The built-in scenarios (:func:`builtin_scenarios`) are the paper's Table I, over the 60 × 40 cm
workspace with 5 cm thick blocks, each layout our choice and described in its ``description``.
Ground-truth labels are block indices in the order of ``Scenario.blocks``; ``-1`` marks the bare
table.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import SettingError, check_array, check_settings, setting
from deformap.environment import Workspace
from deformap.errors import InvalidArgumentError
from deformap.mechanics import hardness_to_youngs_modulus, youngs_modulus_to_hardness
from deformap.world._appearance import Appearance, parse_color
from deformap.world._materials import Orthotropic, Plastic, Viscoelastic
from deformap.world._polygon import (
    is_simple,
    overlap_area,
    points_in_polygon,
    polygon_area,
    rectangle,
)

__all__ = ["BARE_TABLE", "MAX_EXTENT_M", "Block", "Scenario", "builtin_scenarios"]

BARE_TABLE = -1
"""Ground-truth label of table area that no block covers."""

_OVERLAP_TOL_M2 = 1e-8  # 1 mm² of shared area is a real overlap, less is rounding of touching edges
#: Largest side of a workspace or footprint and largest block thickness, in metres: far beyond
#: what an arm over a table reaches, while every map and mesh grows with the area.
MAX_EXTENT_M = 10.0


@dataclass(frozen=True, kw_only=True)
class Block:
    """One block on the table: a prism of foam (or of a rigid material) over a simple polygon.

    Parameters
    ----------
    polygon : (k, 2) float, metres
        Footprint, a simple polygon of ``k >= 3`` vertices, at most :data:`MAX_EXTENT_M` across.
    holes : tuple of (m, 2) float, metres
        Simple polygons inside the footprint, apart from each other, that the block leaves empty.
    hardness_n, youngs_modulus_pa, rigid
        Exactly one is given (ISO 2439 hardness in newtons, Young's modulus in pascals, or a
        board that does not deform); the modulus and hardness derive from each other.
    color : str
        Matplotlib colour for figures.
    appearance : Appearance or None
        How the camera sees the block; None: neutral grey and plain.
    viscoelastic : Viscoelastic or None
        The foam relaxes (a Prony series; the modulus is then the instantaneous one); None:
        elastic.
    anisotropy : Orthotropic or None
        The foam is stiffer along an in-plane axis (the modulus is then the soft one's); None:
        isotropic.
    plastic : Plastic or None
        The material yields and keeps a dent (neither viscoelastic nor anisotropic then); None:
        elastic.
    """

    name: str
    polygon: NDArray[np.float64]
    # a sequence of arrays of their own shapes, checked by _ring below (stored as a tuple)
    holes: Sequence[NDArray[np.float64]] = ()
    # at least the FEM's smallest element (1 mm): a thinner block is no layer the world can mesh
    thickness_m: float = setting(0.05, ge=0.001, le=MAX_EXTENT_M)
    # flexible foams run from about 20 N to 1 kN (ISO 2439); the bounds refuse only what is no
    # material to press: 0.1 N is 7.7 Pa, and 10 GPa is wood or stone, a block to declare rigid
    hardness_n: float | None = setting(None, ge=0.1, le=1.3e8)
    youngs_modulus_pa: float | None = setting(None, ge=10.0, le=1e10)
    rigid: bool = False
    color: str = "#c8a165"
    appearance: Appearance | None = None
    viscoelastic: Viscoelastic | None = None
    anisotropy: Orthotropic | None = None
    plastic: Plastic | None = None

    def __post_init__(self) -> None:
        try:
            check_settings(self)
        except SettingError as exc:
            raise SettingError(exc.field, f"{exc.detail} (block {self.name!r})") from None
        if not self.name:
            raise InvalidArgumentError(
                f"block `name` must be a non-empty string; got {self.name!r}")
        poly = _ring(f"block {self.name!r} polygon", self.polygon)
        if isinstance(self.holes, (str, bytes, np.ndarray)) or not isinstance(self.holes, Sequence):
            raise InvalidArgumentError(
                f"block {self.name!r} `holes` must be a sequence of polygons; got "
                f"{type(self.holes).__name__}")
        holes = tuple(_ring(f"block {self.name!r} holes[{i}]", h) for i, h in enumerate(self.holes))
        self._check_holes(poly, holes)
        extent = poly.max(axis=0) - poly.min(axis=0)
        if np.any(extent > MAX_EXTENT_M):
            raise SettingError(
                "polygon", f"must span at most {MAX_EXTENT_M:g} m on each axis; got "
                f"{extent[0]:g} × {extent[1]:g} m (block {self.name!r})")
        for ring in (poly, *holes):
            ring.setflags(write=False)
        object.__setattr__(self, "polygon", poly)
        object.__setattr__(self, "holes", holes)
        self._check_material()

    def _check_holes(self, poly: NDArray[np.float64], holes: tuple[NDArray[np.float64], ...]
                     ) -> None:
        for i, hole in enumerate(holes):
            inside = overlap_area(hole, poly)
            if abs(inside - polygon_area(hole)) > _OVERLAP_TOL_M2:
                raise InvalidArgumentError(
                    f"block {self.name!r} holes[{i}] must lie inside the polygon; got "
                    f"{(polygon_area(hole) - inside) * 1e4:.2f} cm² of it outside")
            for j, other in enumerate(holes[:i]):
                if overlap_area(hole, other) > _OVERLAP_TOL_M2:
                    raise InvalidArgumentError(
                        f"block {self.name!r} holes[{i}] must not overlap holes[{j}]")

    def _check_material(self) -> None:
        given = [self.hardness_n is not None, self.youngs_modulus_pa is not None, bool(self.rigid)]
        if sum(given) != 1:
            raise InvalidArgumentError(
                f"block {self.name!r} needs exactly one of `hardness_n`, `youngs_modulus_pa` or "
                f"`rigid=True`; got hardness_n={self.hardness_n!r}, "
                f"youngs_modulus_pa={self.youngs_modulus_pa!r}, rigid={self.rigid!r}")
        materials = [k for k in ("viscoelastic", "anisotropy", "plastic")
                     if getattr(self, k) is not None]
        if self.rigid and materials:
            raise InvalidArgumentError(
                f"block {self.name!r} is rigid: it can have no `{materials[0]}`; drop `rigid` or "
                "the material")
        if self.plastic is not None and len(materials) > 1:
            raise InvalidArgumentError(
                f"block {self.name!r}: a `plastic` block can be neither viscoelastic nor "
                f"anisotropic; got {materials}")
        if self.hardness_n is not None:
            object.__setattr__(self, "youngs_modulus_pa",
                               hardness_to_youngs_modulus(float(self.hardness_n)))
        elif self.youngs_modulus_pa is not None:
            object.__setattr__(self, "hardness_n",
                               youngs_modulus_to_hardness(float(self.youngs_modulus_pa)))

    @property
    def modulus_pa(self) -> float:
        """Young's modulus in Pa; ``inf`` for a rigid block."""
        return float("inf") if self.rigid else float(self.youngs_modulus_pa)  # type: ignore[arg-type]

    @property
    def hardness(self) -> float:
        """Hardness in N; ``inf`` for a rigid block."""
        return float("inf") if self.rigid else float(self.hardness_n)  # type: ignore[arg-type]

    @property
    def area_m2(self) -> float:
        """Area of the footprint less its holes, m²."""
        return polygon_area(self.polygon) - sum(polygon_area(h) for h in self.holes)

    def contains(self, xy: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Mask of the ``(n, 2)`` points inside the footprint and outside its holes."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        inside = points_in_polygon(pts, self.polygon)
        for hole in self.holes:
            inside &= ~points_in_polygon(pts, hole)
        return inside

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "polygon": self.polygon.tolist()}
        if self.holes:
            out["holes"] = [h.tolist() for h in self.holes]
        out.update({"rigid": True} if self.rigid else {"hardness_n": self.hardness})
        out.update(thickness_m=self.thickness_m, color=self.color)
        if self.appearance is not None:
            out["appearance"] = self.appearance.to_dict()
        if self.viscoelastic is not None:
            out["viscoelastic"] = self.viscoelastic.to_dict()
        if self.anisotropy is not None:
            out["anisotropy"] = self.anisotropy.to_dict()
        if self.plastic is not None:
            out["plastic"] = self.plastic.to_dict()
        return out


@dataclass(frozen=True, kw_only=True)
class Scenario:
    """A named layout of blocks over a workspace.

    ``blocks``: at least one, no two overlapping, each with some area inside ``workspace``;
    ``workspace``: the rectangle to map, at most :data:`MAX_EXTENT_M` on each side;
    ``table_appearance`` None: a darker warm grey.
    """

    name: str
    blocks: tuple[Block, ...]
    workspace: Workspace = field(default_factory=Workspace)
    description: str = ""
    table_appearance: Appearance | None = None

    def __post_init__(self) -> None:
        check_settings(self)
        blocks = self.blocks
        if not blocks:
            raise SettingError("blocks", f"must hold at least one Block (scenario {self.name!r})")
        size = self.workspace.size
        if max(size) > MAX_EXTENT_M:
            raise SettingError(
                "workspace", f"must span at most {MAX_EXTENT_M:g} m on each axis; got "
                f"{size[0]:g} × {size[1]:g} m (scenario {self.name!r})")
        (x0, y0), (x1, y1) = self.workspace.lower, self.workspace.upper
        rect = rectangle(x0, y0, x1, y1)
        for b in blocks:
            if overlap_area(b.polygon, rect, b.holes) <= _OVERLAP_TOL_M2:
                raise InvalidArgumentError(
                    f"scenario {self.name!r}: block {b.name!r} lies wholly outside the workspace "
                    f"[{x0:g}, {x1:g}] × [{y0:g}, {y1:g}] m; no poke could reach it: move the "
                    "block or widen `workspace`")
        names = [b.name for b in blocks]
        if len(set(names)) != len(names):
            raise InvalidArgumentError(f"scenario {self.name!r} has repeated block names: {names}")
        for i, a in enumerate(blocks):
            for b in blocks[i + 1:]:
                area = overlap_area(a.polygon, b.polygon, a.holes, b.holes)
                if area > _OVERLAP_TOL_M2:
                    raise InvalidArgumentError(
                        f"scenario {self.name!r}: blocks {a.name!r} and {b.name!r} overlap "
                        f"by {area * 1e4:.2f} cm²; blocks may touch but not overlap")

    @property
    def region_names(self) -> list[str]:
        return [b.name for b in self.blocks]

    def labels(self, xs: Any, ys: Any) -> NDArray[np.int64]:
        """``(ny, nx)`` block index at each grid point ``(xs[j], ys[i])``; ``-1`` on bare table."""
        x = check_array("xs", xs, (None,), what="x coordinates in metres", min_rows=1)
        y = check_array("ys", ys, (None,), what="y coordinates in metres", min_rows=1)
        gx, gy = np.meshgrid(x, y)
        pts = np.column_stack([gx.ravel(), gy.ravel()])
        out = np.full(len(pts), BARE_TABLE, dtype=np.int64)
        for k, block in enumerate(self.blocks):
            free = out == BARE_TABLE
            out[free] = np.where(block.contains(pts[free]), k, BARE_TABLE)
        return out.reshape(len(y), len(x))

    def per_block(self, xs: Any, ys: Any, values: Sequence[float],
                  table: float = np.inf) -> NDArray[np.float64]:
        """``(ny, nx)`` the value of the block at each grid point (``values[k]`` of block ``k``),
        ``table`` on the bare table."""
        if len(values) != len(self.blocks):
            raise InvalidArgumentError(f"`values` must have one value per block "
                                       f"({len(self.blocks)}); got {len(values)}")
        return np.asarray(np.array([*values, table], dtype=float)[self.labels(xs, ys)])

    def to_dict(self) -> dict[str, Any]:
        out = {"name": self.name, "description": self.description,
               "workspace": self.workspace.to_dict(),
               "blocks": [b.to_dict() for b in self.blocks]}
        if self.table_appearance is not None:
            out["table_appearance"] = self.table_appearance.to_dict()
        return out


def _ring(what: str, vertices: Any) -> NDArray[np.float64]:
    """A footprint's or hole's vertices, checked simple with a positive area, counter-clockwise."""
    poly = check_array(what, vertices, (None, 2), what="vertices (x, y) in metres", min_rows=3)
    area = polygon_area(poly)
    if area < 0:
        poly, area = poly[::-1].copy(), -area
    simple = is_simple(poly)
    if area <= _OVERLAP_TOL_M2 or not simple:
        raise InvalidArgumentError(
            f"{what} must be a simple polygon (no two edges crossing) with a positive area; "
            f"got area {area:.3g} m², simple={simple}")
    return poly


_FOAM_COLORS = {60: "#f4d35e", 110: "#ee964b", 150: "#c8553d"}
_RIGID_COLOR = "#6b4f3a"
# open-cell foam: a fine mottle of pores, finer in the denser (harder) foams; a wooden board: grain
_FOAM_PORES_M = {60: 0.005, 110: 0.004, 150: 0.003}


def _foam(poly: NDArray[np.float64], hardness: int) -> Block:
    look = Appearance(color=parse_color(_FOAM_COLORS[hardness]), texture="noise",
                      scale_m=_FOAM_PORES_M[hardness], amplitude=0.15, seed=hardness)
    return Block(name=f"foam-{hardness}", polygon=poly, hardness_n=float(hardness),
                 color=_FOAM_COLORS[hardness], appearance=look)


def _rigid(poly: NDArray[np.float64]) -> Block:
    look = Appearance(color=parse_color(_RIGID_COLOR), texture="stripes", scale_m=0.006,
                      amplitude=0.1, angle_deg=90.0)
    return Block(name="rigid", polygon=poly, rigid=True, color=_RIGID_COLOR, appearance=look)


def builtin_scenarios() -> dict[str, Scenario]:
    """The six scenarios of the paper's Table I."""
    full = rectangle(0.0, 0.0, 0.60, 0.40)
    out = [
        Scenario(name="homogeneous-60", blocks=(_foam(full, 60),),
                 description="one 60 N foam block over the whole 60x40 cm area"),
        Scenario(name="homogeneous-110", blocks=(_foam(full, 110),),
                 description="one 110 N foam block over the whole 60x40 cm area"),
        Scenario(name="heterogeneous-60-150",
                 blocks=(_foam(rectangle(0.0, 0.0, 0.30, 0.40), 60),
                         _foam(rectangle(0.30, 0.0, 0.60, 0.40), 150)),
                 description="60 N foam on the left half, 150 N on the right half"),
        Scenario(name="heterogeneous-110-150",
                 blocks=(_foam(rectangle(0.0, 0.0, 0.60, 0.20), 110),
                         _foam(rectangle(0.0, 0.20, 0.60, 0.40), 150)),
                 description="110 N foam at the front (y < 20 cm), 150 N at the back"),
        Scenario(name="heterogeneous-150-rigid",
                 blocks=(_foam(rectangle(0.0, 0.0, 0.32, 0.40), 150),
                         _rigid(rectangle(0.32, 0.0, 0.60, 0.40))),
                 description="150 N foam on x < 32 cm, a rigid board of the same height beyond"),
        Scenario(name="heterogeneous-60-110-rigid",
                 blocks=(_foam(np.array([[0.0, 0.0], [0.18, 0.0], [0.30, 0.40], [0.0, 0.40]]), 60),
                         _foam(np.array([[0.18, 0.0], [0.44, 0.0], [0.44, 0.4], [0.30, 0.4]]), 110),
                         _rigid(rectangle(0.44, 0.0, 0.60, 0.40))),
                 description="60 N | 110 N split by a slanted cut, rigid board on x > 44 cm"),
    ]
    return {s.name: s for s in out}

