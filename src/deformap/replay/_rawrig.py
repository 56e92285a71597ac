"""The recording rig's settings for :mod:`deformap.replay._rawwrite`: rates, per-axis force
noise, clock skew, force profile, frame and topic names (``docs/robot.md``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from deformap._validation import check_settings, setting
from deformap.errors import ConfigError

__all__ = ["RigConfig", "load_rig"]


@dataclass(frozen=True, kw_only=True)
class RigConfig:
    """The simulated rig that records a raw bag, and its imperfections.

    Parameters
    ----------
    camera_hz, wrench_hz, tf_hz : float
        Rates [Hz] of the depth camera, the force sensor and the arm's ``/tf``.
    force_noise_n : (3,) float
        Standard deviation [N] of the force sensor's noise on each of its axes.
    force_bias_n : float
        An offset [N] on the force's world ``z`` (a sensor not zeroed with the probe free).
    stamp_skew_s : float
        The force sensor's clock ahead of the others [s] (its header stamps only).
    force_profile : {"ramp", "step"}
        ``ramp``: the force rises along the press's force–travel record; ``step``: it jumps to
        the commanded force at contact (a force controller with no ramp), leaving no record.
    tip_moves : bool
        False: ``/tf`` holds the tool where it touched the surface for the whole press (the
        commanded pose published, not the measured one), so the record shows no travel.
    world_frame, base_frame, tool_frame, tip_frame, sensor_frame, camera_frame : str
        Frame names: the table (``z`` up), the arm's base, its flange (moving), the tip's centre
        (static below the flange, ``z`` along the stick away from the surface), the force
        sensor's and the camera's optical frame.
    cloud_topic, wrench_topic : str
        Topics of the camera's cloud and the force sensor.
    colors : bool
        Pack the clouds' colours (grey where a cloud has none) into ``rgb``.
    """

    camera_hz: float = setting(30.0, gt=0.0, le=1000.0)
    wrench_hz: float = setting(500.0, gt=0.0, le=10000.0)
    tf_hz: float = setting(50.0, gt=0.0, le=10000.0)
    force_noise_n: tuple[float, float, float] = setting((0.01, 0.01, 0.01), ge=0.0, le=1.0)
    force_bias_n: float = setting(0.0)
    stamp_skew_s: float = setting(0.0, ge=-1.0, le=1.0)
    force_profile: Literal["ramp", "step"] = "ramp"
    tip_moves: bool = True
    world_frame: str = "world"
    base_frame: str = "base_link"
    tool_frame: str = "tool0"
    tip_frame: str = "tool_tip"
    sensor_frame: str = "ft_sensor"
    camera_frame: str = "camera_depth_optical_frame"
    cloud_topic: str = "/camera/depth/color/points"
    wrench_topic: str = "/ft_sensor/wrench"
    colors: bool = True

    def __post_init__(self) -> None:
        check_settings(self)
        frames = [self.world_frame, self.base_frame, self.tool_frame, self.tip_frame,
                  self.sensor_frame, self.camera_frame]  # fmt: skip
        if not all(frames) or len(set(frames)) != len(frames):
            raise ConfigError(f"the rig's six frame names must be distinct and non-empty; got "
                              f"{frames}")  # fmt: skip
        if not self.cloud_topic or not self.wrench_topic or self.cloud_topic == self.wrench_topic:
            raise ConfigError("`cloud_topic` and `wrench_topic` must be distinct, non-empty "
                              f"names; got {self.cloud_topic!r}, {self.wrench_topic!r}")


def load_rig(path: Path) -> RigConfig:
    """The :class:`RigConfig` of the YAML file ``path`` (strict keys; a refusal names the file
    and key)."""
    from deformap._config import config_from_dict, load_yaml

    return config_from_dict(RigConfig, load_yaml(path, what="the rig's settings"),
                            where=str(path))
