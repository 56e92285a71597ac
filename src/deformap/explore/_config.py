"""Settings of the mapper and the exploration loop (one frozen dataclass per component).

Defaults and why
----------------
Surface GP ("GPR world"): hyperparameters are fitted by maximum marginal likelihood on the first
observation, on a seeded subset of 800 points (their mean spacing, about 2 cm over 60×40 cm, is
well below any length scale a table-top surface has, and each likelihood evaluation costs n³), from
the values below and one random restart; the map is read on the paper's 0.5 cm grid. Before the
fit, points on surfaces steeper than 60° are dropped (``max_slope_deg``,
:func:`deformap.cloud.height_field_mask`): a camera at 45° sees the front faces of the blocks, and
fitted as heights those walls make the GP ring over the whole map (README, "β separates hardness
only under the force-driven protocol", says by how much). The fitted length scale is kept at or
above 3 cm (``min_length_scale_m``): a flat surface leaves it undetermined (the fitted signal is
then micrometres and any length scale fits) and the camera's disparity steps pull it to
millimetres, while the grid GP's cost grows steeply below it (its compressed inducing features
number about (extent / σ_w)², and its fit costs their cube, :mod:`deformap.gp`). The dents
themselves are the touch GP's (1 cm).

Robot removal: the convex hull of the robot's points (plus 2 mm: proprioception and camera do not
agree to the millimetre), a ball of the tip's radius plus 3 mm around the tip (the tactile points
stand for what it hides), and every point more than 1 cm above the surface as it was before the
poke — a dent goes down, so anything that high is the stick, the hand or a flying pixel between
them and the surface (1 cm is five times the camera's depth noise at the table). The same 60° slope
filter as for the surface removes the flying-pixel veils that hang lower than that behind the stick.

Touch GP ("GPR-touch"): fitted on a square ROI of the cloud seen while pressing plus the 10 tactile
points. ROI 12 cm: the dent of a 1 cm tip under about a newton spreads over a few centimetres on
foam 5 cm thick, and the edges of the ROI must be undisturbed because shape matching fixes them.
By default the touch GP models the *change* of height against the surface GP's mean before the poke
(``model="residual"``): far from the dent it reverts to "no change" instead of to a constant, which
the occlusion by stick and hand would otherwise bias. ``model="height"`` is the paper's literal form.
Its length scale (1 cm) is the tip's radius: the dent cannot vary faster than the body pressing it.

β-field ("GPR β-field"): prior standard deviation 0.3 (variance 0.09, above the paper's threshold
0.06 so that the unexplored map asks for a poke); length scale 0.2 m, a third of the table's width:
the size of the foam pieces a robot is asked to tell apart. Each poke's noise is its claimed β
uncertainty plus, in variance, the map's nugget: ``√(σᵢ² + τ̂²)``. σᵢ is the camera's noise
(measured in each poke's ROI) carried through the estimate (``TouchGPConfig.noise_samples`` draws
of the touch GP's smoother applied to noise, β̂ re-read on each,
:mod:`deformap.explore._dent_noise`): a repeatability at one place. τ̂ is the scatter of β̂ between
places on one material that σᵢ does not explain (the README, "β separates hardness only under the
force-driven protocol", compares the two), estimated for each map from its own pokes
(``BetaFieldConfig.nugget``, :mod:`deformap.explore._nugget`): the maximum a posteriori of the
restricted likelihood of the pokes within the region test's classes (each class's mean removed,
so the steps between materials are not read as scatter), with a half-Cauchy prior on τ whose scale
is the pokes' median claimed σ (the estimator's own scale, no number of a world). σᵢ is at least
``BetaFieldConfig.noise_floor``, by default the β grid's quantisation,
``shape_matching.beta_resolution / √12`` (0.0029: what every β̂'s σ already is at least, and
what a press read rigid claims), an explicit lower bound a robot may raise. Until this change the
floor was 0.015 and there was no nugget: the spread between places on the simulated world's 150 N
foam, a number fitted to the simulator's output (0.03 on the former reference β scale); ``nugget:
off`` with ``noise_floor: 0.015`` (``0.03`` under ``beta_scale: reference``) reproduces those maps.
On the simulated Table I scenarios (β-field; FEM seeds 0–3, the stiffening foam, kinect-v1) the
nugget came out 0–0.022; on the same pokes the region test found the same classes as with the
former floor in every map, while the planner, given other noises, placed other pokes (27 of 32
maps counted right against 30 of 32: README, Table I on the β-field under "β separates hardness
only under the force-driven protocol").
Modulus field (``ExplorationConfig.field = "modulus"``, :mod:`deformap.explore._modulus`): a
Gaussian random field over ln E [ln Pa] from the pokes' force–travel records. Its prior standard
deviation 1.73 is a quarter of ln(10⁶ Pa / 10³ Pa) = 6.9: the soft foams to rubbers a table-top
robot presses span about 1 kPa to 1 MPa (Gibson & Ashby 1997, ch. 5, flexible foams; rubbers at
0.5–5 MPa), so ±2σ about the data's mean spans that range. Its length scale is the β-field's
0.2 m, for the β-field's reason (the size of the pieces to tell apart, a property of the layout,
not of what is measured). Noise floor 0.1 (10 % in E): an open-cell foam's modulus goes as its
density squared (Gibson & Ashby, Eq. 5.6), and a foam sheet's density varies by a few per cent
from place to place (±5 % in density is ±10 % in E); the contact model's own error is of that
order too (issue 13 asks ≤ 10 % on linear-elastic foams). A rigid poke sits on the ln E axis at
its detection bound with ``rigid_log_std`` (0.75): the bound is the record's travel span plus two
of its standard deviations, so its relative error is about 1/2, and E goes as travel^(−3/2)
(Hertz): 1.5 × 1/2 = 0.75. Settings given in β units take their modulus-field counterpart as
the same fraction of the prior: ``T_h`` scales with the prior variance (0.06 of 0.09, two thirds,
is 2.0 of 3.0 in (ln E)²) and the regions' smallest step with the prior standard deviation
(:func:`deformap.explore.field_settings`).
Next pokes by ``planned`` (:mod:`deformap.explore._planning`): the fewest pokes, the centre
included, that bring every cell below ``T_h``; the README ("Results", the paper's Table I) gives
the pokes each strategy needs on the simulated scenarios.
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import field as _field
from typing import Literal

from deformap._validation import SettingError, check_settings, setting
from deformap.environment import Workspace
from deformap.explore._acquisition import Strategy
from deformap.msm import ShapeMatchingConfig
from deformap.stiffness import StiffnessConfig

__all__ = [
    "MAX_MAP_CELLS",
    "MAX_PLAN_CELLS",
    "MAX_ROI_BAND_BYTES",
    "PLANNER_STRATEGIES",
    "BetaFieldConfig",
    "BetaUncertainty",
    "DepthAnchor",
    "ExplorationConfig",
    "FieldName",
    "ModulusFieldConfig",
    "NuggetEstimate",
    "RegionLabels",
    "StopRegion",
    "SurfaceGPConfig",
    "TactileCap",
    "TouchGPConfig",
    "TouchModel",
    "check_exploration_budget",
]

#: How the touch GP models the dent (``TouchGPConfig.model``).
TouchModel = Literal["residual", "height"]
#: Which cap of the tip carries the tactile points (``TouchGPConfig.tactile_cap``).
TactileCap = Literal["contact", "fixed"]
#: What the dent's depth at the tip is read from (``TouchGPConfig.depth_anchor``).
DepthAnchor = Literal["record", "tip"]
#: Where the variance must fall below ``T_h`` (``ExplorationConfig.stop_region``).
StopRegion = Literal["workspace", "targets"]
#: How cells get their region (``ExplorationConfig.region_labels``).
RegionLabels = Literal["isopleth", "nearest", "indicator-kriging"]
#: Which field the regions and the next-poke choice run on (``ExplorationConfig.field``).
FieldName = Literal["beta", "modulus"]
#: How the β-field's nugget is estimated (``BetaFieldConfig.nugget``).
NuggetEstimate = Literal["within-class", "off"]
#: Where a poke's β uncertainty comes from (``ExplorationConfig.beta_uncertainty``).
BetaUncertainty = Literal["camera-noise", "shape-matching"]

#: Most bytes of one band of the ROI's shape-matching system (:mod:`deformap.msm._linsys`): the
#: β sweep holds its two assembled bands and a few factorisations of that size at once, so 512 MiB
#: keeps the sweep within a few GiB.
MAX_ROI_BAND_BYTES = 512 * 2**20
#: Most cells of the map grid: every map is a dense grid, and the ``min-max-variance`` look-ahead
#: holds a (256 candidates × cells) float64 matrix, 2 GB at this size.
MAX_MAP_CELLS = 1_000_000
#: Most cells of the planner's 2 cm grids (``planned``, ``min-max-variance``,
#: ``integrated-variance``): it holds
#: (candidates × domain) and (candidates × candidates) float64 kernel matrices, 0.8 GB each at
#: this size (4 m² of workspace).
MAX_PLAN_CELLS = 10_000
#: Spacing of the planner's grids (:class:`deformap.explore.MapGrid`'s ``plan_domain`` and
#: ``plan_candidates``), the budget's and the grid's one value.
PLAN_GRID_M = 0.02
#: The strategies that hold the planner's (candidates × domain) matrices.
PLANNER_STRATEGIES: tuple[Strategy, ...] = ("planned", "min-max-variance", "integrated-variance")


@dataclass(frozen=True, kw_only=True)
class SurfaceGPConfig:
    """Crop, outlier filter and the surface Gaussian random field."""

    z_min_m: float = -0.02
    z_max_m: float = 0.30
    # each point's k neighbours are held at once (n·k distances and indices)
    outlier_k: int = setting(20, ge=2, le=1000)
    outlier_std_ratio: float = setting(2.0, gt=0.0)
    max_slope_deg: float = setting(60.0, gt=0.0, le=90.0)
    min_length_scale_m: float = setting(0.03, gt=0.0)
    fit_hyperparameters: bool = True
    # each likelihood evaluation factorises an n × n matrix: 10⁴ points is 0.8 GB and ~3·10¹¹ flops
    max_fit_points: int = setting(800, ge=50, le=10_000)
    fit_restarts: int = setting(1, ge=0, le=100)  # each restart is a whole optimisation
    length_scale_m: float = setting(0.04, gt=0.0)
    signal_std_m: float = setting(0.03, gt=0.0)
    noise_std_m: float = setting(0.002, gt=0.0)
    # below 1 mm is finer than a depth camera resolves on a table (a pixel spans millimetres at
    # a metre), while every map's cell count grows as 1 / spacing²
    grid_spacing_m: float = setting(0.005, gt=0.0, ge=0.001)

    def __post_init__(self) -> None:
        check_settings(self)
        if self.z_max_m <= self.z_min_m:
            raise SettingError(
                "z_max_m", f"must exceed `z_min_m` ({self.z_min_m}); got {self.z_max_m}"
            )


@dataclass(frozen=True, kw_only=True)
class TouchGPConfig:
    """The ROI around a poke and the Gaussian random field that reconstructs its dent.

    ``noise_samples``: how many draws of the camera's noise are carried through the touch GP when
    β's uncertainty is the camera's noise (``ExplorationConfig.beta_uncertainty``, the one
    switch; :mod:`deformap.explore._dent_noise`); 0 when it is not.

    ``tactile_cap``: ``"contact"`` (default) puts the tactile points only on the cap of the tip
    that touches at the poke's indentation (Hertz contact radius ``√(R δ)``, at the paper's
    density of ``n_tactile`` points per 30° cap, at least the pole;
    :func:`deformap.cloud.contact_cap`); ``"fixed"``, the paper's ``n_tactile`` points on a
    fixed 30° cap.

    ``depth_anchor``: ``"record"`` (default) places the tactile points, when the press has a
    force–travel record the stiffness estimate could read, at the surface model's height at the
    contact minus the record's indentation (so that an error in the tip's absolute height does
    not move the dent), with the record's uncertainty of that indentation as their noise;
    ``"tip"``, and every press without such a record, places them on the tip where
    proprioception says it is, with ``tactile_noise_std_m``.

    ``dent_visible_sigmas``: with β's uncertainty from the camera's noise, a dent whose depth at
    the contact's edge (half the indentation, Hertz) is below this many standard deviations of
    the camera's mean height over the points seen around the tip is within the camera's noise:
    β's claimed σ is then that of knowing nothing about β, a uniform over [0, 1) (1/√12).
    2: a one-sided test at about 98 %.
    """

    roi_size_m: float = setting(0.12, gt=0.0)
    model: TouchModel = "residual"
    # the tactile points join the touch GP's data; a thousand on a fingertip's cap are already
    # closer together than the camera's own points
    n_tactile: int = setting(10, ge=1, le=1000)
    tactile_noise_std_m: float = setting(0.0005, gt=0.0)
    tactile_cap: TactileCap = "contact"
    depth_anchor: DepthAnchor = "record"
    dent_visible_sigmas: float = setting(2.0, ge=0.0)
    robot_margin_m: float = setting(0.002, ge=0.0)
    tip_margin_m: float = setting(0.003, ge=0.0)
    above_surface_m: float = setting(0.01, gt=0.0)
    max_slope_deg: float = setting(60.0, gt=0.0, le=90.0)
    length_scale_m: float = setting(0.01, gt=0.0)
    signal_std_m: float = setting(0.01, gt=0.0)
    noise_std_m: float = setting(0.002, gt=0.0)
    # each draw re-reads β̂ over the whole E(β) sweep: the cost is linear in the draws
    noise_samples: int = setting(64, ge=0, le=10_000)

    def __post_init__(self) -> None:
        check_settings(self)
        if self.noise_samples == 1:
            raise SettingError("noise_samples", "must be 0 (off) or at least 2; got 1")


@dataclass(frozen=True, kw_only=True)
class BetaFieldConfig:
    """Prior of the β-field Gaussian random field (the paper's σe, σw, σn; module docstring,
    "β-field", argues the defaults).

    Parameters
    ----------
    signal_std : float
        σe, the prior standard deviation of β about the pokes' weighted mean.
    length_scale_m : float
        σw, metres.
    noise_floor : float or None
        Smallest claimed σ of a poke's β, an explicit lower bound; ``None`` (default): the β
        grid's quantisation, ``shape_matching.beta_resolution / √12``, which every β̂'s σ
        already is at least (:func:`deformap.explore.beta_noise_floor`).
    nugget : {"within-class", "off"}
        ``within-class`` (default): each poke's noise is its σ (at least the floor) plus, in
        variance, the map's nugget τ², the scatter between places on one material that the
        claimed σ does not explain, estimated from the pokes of the map's own region classes
        (:mod:`deformap.explore._nugget`); ``off``: the σ at least the floor alone.
    """

    signal_std: float = setting(0.3, gt=0.0)
    length_scale_m: float = setting(0.2, gt=0.0)
    noise_floor: float | None = setting(None, gt=0.0)
    nugget: NuggetEstimate = "within-class"

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class ModulusFieldConfig:
    """Prior of the modulus field, a Gaussian random field over ln E (E in Pa; module docstring,
    "Modulus field", argues the defaults).

    Parameters
    ----------
    signal_std : float
        Prior standard deviation of ln E about the pokes' weighted mean.
    length_scale_m : float
        σ_w, metres.
    noise_floor : float
        Smallest standard deviation of a poke's ln E (σ_E / E raised to it).
    rigid_log_std : float
        Standard deviation of ln E given to a rigid poke at its detection bound.
    """

    signal_std: float = setting(1.73, gt=0.0)
    length_scale_m: float = setting(0.2, gt=0.0)
    noise_floor: float = setting(0.1, gt=0.0)
    rigid_log_std: float = setting(0.75, gt=0.0)

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class ExplorationConfig:
    """Everything the mapper and the loop need; written next to every result.

    Parameters
    ----------
    threshold : float
        ``T_h``: stop when the β-field's largest variance on the grid falls below it (paper: 0.06).
    max_pokes : int
        Hard limit on the number of pokes.
    strategy : {"paper", "max-variance", "min-max-variance", "planned", "level-set", \
"integrated-variance"}
        How the next target is chosen (see :mod:`deformap.explore._acquisition`).
    first_target : (2,) float or None
        The first poke, in metres; ``None`` means the workspace centre.
    stop_region : {"workspace", "targets"}
        Where the variance must fall below ``T_h``: ``workspace``, every cell of the map;
        ``targets``, only the cells a poke can be centred on (half a ROI inside the edges), the
        paper's literal rule ("until the ROI detector block does not find a new candidate point"),
        which stops sooner and leaves the edge band to extrapolation.
    force_n : float
        The commanded normal force of every press. 0.6 N keeps the Hertz contact of a 1 cm tip
        on the tip itself for foams down to 60 N (``F <= 4 E* R² / 3`` = 0.68 N) while denting
        them by millimetres, well above the camera's noise (:mod:`deformap.world._world`,
        "Default press force").
    max_regions : int
        Most regions the β-field is cut into (see :mod:`deformap.explore._regions`).
    region_prior_dof : float
        How many degrees of freedom the pokes' uncertainties count for when the region test
        judges whether the βs scatter more than one material would (7: as much as the eight
        presses on one foam the former noise floor was measured from; 0: ignore them, scale-free).
    region_labels : {"isopleth", "nearest", "indicator-kriging"}
        How cells get their region once the classes are found (:mod:`deformap.explore._regions`):
        ``isopleth``, the paper's, by the band of the β-field's mean a cell falls in;
        ``nearest``, the default, by the class of the poke nearest to the cell;
        ``indicator-kriging``, by the most probable class, each class's probability kriged from
        the pokes' class indicators (:mod:`deformap.explore._indicator`). Over 100 random
        worlds (``deformap bench worlds``, README "Many worlds") the nearest-poke cut beat the
        isopleths with every strategy from 7 pokes on (level before) and was the best of the
        three at 20 pokes (indicator kriging was a little better at 5–10).
    merge_seams : bool
        Before the cells are labelled, merge the classes whose every poke borders pokes of two
        other classes within twice the layer's thickness (:func:`deformap.explore.merge_seam_classes`):
        a press where two pieces meet reads between them, or softer than both by a free face, and
        is otherwise a region of its own. On by default: on the first 30 worlds of ``deformap
        bench worlds --seed 0`` (rescored on the same pokes, README "Many worlds") it took the
        worlds with more regions found than true after 20 pokes from 53 % to 30 % (``paper``) and
        33 % to 20 % (``planned``) and left Table I as it was; ``false`` gives the classes as found.
    split_by_place : bool
        Before that, split a class whose pokes away from the other classes form two places of
        different values (:func:`deformap.explore.split_by_place`: a join-count test of its best
        split by value against shuffles, no smallest step): two materials closer than the region
        test's smallest step, side by side, are otherwise one region. Needs six such pokes in a
        class, so it acts in longer runs (Table I is as without it). On by default: over 42
        random worlds (README "Many worlds") it mended 3 maps and broke 1 for three pokes, and
        left the median pokes to accuracy 0.9 as they were.
    boundary_pokes : int
        Pokes made after the variance has fallen below ``T_h``, each where a region boundary is
        least certain (:mod:`deformap.explore._acquisition`, "boundary pokes"); 0, the paper's
        rule, stops there.
    stiffness : StiffnessConfig
        Reading stiffness and Young's modulus from a press's force–travel record, when the
        environment gives one (:func:`deformap.stiffness.estimate_stiffness`).
    field : {"beta", "modulus"}
        The field the regions, the next-poke choice and the stopping rule run on: ``beta``, the
        β-field (the paper's); ``modulus``, the modulus field over ln E from the force–travel
        records (:mod:`deformap.explore._modulus`; ``threshold`` is then read as the same fraction
        of its prior variance), the default: it counted the regions right on the simulated FEM
        world and on the stiffening-foam physics where the β-field did not (README, "Regions on
        the β-field or on the modulus field"), and it does not depend on the camera. When no poke
        of a run gives a usable record (a camera-only robot or session) the run falls back to
        ``beta`` at its first poke, and its result says so (``field_fallback``).
    modulus_field : ModulusFieldConfig
        Prior of the modulus field; it is computed whenever a poke has a modulus, whichever
        ``field`` is chosen.
    beta_uncertainty : {"camera-noise", "shape-matching"}
        The one switch for where each poke's β uncertainty (its noise in the β-field) comes from:
        ``camera-noise``, the camera's noise measured in the ROI carried through the touch GP and
        the estimate (``touch.noise_samples`` draws, at least 2); ``shape-matching``, the shape
        matcher's own (``shape_matching.uncertainty``: the tile bootstrap or the E(β) tolerance;
        ``touch.noise_samples`` must then be 0, so that no setting is silently ignored).
    """

    threshold: float = setting(0.06, gt=0.0)
    # every poke is a press and a β sweep (seconds), and the β-field's and the planner's matrices
    # grow with the pokes
    max_pokes: int = setting(12, ge=1, le=1000)
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
    """Refuse, before any work, an exploration whose maps of ``workspace`` would be absurdly large.

    The bounds that depend on a single settings object hold from its construction; these depend
    on the workspace too. The map grid (``Workspace.grid`` at ``surface.grid_spacing_m``) must
    have at most :data:`MAX_MAP_CELLS` cells and, for the strategies that work on the planner's
    2 cm grid (:data:`PLANNER_STRATEGIES`), that grid at most :data:`MAX_PLAN_CELLS`.

    Parameters
    ----------
    config : ExplorationConfig
    workspace : Workspace
        The rectangle to map (``Environment.workspace``).

    Raises
    ------
    SettingError
        Naming ``surface.grid_spacing_m`` or ``strategy``, the cells asked for and the limit.
    """
    if not isinstance(config, ExplorationConfig):
        raise SettingError("config", f"must be an ExplorationConfig; got {type(config).__name__}")
    if not isinstance(workspace, Workspace):
        raise SettingError("workspace", f"must be a Workspace; got {type(workspace).__name__}")
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
    if config.strategy in PLANNER_STRATEGIES and plan > MAX_PLAN_CELLS:
        raise SettingError(
            "strategy",
            f"{config.strategy!r} plans on {plan:,} cells of {PLAN_GRID_M * 100:g} cm over "
            f"{area}; at most {MAX_PLAN_CELLS:,}: use 'max-variance' or 'paper', or a smaller "
            f"workspace",
        )
