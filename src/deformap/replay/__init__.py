"""Recorded sessions (a folder of cloud files, or a ROS 2 bag) read back and fed, poke by poke,
to the mapper the live loop uses.

:func:`load_session` checks ``session.yaml`` (``docs/recording-format.md``) and reads each poke on
demand; :func:`load_raw_bag` opens a robot's own bag (:class:`RawBagConfig`) as a session of form
``"raw"``; :func:`write_session` writes the format.
"""

from __future__ import annotations

from deformap._lazy import lazy_exports
from deformap.replay._format import FORMAT_NAME, FORMAT_VERSION, OPTIONAL_TOPICS, TOPICS
from deformap.replay._rawconfig import (
    DEFAULT_HULL,
    HullPart,
    RawBagConfig,
    load_raw_config,
    raw_config_file,
)
from deformap.replay._rawrig import RigConfig, load_rig
from deformap.replay._rawwrite import (
    APPROACH,
    FIRST_PRESS_S,
    HOLD,
    PAUSE,
    RAMP,
    RELEASE,
    T0_NS,
    RawMessage,
    RawPress,
    raw_messages,
    raw_timeline,
    write_raw_mcap,
)
from deformap.replay._session import RecordedSession, is_raw_bag, load_raw_bag, load_session
from deformap.replay._truth import GroundTruth, read_ground_truth, write_ground_truth
from deformap.replay._write import SESSION_FORMATS, RecordingEnvironment, write_session

__all__ = [
    "APPROACH",
    "DEFAULT_HULL",
    "FIRST_PRESS_S",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "HOLD",
    "OPTIONAL_TOPICS",
    "PAUSE",
    "RAMP",
    "RELEASE",
    "SESSION_FORMATS",
    "T0_NS",
    "TOPICS",
    "GroundTruth",
    "HullPart",
    "RawBagConfig",
    "RawMessage",
    "RawPress",
    "RecordedSession",
    "RecordingEnvironment",
    "ReplayResult",
    "RigConfig",
    "estimate_poke",
    "is_raw_bag",
    "load_raw_bag",
    "load_raw_config",
    "load_rig",
    "load_session",
    "map_session",
    "raw_config_file",
    "raw_messages",
    "raw_timeline",
    "read_ground_truth",
    "tip_sphere_points",
    "write_ground_truth",
    "write_raw_mcap",
    "write_session",
]

# The offline mapper needs deformap.explore (and through it gp and msm): imported on first use, so
# that reading a session stays light.
__getattr__, __dir__ = lazy_exports(
    __name__, {"_offline": ("ReplayResult", "estimate_poke", "map_session", "tip_sphere_points")},
    __all__, globals())
