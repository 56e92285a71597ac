"""A raw robot recording opened as a :class:`~deformap.replay.RecordedSession` of form ``"raw"``:
its presses found when opened, each read when asked for, as a session's pokes are."""

from __future__ import annotations

from pathlib import Path

from deformap._config import config_to_dict
from deformap._validation import check_instance, check_path, check_positive
from deformap.cloud.io import path_kind
from deformap.errors import FileFormatError
from deformap.replay._format import SESSION_FILE, SessionHeader
from deformap.replay._rawbag import RawBagReader
from deformap.replay._rawconfig import RawBagConfig
from deformap.replay._session import DEFAULT_CONTACT_GAP_M, RecordedSession

__all__ = ["RAW_SUFFIXES", "is_raw_bag", "load_raw_bag"]

#: Files that are a ROS 2 bag on their own (MCAP, sqlite3).
RAW_SUFFIXES = (".mcap", ".db3")


def is_raw_bag(path: str | Path) -> bool:
    """Whether ``path`` is a bag as a robot records it: a ``.mcap`` or ``.db3`` file, or a rosbag2
    folder (with ``metadata.yaml``) without ``session.yaml``."""
    p = Path(path)
    kind = path_kind(p)
    if kind == "file":
        return p.suffix in RAW_SUFFIXES
    if kind == "dir":
        return (path_kind(p / "metadata.yaml") == "file"
                and path_kind(p / SESSION_FILE) != "file")  # fmt: skip
    return False


def load_raw_bag(path: str | Path, config: RawBagConfig | None = None, *, default_force_n: float,
                 contact_gap_m: float = DEFAULT_CONTACT_GAP_M) -> RecordedSession:
    """Open a raw robot recording (a ``.mcap`` / ``.db3`` file or a rosbag2 folder) and find its
    presses: a session of form ``"raw"``, one poke per press.

    ``config`` names its topics, frames and thresholds (default ``RawBagConfig()``; see
    :func:`~deformap.replay.load_raw_config`); ``default_force_n`` is the commanded force when
    ``config.force_n`` is None; ``contact_gap_m`` as for :func:`~deformap.replay.load_session`.
    A bag missing or unreadable, lacking a topic or a press, or whose observation frames do not come
    before the first press, is a FileFormatError.
    """
    bag = check_path("path", path)
    cfg = check_instance("config", RawBagConfig() if config is None else config, RawBagConfig)
    if path_kind(bag) == "missing":
        raise FileFormatError(f"{bag}: no such bag")
    force = cfg.commanded_force(check_positive("default_force_n", default_force_n))
    reader = RawBagReader(bag, cfg, force)
    header = SessionHeader(
        root=bag if bag.is_dir() else bag.parent, form="raw", units=cfg.units,
        frame=cfg.world_frame, cam2world=None, workspace=reader.workspace(),
        tip_radius_m=cfg.tip_radius_m, observation=None, bag=bag, ground_truth=None,
        source={"raw": config_to_dict(cfg), "force_n": force, "n_presses": len(reader.presses)},
        pokes=reader.poke_specs())
    return RecordedSession(path=bag, header=header, ground_truth=None,
                           contact_gap_m=check_positive("contact_gap_m", contact_gap_m),
                           _reader=reader)
