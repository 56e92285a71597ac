"""Settings of a raw robot recording (``docs/robot.md``): which topics and frames hold what, and
the thresholds that find its presses; read from a YAML file beside the bag
(:func:`raw_config_file`) and the command line through the same constructor."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from deformap._config import config_from_dict, load_yaml
from deformap._validation import check_settings, setting
from deformap.errors import ConfigError

__all__ = [
    "DEFAULT_HULL",
    "RAW_CONFIG_NAME",
    "WORKSPACE_MARGIN_RADII",
    "HullPart",
    "RawBagConfig",
    "hull_points",
    "load_raw_config",
    "raw_config_file",
]

#: The settings file inside a rosbag2 folder (``NAME.deformap.yaml`` beside a ``NAME.mcap``).
RAW_CONFIG_NAME = "deformap.yaml"


@dataclass(frozen=True, kw_only=True)
class HullPart:
    """One rigid part of the probe in the tip's frame (origin at the tip's centre, ``z`` along the
    stick away from the surface), its convex hull removed from the press's cloud on its own.

    Parameters
    ----------
    shape : {"box", "cylinder", "cap"}
        A box of extents ``size_m``, a cylinder along ``z`` (diameter ``size_m[0]``, length
        ``size_m[2]``) or the tip's upper half-sphere (radius ``size_m[0] / 2``), centred at
        ``center_m``.
    center_m, size_m : (3,) float, metres
    """

    shape: Literal["box", "cylinder", "cap"] = "box"
    center_m: tuple[float, float, float] = setting((0.0, 0.0, 0.0))
    size_m: tuple[float, float, float] = setting((0.01, 0.01, 0.01), gt=0.0)

    def __post_init__(self) -> None:
        check_settings(self)


#: The default probe, the paper's 10 cm stick on the hand (Sec. V), each part grown by a few
#: millimetres so that depth noise on its edges goes with it (docs/robot.md): the tip's upper
#: half (1 cm radius; its lower half is in the dent), the stick (12 mm × 10 cm, as 16 mm) and an
#: 8 × 6 × 10 cm hand box (as 8.5 × 6.5 × 10.5 cm).
DEFAULT_HULL = (HullPart(shape="cap", center_m=(0.0, 0.0, 0.0), size_m=(0.02, 0.02, 0.02)),
                HullPart(shape="cylinder", center_m=(0.0, 0.0, 0.05), size_m=(0.016, 0.016, 0.10)),
                HullPart(shape="box", center_m=(0.0, 0.0, 0.15), size_m=(0.085, 0.065, 0.105)))


#: The default workspace reaches this many tip radii beyond the presses: a dent and the region
#: of interest around it span a few radii (Hertz: the surface sinks out to about three).
WORKSPACE_MARGIN_RADII = 5.0


@dataclass(frozen=True, kw_only=True)
class RawBagConfig:
    """What a raw robot recording holds, and how its presses are found.

    Parameters
    ----------
    cloud_topic, wrench_topic : str or None
        Topics of the depth camera's organised cloud and of the force sensor; None: the bag's one
        topic of that type (``PointCloud2``, ``WrenchStamped``).
    tf_topic, tf_static_topic : str
        Topics of the transforms.
    world_frame : str or None
        The frame whose ``z = 0`` is the table, ``z`` up (the map's frame); None: ``world`` when
        the bag has it, else the root of the camera's frame.
    tip_frame : str or None
        The ``/tf`` frame at the centre of the probe's tip, ``z`` along the stick away from the
        surface; None: found (the lowest frame rigidly joined to the force sensor, else moving
        with the arm, whose ``z`` points up during the first press).
    camera_frame, force_frame : str or None
        Override the clouds' and the wrenches' ``header.frame_id`` (None: use them).
    units : {"m", "mm"}
        Units of the cloud's coordinates.
    force_n : float or None
        The commanded normal force [N]; None: the run configuration's ``exploration.force_n``.
    wrench_sign : {"reaction", "applied"}
        Whether the sensor reports the force on the probe (negated here) or on the surface.
    contact_force_n : float or None
        A press lasts while the force exceeds this [N]; None: four times the rms magnitude of
        the sensor's noise, estimated from the quiet samples before the presses.
    hold_band : float
        The hold is the longest run within ``hold_band · force_n`` of the command; four times the noise.
    hold_min_s : float
        The shortest hold accepted [s]; 0.1 s gives a 30 Hz camera at least three frames.
    stamp_tolerance_s : float
        A frame or transform farther than this [s] from the moment wanted is not used; 1.5 frames.
    observation_time_s : float or None
        When the observation was taken [s after the bag's start]; None: the first frame.
    observation_frames : int
        Frames averaged for the observation, from the one picked (all before the first contact).
    workspace_lower, workspace_upper : (2,) float or None
        The rectangle to map in the world frame; None: the presses' surroundings (their
        bounding box grown by :data:`WORKSPACE_MARGIN_RADII` tip radii) within the observation's
        ``x``–``y`` extent.
    tip_radius_m : float
        Radius of the probe's spherical tip; 1 cm, the order of the paper's OptoForce tip.
    hull : tuple of HullPart
        The probe's parts in the tip's frame (:data:`DEFAULT_HULL`).
    """

    cloud_topic: str | None = None
    wrench_topic: str | None = None
    tf_topic: str = "/tf"
    tf_static_topic: str = "/tf_static"
    world_frame: str | None = None
    tip_frame: str | None = None
    camera_frame: str | None = None
    force_frame: str | None = None
    units: Literal["m", "mm"] = "m"
    force_n: float | None = setting(None, gt=0.0)
    wrench_sign: Literal["reaction", "applied"] = "reaction"
    contact_force_n: float | None = setting(None, gt=0.0)
    hold_band: float = setting(0.1, gt=0.0, lt=1.0)
    hold_min_s: float = setting(0.1, gt=0.0)
    stamp_tolerance_s: float = setting(0.05, gt=0.0)
    observation_time_s: float | None = setting(None, ge=0.0)
    observation_frames: int = setting(1, ge=1)
    workspace_lower: tuple[float, float] | None = None
    workspace_upper: tuple[float, float] | None = None
    tip_radius_m: float = setting(0.01, limit="tip_radius_m")
    hull: tuple[HullPart, ...] = field(default=DEFAULT_HULL)

    def __post_init__(self) -> None:
        check_settings(self)
        for name in ("cloud_topic", "wrench_topic", "tf_topic", "tf_static_topic",
                     "world_frame", "tip_frame"):  # fmt: skip
            if getattr(self, name) == "":
                raise ConfigError(f"`{name}` must be a non-empty string; got ''")
        if (self.workspace_lower is None) != (self.workspace_upper is None):
            raise ConfigError("`workspace_lower` and `workspace_upper` must be given together; "
                              "got one of them")
        if not self.hull:
            raise ConfigError("`hull` must hold at least one part (the stick); got none")


def raw_config_file(bag: Path) -> Path:
    """Where the settings of ``bag`` live: ``deformap.yaml`` inside a rosbag2 folder, or
    ``NAME.deformap.yaml`` beside a ``NAME.mcap`` / ``NAME.db3`` file."""
    return bag / RAW_CONFIG_NAME if bag.is_dir() else bag.with_name(f"{bag.stem}.{RAW_CONFIG_NAME}")


def load_raw_config(bag: Path, file: Path | None = None, **overrides: Any) -> RawBagConfig:
    """The settings of the raw recording ``bag``: ``file`` (default :func:`raw_config_file`, used
    when it exists), then the command line's ``overrides`` (None values left out); a refusal is a
    ConfigError naming the file and key."""
    path = raw_config_file(bag) if file is None else file
    data: dict[str, Any] = {}
    if file is not None or path.is_file():
        loaded = load_yaml(path, what="the raw recording's settings")
        if loaded is not None and not isinstance(loaded, dict):
            raise ConfigError(f"{path}: must be a mapping of settings; got {type(loaded).__name__}")
        data = dict(loaded or {})
    where = str(path) if data else "raw recording settings"
    config = config_from_dict(RawBagConfig, data, where=where)
    try:
        return replace(config, **{k: v for k, v in overrides.items() if v is not None})
    except TypeError as exc:
        raise ConfigError(f"raw recording settings: {exc}") from None


#: Points of a hull part's circle (cylinder, cap): 16 give a polygon within 2 % of the circle.
_CIRCLE = 16


def hull_points(part: HullPart, rot: NDArray[np.float64], origin: NDArray[np.float64]
                ) -> NDArray[np.float64]:  # fmt: skip
    """``(m, 3)`` world points whose convex hull is ``part`` at the tip pose ``rot``, ``origin``."""
    c, (sx, sy, sz) = np.asarray(part.center_m), part.size_m
    if part.shape == "box":
        local = np.array([[x * sx, y * sy, z * sz] for x in (-0.5, 0.5) for y in (-0.5, 0.5)
                          for z in (-0.5, 0.5)])  # fmt: skip
    else:
        az = np.linspace(0.0, 2 * np.pi, _CIRCLE, endpoint=False)
        ring = np.column_stack([np.cos(az), np.sin(az), np.zeros_like(az)]) * (sx / 2)
        if part.shape == "cylinder":
            half = np.array([0.0, 0.0, sz / 2])
            local = np.vstack([ring - half, ring + half])
        else:  # cap: the upper half-sphere, as rings at 0°, 30°, 60° and the pole
            r = sx / 2
            local = np.vstack([ring * np.cos(a) + [0, 0, r * np.sin(a)]
                               for a in (0.0, np.pi / 6, np.pi / 3)] + [[[0, 0, r]]])
    return np.asarray((local + c) @ rot.T + origin)
