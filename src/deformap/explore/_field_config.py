"""Settings of the map's Gaussian random fields: the surface, the touch (dent), the β-field and the
modulus field, one frozen, keyword-only dataclass each (gathered in
:class:`deformap.explore.ExplorationConfig`); lengths in metres, β dimensionless, ln E in ln Pa.

References
----------
Caccamo, S., Güler, P., Kjellström, H., Kragic, D. (2016). Active Perception and Modeling of
Deformable Surfaces using Gaussian Processes and Position-based Dynamics. Humanoids.
Gibson, L. J., Ashby, M. F. (1997). Cellular Solids, 2nd ed., ch. 5.
Rasmussen, C. E., Williams, C. K. I. (2006). Gaussian Processes for Machine Learning, Sec. 5.4.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from deformap._validation import SettingError, check_settings, setting

__all__ = ["BetaFieldConfig", "DepthAnchor", "ModulusFieldConfig", "NuggetEstimate", "SurfaceGPConfig",
           "TactileCap", "TouchGPConfig", "TouchModel"]

#: How the touch GP models the dent (``TouchGPConfig.model``).
TouchModel = Literal["residual", "height"]
#: Which cap of the tip carries the tactile points (``TouchGPConfig.tactile_cap``).
TactileCap = Literal["contact", "fixed"]
#: What the dent's depth at the tip is read from (``TouchGPConfig.depth_anchor``).
DepthAnchor = Literal["record", "tip"]
#: How the β-field's nugget is estimated (``BetaFieldConfig.nugget``).
NuggetEstimate = Literal["within-class", "off"]

@dataclass(frozen=True, kw_only=True)
class SurfaceGPConfig:
    """Crop, outlier filter and the surface Gaussian random field ("GPR world"), its
    hyperparameters fitted by maximum marginal likelihood (RW2006 Sec. 5.4) from the values below.

    Parameters
    ----------
    z_min_m : float
        Lowest height the crop keeps, metres in the world frame.
    z_max_m : float
        Highest height the crop keeps, metres in the world frame; must exceed ``z_min_m``.
    outlier_k : int
        Neighbours per point of the statistical outlier and slope filters, a count.
    outlier_std_ratio : float
        Outlier cut, in standard deviations of the points' mean neighbour distances.
    max_slope_deg : float
        Steepest surface kept, degrees from the horizontal.
        60°: the blocks' front faces a camera at 45° sees, fitted as heights, make the GP ring.
    min_length_scale_m : float
        Smallest length scale the fit may reach, metres.
        3 cm: on a flat surface disparity steps pull it to millimetres, where the grid GP is slow.
    fit_hyperparameters : bool
        Whether to fit the hyperparameters; ``False`` keeps the values below.
    max_fit_points : int
        Points of the seeded subset the likelihood is evaluated on, a count.
        800: about 2 cm apart, well below a table-top surface's length scale, at n³ per evaluation.
    fit_restarts : int
        Random restarts of the fit besides the start below, a count.
    length_scale_m : float
        Length scale σ_w the fit starts from, metres.
    signal_std_m : float
        Prior standard deviation of the heights the fit starts from, metres.
    noise_std_m : float
        Standard deviation of the camera's height noise the fit starts from, metres.
    grid_spacing_m : float
        Spacing of the map grid, metres; 5 mm is the paper's grid.
    """

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
    # below 1 mm is finer than a depth camera resolves, and cell counts grow as 1 / spacing²
    grid_spacing_m: float = setting(0.005, gt=0.0, ge=0.001)

    def __post_init__(self) -> None:
        check_settings(self)
        if self.z_max_m <= self.z_min_m:
            raise SettingError("z_max_m", f"must exceed `z_min_m` ({self.z_min_m}); got {self.z_max_m}")


@dataclass(frozen=True, kw_only=True)
class TouchGPConfig:
    """The ROI around a poke, the robot's removal from it, and the touch GP ("GPR-touch").

    Parameters
    ----------
    roi_size_m : float
        Side of the square ROI centred on the poke, metres.
        12 cm: a 1 cm tip dents foam over a few centimetres, inside the ROI's fixed edges.
    model : {"residual", "height"}
        What the touch GP models, heights or their change, metres.
        ``residual`` reverts far from the dent to "no change"; ``height`` is the paper's form.
    n_tactile : int
        Tactile points per 30° cap of the tip, a count (the paper's 10).
    tactile_noise_std_m : float
        Noise standard deviation of tactile points on the tip's proprioceptive pose, metres.
    tactile_cap : {"contact", "fixed"}
        Which cap of the tip carries the tactile points (``fixed`` is the paper's 30°).
    depth_anchor : {"record", "tip"}
        Where the tactile points' depth comes from, the record or the tip.
        ``record``: the surface minus the record's indentation, blind to the tip's height error.
    dent_visible_sigmas : float
        Smallest visible dent, in standard deviations of the camera's mean height near the tip.
        2 is a one-sided test at about 98 %.
    robot_margin_m : float
        Margin of the robot's convex hull whose points are removed, metres.
        2 mm: proprioception and camera do not agree to the millimetre.
    tip_margin_m : float
        Margin beyond the tip's radius of the ball whose points are removed, metres.
    above_surface_m : float
        Height above the pre-poke surface above which points are removed, metres.
        A dent goes down, so 1 cm higher is the stick, the hand or a flying pixel.
    max_slope_deg : float
        Steepest surface kept in the ROI, degrees from the horizontal.
    length_scale_m : float
        Length scale σ_w of the touch GP, metres.
        1 cm, the tip's radius: the dent cannot vary faster than the body pressing it.
    signal_std_m : float
        Prior standard deviation of the touch GP's heights, metres.
    noise_std_m : float
        Standard deviation of the camera's height noise in the ROI, metres.
    noise_samples : int
        Draws of the camera's noise carried through the touch GP for β's uncertainty, a count.
    """

    roi_size_m: float = setting(0.12, gt=0.0)
    model: TouchModel = "residual"
    # a thousand on a fingertip's cap are already closer together than the camera's points
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
    """Prior of the β-field over the pokes' β (the paper's σe, σw, σn).

    Parameters
    ----------
    signal_std : float
        Prior standard deviation σe of β about the pokes' weighted mean, dimensionless.
        0.3: its variance 0.09 exceeds the paper's ``T_h`` = 0.06, so an unexplored map asks for a poke.
    length_scale_m : float
        Length scale σw of the β-field, metres.
        0.2 m, a third of a table, is the size of the pieces a robot is asked to tell apart.
    noise_floor : float or None
        Smallest claimed σ of a poke's β, dimensionless; ``None``: the β grid's quantisation.
    nugget : {"within-class", "off"}
        How the nugget τ̂, in β units, is estimated (:mod:`deformap.explore._nugget`; off: 0).
    """

    signal_std: float = setting(0.3, gt=0.0)
    length_scale_m: float = setting(0.2, gt=0.0)
    noise_floor: float | None = setting(None, gt=0.0)
    nugget: NuggetEstimate = "within-class"

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class ModulusFieldConfig:
    """Prior of the modulus field, the Gaussian random field over the pokes' ln E (E in Pa).

    Parameters
    ----------
    signal_std : float
        Prior standard deviation of ln E about the pokes' weighted mean, ln Pa.
        1.73: ±2σ spans the 1 kPa to 1 MPa of soft foams to rubbers (Gibson & Ashby 1997, ch. 5).
    length_scale_m : float
        Length scale σ_w of the modulus field, metres.
        The β-field's, for its reason: the pieces' size is a property of the layout.
    noise_floor : float
        Smallest standard deviation of a poke's ln E, ln Pa (its σ_E / E is raised to it).
        0.1: a foam's modulus goes as its density squared, which varies by a few per cent.
    rigid_log_std : float
        Standard deviation of ln E given to a rigid poke at its detection bound, ln Pa.
        0.75: the bound has a relative error of about 1/2, and E goes as travel^(−3/2).
    """

    signal_std: float = setting(1.73, gt=0.0)
    length_scale_m: float = setting(0.2, gt=0.0)
    noise_floor: float = setting(0.1, gt=0.0)
    rigid_log_std: float = setting(0.75, gt=0.0)

    def __post_init__(self) -> None:
        check_settings(self)
