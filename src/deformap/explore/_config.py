"""Settings of the mapper and the exploration loop (one frozen dataclass per component).

Defaults and why
----------------
Surface GP ("GPR world"): hyperparameters are fitted by maximum marginal likelihood on the first
observation, on a seeded subset of 800 points (their mean spacing, about 2 cm over 60×40 cm, is
well below any length scale a table-top surface has, and each likelihood evaluation costs n³), from
the values below and one random restart; the map is read on the paper's 0.5 cm grid. Before the
fit, points on surfaces steeper than 60° are dropped (``max_slope_deg``,
:func:`deformap.cloud.height_field_mask`): a camera at 45° sees the front faces of the blocks, and
fitted as heights those walls made the GP ring by ±1–2 mm over the whole map (measured on a
homogeneous block: ±0.03 mm without them). The fitted length scale is kept at or above 3 cm
(``min_length_scale_m``): a flat surface leaves it undetermined (the fitted signal is then
micrometres and any length scale fits) and the camera's disparity steps pull it to millimetres,
while the grid GP's cost grows steeply below it (fit and map of 46,000 points over 60×40 cm:
28 s at 1.5 cm, 6.5 s at 2 cm, 0.9 s at 3 cm). The dents themselves are the touch GP's (1 cm).

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
the size of the foam pieces a robot is asked to tell apart; each poke's β uncertainty is its noise,
with a floor of 0.03. That uncertainty is the camera's noise (measured in the ROI) carried
through the estimate (``TouchGPConfig.noise_samples`` = 64 draws of the touch GP's smoother applied
to noise, β̂ re-read on each, :mod:`deformap.explore._dent_noise`): about 0.01 / 0.025 / 0.05 /
0.12 on 60 / 110 / 150 / 250 N blocks, about twice the spread of β̂ over eight places on one block
(0.004 / 0.015 / 0.028 / 0.050), so it errs on the safe side. The floor stands for what the noise
does not explain (a 150 N block's eight places spread by 0.03).
Next pokes by ``planned`` (:mod:`deformap.explore._planning`): with these settings it needs 5
pokes, the centre included, to bring every cell of a 60×40 cm table below 0.06, where
``max-variance`` needs 7 and the paper's random choice (``paper``) 8–12.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from deformap._validation import check_int, check_positive, check_slope_deg, check_vector
from deformap.errors import InvalidArgumentError
from deformap.explore._acquisition import STRATEGIES
from deformap.msm import ShapeMatchingConfig

__all__ = [
    "BetaFieldConfig",
    "ExplorationConfig",
    "SurfaceGPConfig",
    "TouchGPConfig",
]


@dataclass(frozen=True, kw_only=True)
class SurfaceGPConfig:
    """Crop, outlier filter and the surface Gaussian random field."""

    z_min_m: float = -0.02
    z_max_m: float = 0.30
    outlier_k: int = 20
    outlier_std_ratio: float = 2.0
    max_slope_deg: float = 60.0
    min_length_scale_m: float = 0.03
    fit_hyperparameters: bool = True
    max_fit_points: int = 800
    fit_restarts: int = 1
    length_scale_m: float = 0.04
    signal_std_m: float = 0.03
    noise_std_m: float = 0.002
    grid_spacing_m: float = 0.005

    def __post_init__(self) -> None:
        if self.z_max_m <= self.z_min_m:
            raise InvalidArgumentError(
                f"`z_max_m` must exceed `z_min_m`; got {self.z_min_m} and {self.z_max_m}"
            )
        check_int("outlier_k", self.outlier_k, minimum=2)
        check_positive("outlier_std_ratio", self.outlier_std_ratio)
        check_slope_deg("max_slope_deg", self.max_slope_deg)
        check_int("max_fit_points", self.max_fit_points, minimum=50)
        check_int("fit_restarts", self.fit_restarts, minimum=0)
        for name in ("length_scale_m", "signal_std_m", "noise_std_m", "grid_spacing_m",
                     "min_length_scale_m"):
            check_positive(name, getattr(self, name))


@dataclass(frozen=True, kw_only=True)
class TouchGPConfig:
    """The ROI around a poke and the Gaussian random field that reconstructs its dent.

    ``noise_samples`` draws of the camera's noise through the touch GP give each poke's β
    uncertainty (:mod:`deformap.explore._dent_noise`); 0 falls back to
    ``ShapeMatchingConfig.uncertainty`` (the tile bootstrap of E(β) by default).
    """

    roi_size_m: float = 0.12
    model: Literal["residual", "height"] = "residual"
    n_tactile: int = 10
    tactile_noise_std_m: float = 0.0005
    robot_margin_m: float = 0.002
    tip_margin_m: float = 0.003
    above_surface_m: float = 0.01
    max_slope_deg: float = 60.0
    length_scale_m: float = 0.01
    signal_std_m: float = 0.01
    noise_std_m: float = 0.002
    noise_samples: int = 64

    def __post_init__(self) -> None:
        check_positive("roi_size_m", self.roi_size_m)
        check_int("n_tactile", self.n_tactile, minimum=1)
        check_int("noise_samples", self.noise_samples, minimum=0)
        if self.noise_samples == 1:
            raise InvalidArgumentError("`noise_samples` must be 0 (off) or at least 2; got 1")
        check_positive("robot_margin_m", self.robot_margin_m, allow_zero=True)
        check_positive("tip_margin_m", self.tip_margin_m, allow_zero=True)
        check_slope_deg("max_slope_deg", self.max_slope_deg)
        for name in (
            "tactile_noise_std_m",
            "length_scale_m",
            "signal_std_m",
            "noise_std_m",
            "above_surface_m",
        ):
            check_positive(name, getattr(self, name))


@dataclass(frozen=True, kw_only=True)
class BetaFieldConfig:
    """Prior of the β-field Gaussian random field (the paper's σe, σw, σn)."""

    signal_std: float = 0.3
    length_scale_m: float = 0.2
    noise_floor: float = 0.03

    def __post_init__(self) -> None:
        for name in ("signal_std", "length_scale_m", "noise_floor"):
            check_positive(name, getattr(self, name))


@dataclass(frozen=True, kw_only=True)
class ExplorationConfig:
    """Everything the mapper and the loop need; written next to every result.

    Parameters
    ----------
    threshold : float
        ``T_h``: stop when the β-field's largest variance on the grid falls below it (paper: 0.06).
    max_pokes : int
        Hard limit on the number of pokes.
    strategy : {"paper", "max-variance", "min-max-variance", "planned"}
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
        them by 4–7 mm, well above the camera's noise.
    max_regions : int
        Most regions the β-field is cut into (see :mod:`deformap.explore._regions`).
    region_prior_dof : float
        How many degrees of freedom the pokes' uncertainties count for when the region test
        judges whether the βs scatter more than one material would (7: as much as the eight
        presses on one foam the noise floor was measured from; 0: ignore them, scale-free).
    region_labels : {"isopleth", "nearest"}
        How cells get their region once the classes are found (:mod:`deformap.explore._regions`):
        ``isopleth``, the paper's, by the band of the β-field's mean a cell falls in;
        ``nearest``, by the class of the poke nearest to the cell.
    boundary_pokes : int
        Pokes made after the variance has fallen below ``T_h``, each where a region boundary is
        least certain (:mod:`deformap.explore._acquisition`, "boundary pokes"); 0, the paper's
        rule, stops there.
    """

    threshold: float = 0.06
    max_pokes: int = 12
    strategy: Literal["paper", "max-variance", "min-max-variance", "planned"] = "planned"
    first_target: tuple[float, float] | None = None
    stop_region: Literal["workspace", "targets"] = "workspace"
    force_n: float = 0.6
    max_regions: int = 6
    region_prior_dof: float = 7.0
    region_labels: Literal["isopleth", "nearest"] = "isopleth"
    boundary_pokes: int = 0
    surface: SurfaceGPConfig = field(default_factory=SurfaceGPConfig)
    touch: TouchGPConfig = field(default_factory=TouchGPConfig)
    beta_field: BetaFieldConfig = field(default_factory=BetaFieldConfig)
    shape_matching: ShapeMatchingConfig = field(default_factory=ShapeMatchingConfig)

    def __post_init__(self) -> None:
        check_positive("threshold", self.threshold)
        check_int("max_pokes", self.max_pokes, minimum=1)
        if self.strategy not in STRATEGIES:
            raise InvalidArgumentError(
                f"`strategy` must be one of {list(STRATEGIES)}; got {self.strategy!r}"
            )
        if self.stop_region not in ("workspace", "targets"):
            raise InvalidArgumentError(
                f"`stop_region` must be one of ['workspace', 'targets']; got {self.stop_region!r}"
            )
        if self.first_target is not None:
            check_vector("first_target", self.first_target, 2, what="metres")
        check_positive("force_n", self.force_n)
        check_int("max_regions", self.max_regions, minimum=1)
        check_positive("region_prior_dof", self.region_prior_dof, allow_zero=True)
        if self.region_labels not in ("isopleth", "nearest"):
            raise InvalidArgumentError(
                f"`region_labels` must be one of ['isopleth', 'nearest']; got {self.region_labels!r}"
            )
        check_int("boundary_pokes", self.boundary_pokes, minimum=0)
