"""Settings of the simulated world (:class:`WorldConfig`) and the budget that keeps a world from
asking for absurd memory or time (:func:`check_world_budget`), checked before any mesh is built.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, get_args

import numpy as np

from deformap._validation import SettingError, check_settings, setting
from deformap.world._appearance import parse_color
from deformap.world._camera import CameraConfig
from deformap.world._probe import ProbeGeometry
from deformap.world._scenario import Scenario
from deformap.world._stiffening import max_grid_nodes

__all__ = ["MAX_FEM_UNKNOWNS", "PHYSICS", "Physics", "WorldConfig", "check_world_budget"]

#: The world's contact physics (``WorldConfig.physics``).
Physics = Literal["linear-fem", "stiffening-foam", "stiffening-fem"]
PHYSICS: tuple[str, ...] = get_args(Physics)


@dataclass(frozen=True, kw_only=True)
class WorldConfig:
    """Settings of the simulated world.

    Parameters
    ----------
    physics : {"linear-fem", "stiffening-foam", "stiffening-fem"}
        How the foam answers a press. ``modulus_pa`` is the small-strain modulus in each.
    densification_strain : float
        Densification strain ``ε_d`` of the stiffening law ``σ = M ε / (1 − ε / ε_d)^m`` (stiffening
        physics only). 0.95 is Gibson & Ashby's ``1 − 1.4 ρ*/ρ_s`` at relative density 0.035.
    stiffening_exponent : float
        Exponent ``m`` of that law; 1 is Gibson & Ashby's densification fit, 0 is linear.
    element_size_m : float
        In-plane size of the foam's hexahedra. 7.5 mm resolves the 1 cm tip's dent.
    top_layer_m : float
        Thickness of the top element layer.
    layer_growth : float
        Growth factor of the element layers' thickness below the top one.
    poisson_ratio : float
        Poisson's ratio of every foam block.
    tip_radius_m : float
        Radius of the probe's spherical tip (1 cm, Optoforce-like).
    stick_length_m : float
        Length of the stick that holds the tip.
    stick_radius_m : float
        Radius of that stick.
    hand_size_m : (3,) float
        The box standing for the hand that holds the stick.
    force_noise_n : float
        Standard deviation per axis of the force sensor's noise (Optoforce-class resolution).
    force_travel_levels : int
        Load levels above contact, evenly spaced in force, at which the world's physics solves a
        press (one press solve each, :mod:`deformap.world._force_travel`); the sensors read the
        record between them at ``sample_rate_hz``, never fewer samples per stretch than these.
    ramp_rate_n_per_s : float
        Probe protocol: the rate at which the commanded force rises on the loading ramp (a
        load-controlled press) and falls on the unloading branch.
    hold_s : float
        Probe protocol: how long the commanded force is held after the ramp (the record's hold:
        the travel creeps on a viscoelastic block); 0: no hold recorded.
    sample_rate_hz : float
        The rate at which the force sensor and the encoders are read on the ramp, the hold and
        the unloading (never fewer samples per stretch than ``force_travel_levels``): a ramp of
        ``(F − contact_threshold_n) / ramp_rate_n_per_s`` seconds gives that times this rate
        samples after the first. No sample costs a press solve of its own.
    unload : bool
        Probe protocol: record the unloading branch (the force falling back to contact).
    contact_threshold_n : float
        The force at which the probe detects contact: the record's first sample, where travel starts.
    encoder_noise_m : float
        Standard deviation of the arm's reading of the tip's position along the press direction.
    force_travel_noise_rel : float
        Relative part ``rel`` of the record's force noise ``rel · F + n`` at force ``F``.
    force_travel_noise_n : float
        Absolute part ``n`` of the record's force noise ``rel · F + n``.
    noise : bool
        False turns off every noise source (camera, force sensor, force–travel record) at once.
    camera : CameraConfig
        The simulated depth camera.
    table_margin_m : float
        How far the table extends beyond the workspace on every side.
    """

    #: Keys a release removed, and why (a run config or journal written before refuses with it).
    RETIRED_KEYS: ClassVar[dict[str, str]] = {
        "force_travel_spacing": "the record's samples are the sensors', evenly in time at "
                                "`sample_rate_hz` on a load-controlled ramp"}

    physics: Physics = "linear-fem"
    densification_strain: float = setting(0.95, gt=0.0, le=1.0)  # a strain: at most full collapse
    # m > 10 is a wall, not a foam; each unit of m steepens σ near ε_d by another 1 / (1 − ε/ε_d)
    stiffening_exponent: float = setting(1.0, ge=0.0, le=10.0)
    # finer than 1 mm resolves nothing the tip or the camera can tell (elements grow as 1 / size²)
    element_size_m: float = setting(0.0075, gt=0.0, ge=0.001)
    # the layer count grows as thickness / top layer when the layers do not grow (growth 1)
    top_layer_m: float = setting(0.005, gt=0.0, ge=0.001)
    layer_growth: float = setting(1.5, ge=1.0, le=10.0)
    poisson_ratio: float = setting(0.3, ge=0.0, lt=0.5)  # 0.5 makes the FEM's λ infinite
    tip_radius_m: float = setting(0.01, limit="tip_radius_m")
    stick_length_m: float = setting(0.10, gt=0.0)
    stick_radius_m: float = setting(0.006, gt=0.0)
    hand_size_m: tuple[float, float, float] = setting((0.08, 0.06, 0.10), gt=0.0)
    # the protocol refuses a force 0.125 N off a 0.3 N command: 0.02 N per axis stays 6 σ inside
    force_noise_n: float = setting(0.01, ge=0.0, le=0.02)
    # 8 levels resolve the curvature of a sphere's F ∝ δ^(3/2); each level costs one press solve
    force_travel_levels: int = setting(8, ge=2, le=1000)
    # a hand-held press gauge loads at about 1–10 N/s; 1 kN/s is an impact, not a press
    ramp_rate_n_per_s: float = setting(2.0, gt=0.0, le=1000.0)
    hold_s: float = setting(0.0, ge=0.0, le=600.0)  # ten minutes: longer is a creep test
    # 100 Hz: the Robotiq FT 300's data output rate (its datasheet); arms' F/T streams run at
    # hundreds of Hz to 1 kHz (docs/robot.md), so this is the slow end
    sample_rate_hz: float = setting(100.0, gt=0.0, le=10000.0)
    unload: bool = False
    contact_threshold_n: float = setting(0.02, gt=0.0, le=0.1)
    encoder_noise_m: float = setting(5e-5, ge=0.0, le=1e-3)  # arm encoders: about 0.05 mm
    force_travel_noise_rel: float = setting(0.01, ge=0.0, le=0.1)  # force sensors: 1 % + 5 mN
    force_travel_noise_n: float = setting(0.005, ge=0.0, le=0.1)
    noise: bool = True
    camera: CameraConfig = field(default_factory=CameraConfig)
    table_margin_m: float = setting(0.2, gt=0.0)
    # a light up and to the front left, as over a lab bench: side faces show three shades
    light_direction: tuple[float, float, float] = setting(
        (-0.3, -0.4, 1.0), ge=-1e3, le=1e3, doc="direction toward the light (z > 0)")
    # a lit room: a third of the light on a face comes from everywhere
    ambient: float = setting(0.3, ge=0.0, le=1.0, doc="share of ambient light")
    tip_color: tuple[float, float, float] = setting(
        (0.15, 0.15, 0.15), ge=0.0, le=1.0, doc="probe tip colour, sRGB")  # black rubber
    stick_color: tuple[float, float, float] = setting(
        (0.75, 0.75, 0.78), ge=0.0, le=1.0, doc="probe stick colour, sRGB")  # aluminium
    hand_color: tuple[float, float, float] = setting(
        (0.2, 0.35, 0.6), ge=0.0, le=1.0, doc="hand colour, sRGB")  # a blue gripper

    def __post_init__(self) -> None:
        for name in ("tip_color", "stick_color", "hand_color"):
            object.__setattr__(self, name, parse_color(getattr(self, name), name))
        check_settings(self)
        light = np.asarray(self.light_direction)
        if not light[2] > 1e-6 * np.linalg.norm(light):
            raise SettingError("light_direction", f"must point up (z > 0); got {light.tolist()}")

    @property
    def probe(self) -> ProbeGeometry:
        """The probe geometry built from the `tip_radius_m`, `stick_*`, `hand_size_m` fields."""
        return ProbeGeometry(tip_radius_m=self.tip_radius_m, stick_length_m=self.stick_length_m,
                             stick_radius_m=self.stick_radius_m,
                             hand_size_m=tuple(self.hand_size_m))  # type: ignore[arg-type]

    @classmethod
    def coarse(cls, **overrides: Any) -> WorldConfig:
        """A 2 cm mesh and a 320×240 camera, for fast tests (not for measurements)."""
        settings: dict[str, Any] = {"element_size_m": 0.02, "top_layer_m": 0.01,
                                    "camera": CameraConfig(width=320, height=240)}
        settings.update(overrides)
        return cls(**settings)


#: Most displacement unknowns (3 per mesh node, all blocks) of the foam FEM: each block's
#: factorisation is kept, and its fill-in (about N^(4/3) in 3-D) reaches gigabytes at a million.
MAX_FEM_UNKNOWNS = 1_000_000


def _layer_count(thickness_m: float, top_m: float, growth: float) -> int:
    """Upper bound, in closed form, on the layers of :func:`~deformap.world._fem.graded_levels`."""
    top = min(top_m, thickness_m)
    if growth <= 1.0 + 1e-12:
        return math.ceil(thickness_m / top) + 1
    return math.ceil(math.log1p(thickness_m * (growth - 1.0) / top) / math.log(growth)) + 1


def check_world_budget(config: WorldConfig, scenario: Scenario) -> None:
    """Refuse, before any work, a world of more than :data:`MAX_FEM_UNKNOWNS` unknowns in its
    blocks' meshes, or (``stiffening-foam``) in a press grid
    (:func:`~deformap.world._stiffening.max_grid_nodes`).

    Raises
    ------
    SettingError
        Naming ``element_size_m`` (or ``tip_radius_m``), the unknowns asked for and the limit.
    """
    if not isinstance(config, WorldConfig):
        raise SettingError("config", f"must be a WorldConfig; got {type(config).__name__}")
    if not isinstance(scenario, Scenario):
        raise SettingError("scenario", f"must be a Scenario; got {type(scenario).__name__}")
    size = config.element_size_m
    unknowns = 0
    for block in scenario.blocks:
        extent = block.polygon.max(axis=0) - block.polygon.min(axis=0)
        nx, ny = (max(1, math.ceil(e / size - 1e-9)) for e in extent)
        nz = _layer_count(block.thickness_m, config.top_layer_m, config.layer_growth)
        unknowns += 3 * (nx + 1) * (ny + 1) * (nz + 1)
        if config.physics == "stiffening-foam" and not block.rigid:
            nodes = max_grid_nodes(extent, config.tip_radius_m)
            if nodes > MAX_FEM_UNKNOWNS:
                raise SettingError(
                    "tip_radius_m",
                    f"grades a press grid of up to {nodes:,} nodes over block {block.name!r}; at "
                    f"most {MAX_FEM_UNKNOWNS:,}: use a larger tip; got {config.tip_radius_m:g} m")
    if unknowns > MAX_FEM_UNKNOWNS:
        raise SettingError(
            "element_size_m",
            f"meshes scenario {scenario.name!r} with about {unknowns:,} FEM unknowns; at most "
            f"{MAX_FEM_UNKNOWNS:,}: use larger elements or a thicker `top_layer_m`; got {size:g} m")
