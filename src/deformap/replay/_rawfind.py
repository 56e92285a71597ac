"""What a raw bag holds, found once when it is opened: each role's topic by its message type, the
world, camera, force and tip frames, and the force's noise floor with the contact threshold it sets
(:class:`BagDiscovery`, the part of :class:`~deformap.replay._rawbag.RawBagReader` that reads no
press). Every value found or assumed is noted with its reason for the report."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud.io import TransformTree, bag_topics
from deformap.errors import DeformapError, FileFormatError
from deformap.replay._rawconfig import RawBagConfig
from deformap.replay._rawpress import (
    CONTACT_NOISE_MULTIPLE,
    FoundPress,
    contact_threshold,
    noise_floor,
)

__all__ = ["CLOUD_TYPE", "TF_TYPE", "WRENCH_TYPE", "BagDiscovery"]

CLOUD_TYPE = "sensor_msgs/msg/PointCloud2"
WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"


def _resolved(name: str | None) -> str:
    """A topic or frame name, found or given, once the bag is open."""
    assert name is not None, "resolved when the bag is opened"
    return name


class BagDiscovery:
    """Topics, frames, tip and contact threshold of a raw bag; :class:`RawBagReader` fills the
    attributes below while it opens the bag."""

    path: Path
    commanded_n: float
    found: dict[str, dict[str, Any]]
    config: RawBagConfig
    tree: TransformTree
    presses: list[FoundPress]
    noise: Any
    camera_frame: str
    force_frame: str
    wrench_ns: NDArray[np.int64]
    wrench_force: NDArray[np.float64]

    # -- what the bag holds, found once when it is opened ---------------------------------

    @property
    def cloud_topic(self) -> str:
        return _resolved(self.config.cloud_topic)

    @property
    def wrench_topic(self) -> str:
        return _resolved(self.config.wrench_topic)

    @property
    def world_frame(self) -> str:
        return _resolved(self.config.world_frame)

    @property
    def tip_frame(self) -> str:
        return _resolved(self.config.tip_frame)

    def _note(self, key: str, value: Any, why: str) -> None:
        self.found[key] = {"value": value, "from": why}

    def _topics(self, cfg: RawBagConfig) -> RawBagConfig:
        """Each role's topic, given (its type checked) or found (the one topic of its type)."""
        topics = bag_topics(self.path)
        listing = ", ".join(f"{t} ({kind}, {n})" for t, (kind, n) in sorted(topics.items()))
        chosen: dict[str, str] = {}
        roles = (("cloud_topic", CLOUD_TYPE, "the camera's cloud", "--cloud-topic"),
                 ("wrench_topic", WRENCH_TYPE, "the force sensor", "--wrench-topic"),
                 ("tf_topic", TF_TYPE, "the transforms", "`tf_topic`"),
                 ("tf_static_topic", TF_TYPE, "the static transforms", "`tf_static_topic`"))
        for key, msgtype, role, option in roles:
            given = getattr(cfg, key)
            if given is None:
                of_type = sorted(t for t, (kind, _) in topics.items() if kind == msgtype)
                if len(of_type) != 1:
                    raise FileFormatError(
                        f"{self.path}: {len(of_type)} topics carry {msgtype} ({role}); name one "
                        f"with {option}. The bag holds: {listing or 'no topic'}")
                chosen[key] = of_type[0]
                self._note(key, of_type[0], f"found: the bag's one {msgtype} topic")
                continue
            if given not in topics:
                if key == "tf_static_topic":  # optional: a rig may publish every link on /tf
                    chosen[key] = given
                    continue
                raise FileFormatError(
                    f"{self.path}: bag has no topic {given!r} ({role}, {option}). The bag holds: "
                    f"{listing or 'no topic'}")
            if topics[given][0] != msgtype:
                raise FileFormatError(
                    f"{self.path}: topic {given!r} ({option}, {role}) carries "
                    f"{topics[given][0]}; expected {msgtype}")
            chosen[key] = given
            if key in ("cloud_topic", "wrench_topic"):
                self._note(key, given, "given")
        used = [chosen["cloud_topic"], chosen["wrench_topic"], chosen["tf_topic"]]
        if len(set(used)) != 3:
            raise FileFormatError(f"{self.path}: the camera, force and /tf topics must differ; "
                                  f"got {used}")  # fmt: skip
        return replace(cfg, cloud_topic=chosen["cloud_topic"],
                       wrench_topic=chosen["wrench_topic"], tf_topic=chosen["tf_topic"],
                       tf_static_topic=chosen["tf_static_topic"])

    def _frames(self, cfg: RawBagConfig) -> RawBagConfig:
        """The world frame (given, ``world``, or the camera's root) and the camera's and the
        sensor's frames, each checked to reach the world frame: one refusal naming what is
        missing and listing the frames there are."""
        frames = self.tree.frames
        if cfg.world_frame is not None:
            world, why = cfg.world_frame, "given"
        elif "world" in frames:
            world, why = "world", "assumed: the frame named 'world' (z up, the table at z = 0)"
        elif self.camera_frame in frames:
            world = self.tree.root(self.camera_frame)
            why = (f"assumed: the root of the camera's frame {self.camera_frame!r} (z up, the "
                   "table at z = 0)")
        else:
            world, why = "world", "default"
        self._note("world_frame", world, why)
        self._note("camera_frame", self.camera_frame,
                   "given" if cfg.camera_frame else "found: the cloud's header.frame_id")
        self._note("force_frame", self.force_frame,
                   "given" if cfg.force_frame else "found: the wrench's header.frame_id")
        absent, apart = [], []
        for what, frame, option in (("world", world, "--world-frame"),
                                    ("camera", self.camera_frame, "`camera_frame`"),
                                    ("force sensor", self.force_frame, "--force-frame")):
            if frame not in frames:
                absent.append(f"the {what} frame {frame!r} ({option})")
            elif world in frames and self.tree.root(frame) != self.tree.root(world):
                apart.append(f"the {what} frame {frame!r} ({option})")
        if absent or apart:
            parts = ([f"not on {cfg.tf_topic!r} or {cfg.tf_static_topic!r}: {', '.join(absent)}"]
                     if absent else [])
            parts += [f"not connected to {world!r}: {', '.join(apart)}"] if apart else []
            raise FileFormatError(f"{self.path}: {'; '.join(parts)}; the frames there: {frames}")
        return replace(cfg, world_frame=world)

    def _threshold(self, cfg: RawBagConfig) -> float:
        """The contact threshold: given, or from the noise of the quiet samples before the presses."""
        self.noise = noise_floor(self.wrench_force)
        self._note("force_noise_n", [round(float(v), 6) for v in self.noise.std],
                   f"estimated: per sensor axis, from {self.noise.n_samples} quiet samples in "
                   f"{self.noise.n_windows} span(s) between the presses")
        if cfg.contact_force_n is not None:
            self._note("contact_force_n", cfg.contact_force_n, "given (`contact_force_n`)")
            return cfg.contact_force_n
        contact = contact_threshold(self.noise, self.commanded_n)
        self._note("contact_force_n", round(contact, 6),
                   f"{CONTACT_NOISE_MULTIPLE:g} × the noise's rms magnitude "
                   f"{self.noise.rms_n:.3g} N: noise alone crosses it with probability < 1e-4 a "
                   "sample")
        band_low = self.commanded_n * (1 - cfg.hold_band)
        if contact >= band_low:
            raise FileFormatError(
                f"{self.path}: topic {self.wrench_topic!r} is too noisy for presses of "
                f"{self.commanded_n:.4g} N: its noise ({self.noise.rms_n:.3g} N rms with the probe "
                f"free) puts the contact threshold at {contact:.3g} N, above the hold's band; "
                "set `contact_force_n` if the force holds well above it")
        return contact

    def _tip(self, cfg: RawBagConfig) -> RawBagConfig:
        """The tip frame: given and checked, or found among the frames rigidly joined to the
        force sensor (else the moving frames) as the lowest at the first press's hold whose
        ``z`` points up (the press goes along its ``−z``)."""
        frames, world = self.tree.frames, self.world_frame
        assert world is not None
        press = next((p for p in self.presses if p.error is None), self.presses[0])
        k = press.hold_start if press.hold_start >= 0 else press.start
        stamp = int(self.wrench_ns[k])
        what = f"{self.path}: the tip frame"
        if cfg.tip_frame is not None:
            if cfg.tip_frame not in frames or self.tree.root(cfg.tip_frame) != self.tree.root(world):
                raise FileFormatError(
                    f"{what} {cfg.tip_frame!r} (--tip-frame) is not on {cfg.tf_topic!r} or "
                    f"{cfg.tf_static_topic!r}, connected to {world!r}; the frames there: "
                    f"{frames}")
            self._note("tip_frame", cfg.tip_frame, "given")
            return cfg
        rigid = [f for f in self.tree.rigid_group(self.force_frame) if self.tree.moves(f)]
        moving = [f for f in frames if f != world and self.tree.moves(f)
                  and self.tree.root(f) == self.tree.root(world)]  # fmt: skip
        for pool, why in ((rigid, f"rigidly joined to the force sensor's {self.force_frame!r}"),
                          (moving, "moving with the arm")):
            up = []
            for frame in pool:
                try:
                    rot, trans = self.tree.lookup(world, frame, stamp, what=what)
                except DeformapError:
                    continue
                if rot[0][2, 2] > 0.5:  # z up: the press goes along -z, into the table
                    up.append((float(trans[0][2]), frame))
            if up:
                tip = min(up)[1]
                self._note("tip_frame", tip, f"found: the lowest frame {why} whose z points up "
                           f"at press {press.index + 1}'s hold")
                return replace(cfg, tip_frame=tip)
        raise FileFormatError(
            f"{what}: none found (no frame rigidly joined to the force sensor's "
            f"{self.force_frame!r} or moving with the arm has its z up at press "
            f"{press.index + 1}); name it with --tip-frame. The frames there: {frames}")

    # -- first pass -------------------------------------------------------------------------
