"""Settings of the mapper and the exploration loop: :class:`ExplorationConfig` gathers one frozen,
keyword-only dataclass per component (the fields' in :mod:`deformap.explore._field_config`).

Each Parameters entry is a one-line description with its unit (metres, newtons, β in [0, 1),
ln E with E in pascals), then the reason for its default. A setting in β units holds for the
modulus field as the same fraction of its prior (:func:`deformap.explore.field_settings`).
The ``MAX_*`` bounds refuse, before any work, settings whose matrices would not fit in memory.
"The paper": Caccamo et al. (2016), referenced in :mod:`deformap.explore._field_config`.
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import field as _field
from typing import Literal

from deformap._validation import SettingError, check_settings, setting
from deformap.environment import Workspace
from deformap.explore._acquisition import Strategy
from deformap.explore._field_config import (
    BetaFieldConfig,
    DepthAnchor,
    ModulusFieldConfig,
    NuggetEstimate,
    SurfaceGPConfig,
    TactileCap,
    TouchGPConfig,
    TouchModel,
)
from deformap.msm import ShapeMatchingConfig
from deformap.stiffness import StiffnessConfig

__all__ = ["MAX_MAP_CELLS", "MAX_PLAN_CELLS", "MAX_ROI_BAND_BYTES", "AppearanceUse",
           "BetaFieldConfig", "BetaUncertainty", "DepthAnchor", "ExplorationConfig", "FieldName",
           "ModulusFieldConfig", "NuggetEstimate", "RegionLabels", "StopRegion", "SurfaceGPConfig",
           "TactileCap", "TouchGPConfig", "TouchModel", "check_exploration_budget"]

#: Where the variance must fall below ``T_h`` (``ExplorationConfig.stop_region``).
StopRegion = Literal["workspace", "targets"]
#: How cells get their region (``ExplorationConfig.region_labels``).
RegionLabels = Literal["isopleth", "nearest", "indicator-kriging"]
#: Which field the regions and the next-poke choice run on (``ExplorationConfig.field``).
FieldName = Literal["beta", "modulus"]
#: Where a poke's β uncertainty comes from (``ExplorationConfig.beta_uncertainty``).
BetaUncertainty = Literal["camera-noise", "shape-matching"]
#: Whether the map uses the camera's view of the layout (``ExplorationConfig.appearance``).
AppearanceUse = Literal["auto", "off"]

#: Most bytes of one band of the ROI's shape-matching system (:mod:`deformap.msm._linsys`); the
#: β sweep holds a few arrays of that size at once, so 512 MiB keeps it within a few GiB.
MAX_ROI_BAND_BYTES = 512 * 2**20
#: Most cells of the map grid: every map (the surface, the field's mean and variance, the labels,
#: each figure) is a dense grid of these cells, and a million (25 m² at the default 5 mm) is far
#: more than a table top needs while each float64 map stays at 8 MB.
MAX_MAP_CELLS = 1_000_000
#: Most cells of the ``planned`` strategy's 2 cm grids: its (candidates × domain) and
#: (candidates × candidates) float64 matrices are 0.8 GB each at this size (4 m² of workspace).
MAX_PLAN_CELLS = 10_000
#: Spacing of the planner's grids (``MapGrid.plan_domain``, ``plan_candidates``), metres.
PLAN_GRID_M = 0.02


@dataclass(frozen=True, kw_only=True)
class ExplorationConfig:
    """Everything the mapper and the loop need; written next to every result.

    Parameters
    ----------
    threshold : float
        ``T_h``, the largest map-field variance the stop cells may keep, in β².
        The modulus field reads it as the same fraction of its prior variance; 0.06 is the paper's.
    max_pokes : int
        Most pokes of a run, boundary pokes included, a count.
    strategy : {"paper", "max-variance", "planned", "level-set"}
        How the next poke is chosen (:mod:`deformap.explore._acquisition`).
    first_target : (2,) float or None
        The first poke's x, y, metres in the world frame; ``None``: the workspace's centre.
    stop_region : {"workspace", "targets"}
        Where the variance must fall below ``T_h``, the whole map or the targets.
        ``targets`` (half a ROI inside the edges) is the paper's rule, which leaves the edge band
        to extrapolation.
    force_n : float
        Commanded normal force of every press, newtons.
        0.6 N keeps the Hertz contact of a 1 cm tip on the tip for foams down to 60 N while
        denting them by millimetres.
    max_regions : int
        Most regions the map field is cut into, a count (:mod:`deformap.explore._classes`).
    region_prior_dof : float
        Degrees of freedom the pokes' claimed uncertainties count for in the region test.
        7 is as much as eight presses on one foam; 0 ignores the claims (scale-free).
    region_labels : {"isopleth", "nearest", "indicator-kriging"}
        How cells get their region once the classes are found (:mod:`deformap.explore._labels`).
    merge_seams : bool
        Whether to merge the classes that lie on a seam between two others before labelling.
        On, because a press where two pieces meet reads between both.
    split_by_place : bool
        Whether to split a class whose pokes form two places of different values, before merging.
        On, because two close materials side by side are otherwise one region.
    boundary_pokes : int
        Pokes made after the variance has fallen below ``T_h``, a count.
        Each goes where a region boundary is least certain; 0, the paper's rule, stops there.
    beta_uncertainty : {"camera-noise", "shape-matching"}
        Where each poke's β uncertainty, its noise in the β-field, comes from.
        ``camera-noise`` needs ``touch.noise_samples`` >= 2, ``shape-matching`` needs it 0.
    field : {"beta", "modulus"}
        The field the regions, the next-poke choice and the stop run on, β or ln E.
        ``modulus`` is in physical units and maps on β while no poke has a modulus
        (``field_fallback``).
    appearance : {"auto", "off"}
        Whether the map field uses the first observation's colours as a prior on the layout.
        ``auto`` uses them when the image shows a layout (:mod:`deformap.explore._appearance`).
    surface : SurfaceGPConfig
        The crop, filters and surface GP of the first observation.
    touch : TouchGPConfig
        The ROI, robot removal and touch GP of each press.
    beta_field : BetaFieldConfig
        Prior and noise of the β-field.
    modulus_field : ModulusFieldConfig
        Prior of the modulus field, computed whenever a poke has a modulus.
    shape_matching : ShapeMatchingConfig
        The shape-matching β estimate of each dent (:mod:`deformap.msm`).
    stiffness : StiffnessConfig
        Reading stiffness and Young's modulus from a press's force–travel record.
    """

    threshold: float = setting(0.06, gt=0.0)
    max_pokes: int = setting(12, limit="pokes")
    strategy: Strategy = "planned"
    first_target: tuple[float, float] | None = None
    stop_region: StopRegion = "workspace"
    force_n: float = setting(0.6, gt=0.0)
    max_regions: int = setting(6, ge=1)
    region_prior_dof: float = setting(7.0, ge=0.0)
    region_labels: RegionLabels = "nearest"
    merge_seams: bool = True
    split_by_place: bool = True
    boundary_pokes: int = setting(0, ge=0, le=1000)  # as for max_pokes
    beta_uncertainty: BetaUncertainty = "camera-noise"
    field: FieldName = "modulus"
    appearance: AppearanceUse = "auto"
    surface: SurfaceGPConfig = _field(default_factory=SurfaceGPConfig)
    touch: TouchGPConfig = _field(default_factory=TouchGPConfig)
    beta_field: BetaFieldConfig = _field(default_factory=BetaFieldConfig)
    modulus_field: ModulusFieldConfig = _field(default_factory=ModulusFieldConfig)
    shape_matching: ShapeMatchingConfig = _field(default_factory=ShapeMatchingConfig)
    stiffness: StiffnessConfig = _field(default_factory=StiffnessConfig)

    def __post_init__(self) -> None:
        check_settings(self)
        self._check_roi()
        samples = self.touch.noise_samples
        if self.beta_uncertainty == "camera-noise" and samples == 0:
            raise SettingError(
                "touch.noise_samples",
                "must be at least 2 when `beta_uncertainty` is 'camera-noise' (or set "
                "`beta_uncertainty` to 'shape-matching'); got 0",
            )
        if self.beta_uncertainty == "shape-matching" and samples != 0:
            raise SettingError(
                "touch.noise_samples",
                "must be 0 when `beta_uncertainty` is 'shape-matching' (the shape matcher's "
                f"`shape_matching.uncertainty` gives β's uncertainty then); got {samples}",
            )

    def _check_roi(self) -> None:
        """The ROI's particle grid (``_dent.roi_grid``: the surface grid's spacing, an odd node
        count per side) must hold one cluster and keep its linear system's band within
        :data:`MAX_ROI_BAND_BYTES` (half-width as in :mod:`deformap.msm._linsys`)."""
        spacing = self.surface.grid_spacing_m
        side = 2 * round(self.touch.roi_size_m / spacing / 2) + 1
        sm = self.shape_matching
        k, nz = sm.cluster_size, sm.body_layers + 1
        where = f"at `surface.grid_spacing_m` = {spacing:g} m"
        if side < k:
            raise SettingError(
                "touch.roi_size_m",
                f"must span at least `shape_matching.cluster_size` = {k} grid nodes per side "
                f"{where}; got {self.touch.roi_size_m:g} m ({side} nodes)",
            )
        half_width = (k - 1) * (side * nz + nz) + nz - 1
        band = 8 * side * side * nz * (half_width + 1)
        if band > MAX_ROI_BAND_BYTES:
            raise SettingError(
                "touch.roi_size_m",
                f"makes a shape-matching body of {side} × {side} × {nz} particles {where} "
                f"(cluster size {k}), whose linear system needs {band / 2**20:,.0f} MiB per band; "
                f"at most {MAX_ROI_BAND_BYTES / 2**20:,.0f} MiB: use a smaller ROI, a coarser "
                f"grid or fewer `shape_matching.layers`; got {self.touch.roi_size_m:g} m",
            )


def check_exploration_budget(config: ExplorationConfig, workspace: Workspace) -> None:
    """Refuse, before any work, an exploration whose ``first_target`` lies outside ``workspace``,
    whose map grid has over :data:`MAX_MAP_CELLS` cells or, for ``planned``, whose 2 cm planning
    grid has over :data:`MAX_PLAN_CELLS`.

    Raises
    ------
    SettingError
        Naming ``first_target``, ``surface.grid_spacing_m`` or ``strategy``, what came and the
        limit.
    """
    if not isinstance(config, ExplorationConfig):
        raise SettingError("config", f"must be an ExplorationConfig; got {type(config).__name__}")
    if not isinstance(workspace, Workspace):
        raise SettingError("workspace", f"must be a Workspace; got {type(workspace).__name__}")
    if config.first_target is not None:
        (x, y), (x0, y0), (x1, y1) = config.first_target, workspace.lower, workspace.upper
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            raise SettingError(
                "first_target",
                f"must lie inside the workspace [{x0:g}, {x1:g}] × [{y0:g}, {y1:g}] m; got "
                f"({x:g}, {y:g})",
            )
    (width, depth), spacing = workspace.size, config.surface.grid_spacing_m
    cells = max(1, round(width / spacing)) * max(1, round(depth / spacing))
    area = f"a {width:g} × {depth:g} m workspace"
    if cells > MAX_MAP_CELLS:
        raise SettingError(
            "surface.grid_spacing_m",
            f"makes {cells:,} map cells over {area}; at most {MAX_MAP_CELLS:,}: use a coarser "
            f"spacing or a smaller workspace; got {spacing:g} m",
        )
    plan = (round(width / PLAN_GRID_M) + 1) * (round(depth / PLAN_GRID_M) + 1)
    if config.strategy == "planned" and plan > MAX_PLAN_CELLS:
        raise SettingError(
            "strategy",
            f"{config.strategy!r} plans on {plan:,} cells of {PLAN_GRID_M * 100:g} cm over "
            f"{area}; at most {MAX_PLAN_CELLS:,}: use 'max-variance' or 'paper', or a smaller "
            f"workspace",
        )
