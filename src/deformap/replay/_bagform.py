"""The bag form of a session: a ROS 2 bag on the topics of ``TOPICS``.

A poke's messages share one header stamp, which ``session.yaml`` names (``stamp_ns``) beside the
command (target, force). Each message is decoded when its poke is read, so a corrupted message
breaks only its own poke. The force–travel record (``OPTIONAL_TOPICS``) is a
``Float64MultiArray`` of dimensions ``samples`` (n) × ``travel_m,force_n`` (2), or, for a record
with its times, ``samples`` × ``time_s,travel_m,force_n,phase`` (4), ``phase`` 0 on the ramp, 1 in
the hold and 2 while unloading, in that order; having no header, it is logged at the poke's stamp.
Without one a poke has no record. The cloud after release (``OPTIONAL_TOPICS["released"]``) is a
``PointCloud2`` stamped as the poke's other messages, in the session's frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud
from deformap.cloud.io import (
    TransformTree,
    array_to_pointcloud2,
    bag_error_text,
    bag_read_errors,
    bag_writer,
    header_message,
    header_stamp_ns,
    iter_bag_messages,
    path_kind,
    pointcloud2_colors,
    pointcloud2_structured,
    pointcloud2_to_cloud,
    read_bag_static_transform,
    read_bag_transforms,
    typestore,
    wrench_message,
    xyz_with_holes,
)
from deformap.environment import ForceTravel, PressObservation, PressPhase
from deformap.errors import DeformapError, FileFormatError
from deformap.replay._confine import check_bag_confined, verify_digest
from deformap.replay._format import OPTIONAL_TOPICS, TOPICS, PokeSpec, PressParts, SessionHeader

#: Labels of the record's two dimensions in its ``Float64MultiArray`` layout.
FORCE_TRAVEL_DIMS = ("samples", "travel_m,force_n")
#: Labels of a record with times and phases (``phase``: 0 ramp, 1 hold, 2 unloading).
FORCE_TRAVEL_PHASED_DIMS = ("samples", "time_s,travel_m,force_n,phase")

__all__ = ["FORCE_TRAVEL_DIMS", "FORCE_TRAVEL_PHASED_DIMS", "BagReader", "force_travel_message",
           "write_session_bag"]


class BagReader:
    """Reads the poke messages of a bag-form session, each one when its poke is asked for."""

    def __init__(self, header: SessionHeader, stamp_tolerance_ns: int = 0) -> None:
        assert header.bag is not None
        self.header = header
        self.path = header.bag
        #: a message stamped this far [ns] from its poke's ``stamp_ns`` still belongs to it
        self.stamp_tolerance_ns = stamp_tolerance_ns
        #: per poke (0-based): what its entry says beyond its β (``stamp_gaps_s``)
        self.notes: dict[int, dict[str, Any]] = {}
        if path_kind(self.path) == "missing":
            raise FileFormatError(f"{self.path}: no such bag (the session's `bag`)")
        for file in check_bag_confined(self.path):
            if path_kind(file) == "file":  # a missing one: rosbags names it
                verify_digest(header.sha256, file)
        # topic -> (log time, CDR bytes) of each message
        self._raw: dict[str, list[tuple[int, bytes]]] = {
            topic: [] for topic, _ in (*TOPICS.values(), *OPTIONAL_TOPICS.values())}
        for raw in iter_bag_messages(self.path, dict(TOPICS.values()),
                                     optional=dict(OPTIONAL_TOPICS.values())):  # fmt: skip
            self._raw[raw.topic].append((raw.log_time_ns, bytes(raw.data)))
        self._decoded: dict[str, dict[int, list[Any]]] = {}  # key -> stamp -> messages
        self._undecodable: dict[str, list[str]] = {}  # key -> why its messages failed to decode
        self._tf_static: NDArray[np.float64] | None = None
        self._tree: TransformTree | None = None  # /tf and /tf_static, read on first use

    def _force_travel(self, stamp: int) -> ForceTravel | None:
        """The record logged at ``stamp``, or None."""
        topic, msgtype = OPTIONAL_TOPICS["force_travel"]
        where = f"{self.path} [{topic} logged at {stamp}]"
        raws = [data for time, data in self._raw[topic] if time == stamp]
        if not raws:
            return None
        if len(raws) > 1:
            raise FileFormatError(
                f"{where}: {len(raws)} messages; a poke needs at most one force–travel record")
        try:
            msg = typestore().deserialize_cdr(raws[0], msgtype)
        except bag_read_errors() as exc:
            raise FileFormatError(
                f"{where}: could not be decoded: {bag_error_text(exc, 120)}") from None
        dims = [(str(d.label), int(d.size)) for d in msg.layout.dim]
        data = np.asarray(msg.data, dtype=float)
        labels = tuple(d[0] for d in dims)
        width = 4 if labels == FORCE_TRAVEL_PHASED_DIMS else 2
        if (len(dims) != 2 or labels not in (FORCE_TRAVEL_DIMS, FORCE_TRAVEL_PHASED_DIMS)
                or dims[1][1] != width or msg.layout.data_offset != 0
                or data.size != width * dims[0][1]):
            raise FileFormatError(
                f"{where}: layout must be {FORCE_TRAVEL_DIMS[0]!r} (n) × "
                f"{FORCE_TRAVEL_DIMS[1]!r} (2) or {FORCE_TRAVEL_PHASED_DIMS[1]!r} (4) with 2n or "
                f"4n values from offset 0; got dims {dims}, offset {msg.layout.data_offset}, "
                f"{data.size} values")
        rows = data.reshape(-1, width)
        try:
            if width == 2:
                return ForceTravel(travel_m=rows[:, 0], force_n=rows[:, 1])
            return _phased_record(rows)
        except DeformapError as exc:
            raise FileFormatError(f"{where}: {exc}") from None

    def _released(self, stamp: int) -> PointCloud | None:
        """The cloud after release stamped ``stamp`` (world frame), or None."""
        topic, msgtype = OPTIONAL_TOPICS["released"]
        where = f"{self.path} [{topic} stamped {stamp}]"
        found = []
        for number, (_, data) in enumerate(self._raw[topic], start=1):
            try:
                msg = typestore().deserialize_cdr(data, msgtype)
            except bag_read_errors() as exc:
                raise FileFormatError(f"{self.path} [{topic}] message {number}: could not be "
                                      f"decoded: {bag_error_text(exc, 120)}") from None
            if header_stamp_ns(msg.header) == stamp:
                found.append(msg)
        if not found:
            return None
        if len(found) > 1:
            raise FileFormatError(f"{where}: {len(found)} messages; a poke has at most one")
        return self._to_world(self._cloud(found[0], where, self.header.frame))

    def _by_stamp(self, key: str) -> dict[int, list[Any]]:
        """The messages of ``TOPICS[key]`` by header stamp, decoded on first use; why each one
        that could not be decoded failed goes to ``_undecodable``."""
        if key not in self._decoded:
            topic, msgtype = TOPICS[key]
            store, errors = typestore(), bag_read_errors()
            by_stamp: dict[int, list[Any]] = {}
            bad = self._undecodable[key] = []
            for number, (_, data) in enumerate(self._raw[topic], start=1):
                try:
                    msg = store.deserialize_cdr(data, msgtype)
                    by_stamp.setdefault(header_stamp_ns(msg.header), []).append(msg)
                except errors as exc:
                    bad.append(f"message {number}: {bag_error_text(exc, 120)}")
            self._decoded[key] = by_stamp
        return self._decoded[key]

    def _message(self, key: str, stamp: int, index: int = -1) -> Any:
        by_stamp = self._by_stamp(key)
        msgs = by_stamp.get(stamp, [])
        if not msgs and self.stamp_tolerance_ns and by_stamp:
            # the nearest stamp within the tolerance; the gap goes to the poke's entry
            near = min(by_stamp, key=lambda s: abs(s - stamp))
            if abs(near - stamp) <= self.stamp_tolerance_ns:
                msgs = by_stamp[near]
                gaps = self.notes.setdefault(index, {}).setdefault("stamp_gaps_s", {})
                gaps[TOPICS[key][0]] = (near - stamp) / 1e9
        topic = TOPICS[key][0]
        if len(msgs) > 1:  # which one is the poke's? neither is kept silently
            raise FileFormatError(
                f"{self.path}: topic {topic!r} has {len(msgs)} messages stamped {stamp}; "
                "a poke needs exactly one on each topic")
        if not msgs:
            bad = self._undecodable[key]
            note = f"; {len(bad)} message(s) there could not be decoded ({bad[0]})" if bad else ""
            within = (f" or within {self.stamp_tolerance_ns / 1e9:g} s (--stamp-tolerance)"
                      if self.stamp_tolerance_ns else "")
            raise FileFormatError(
                f"{self.path}: topic {topic!r} has no message stamped {stamp}{within}{note}")
        return msgs[0]

    def _cloud(self, msg: Any, where: str, frame: str, colors: bool = True) -> PointCloud:
        if msg.header.frame_id != frame:
            raise FileFormatError(
                f"{where}: header.frame_id is {msg.header.frame_id!r} but the session's frame is "
                f"{frame!r} (session.yaml `frame`)")
        # holes of an organised cloud (is_dense false) are dropped with their colours
        cloud, _ = pointcloud2_to_cloud(msg, where=where, units=self.header.units, frame=frame,
                                        colors=colors)  # fmt: skip
        return cloud

    def _frame_to_world(self, frame: str, stamp_ns: int, where: str
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
        """``frame``'s rotation and translation to ``world`` at ``stamp_ns`` (a message's header
        stamp), from the bag's ``/tf`` and ``/tf_static`` within the stamp tolerance; a frame they
        do not resolve there is refused naming the message."""
        try:
            if self._tree is None:
                self._tree = read_bag_transforms(self.path, tolerance_ns=self.stamp_tolerance_ns)
            rot, trans = self._tree.lookup("world", frame, stamp_ns, what=where)
        except FileFormatError as exc:
            raise FileFormatError(
                f"{where}: header.frame_id is {frame!r}, which the bag's /tf and /tf_static do "
                f"not take to 'world' at its stamp, within --stamp-tolerance ({exc})") from None
        return rot[0], trans[0]

    def _to_world(self, cloud: PointCloud) -> PointCloud:
        cam2world = self.header.cam2world
        if cam2world is None:
            return cloud
        if isinstance(cam2world, str):
            if self._tf_static is None:
                self._tf_static = read_bag_static_transform(self.path, self.header.frame, "world")
            cam2world = self._tf_static
        return cloud.transformed(cam2world, "world")

    def observation(self) -> PointCloud:
        topic = TOPICS["observation"][0]
        msgs = [msg for _, same in sorted(self._by_stamp("observation").items()) for msg in same]
        bad = self._undecodable["observation"]
        if not msgs or bad:
            raise FileFormatError(
                f"{self.path}: topic {topic!r} must hold at least one message, each readable; got "
                f"{len(msgs)}" + (f" ({len(bad)} could not be decoded: {bad[0]})" if bad else ""))
        if len(msgs) == 1:
            return self._to_world(self._cloud(msgs[0], f"{self.path} [{topic}]",
                                              self.header.frame))  # fmt: skip
        return self._to_world(self._averaged(msgs, f"{self.path} [{topic}]"))

    def _averaged(self, msgs: list[Any], where: str) -> PointCloud:
        """A stream of organised clouds of one shape averaged pixel by pixel (NaN holes left
        out; colours too when every frame has them), as a raw bag's observation is."""
        shapes = {(int(m.height), int(m.width)) for m in msgs}
        if len(shapes) != 1 or next(iter(shapes))[0] == 1:
            raise FileFormatError(
                f"{where}: {len(msgs)} messages; several are averaged pixel by pixel, so they "
                f"must be organised clouds (height > 1) of one shape; got shapes {sorted(shapes)}")
        total: NDArray[np.float64] | None = None
        count: NDArray[np.int64] | None = None
        rgb_sum: NDArray[np.float64] | None = None
        colored = True
        for n, msg in enumerate(msgs, start=1):
            if msg.header.frame_id != self.header.frame:
                raise FileFormatError(
                    f"{where} message {n}: header.frame_id is {msg.header.frame_id!r} but the "
                    f"session's frame is {self.header.frame!r} (session.yaml `frame`)")
            try:
                table = pointcloud2_structured(msg)
                xyz = xyz_with_holes(msg, table)
            except DeformapError as exc:
                raise FileFormatError(f"{where} message {n}: {exc}") from None
            ok = np.isfinite(xyz).all(axis=1)
            rgb = pointcloud2_colors(msg, where=f"{where} message {n}", table=table, valid=ok)
            if total is None or count is None:
                total, count = np.zeros_like(xyz), np.zeros(len(xyz), dtype=np.int64)
                rgb_sum = np.zeros_like(xyz)
            total[ok] += xyz[ok]
            count[ok] += 1
            if rgb is None:
                colored = False
            elif rgb_sum is not None:
                rgb_sum[ok] += rgb[ok]
        assert total is not None and count is not None and rgb_sum is not None
        seen = count > 0
        if not seen.any():
            raise FileFormatError(f"{where}: its {len(msgs)} messages hold no finite point")
        scale = 1e-3 if self.header.units == "mm" else 1.0
        colors = np.clip(rgb_sum[seen] / count[seen, None], 0, 1) if colored else None
        return PointCloud(total[seen] / count[seen, None] * scale, colors,
                          frame=self.header.frame)

    def press_parts(self, spec: PokeSpec) -> PressParts:
        assert spec.stamp_ns is not None
        stamp = spec.stamp_ns

        def where(key: str) -> str:
            return f"{self.path} [{TOPICS[key][0]} stamped {stamp}]"

        i = spec.index
        cloud = self._to_world(self._cloud(self._message("cloud", stamp, i), where("cloud"),
                                           self.header.frame))  # fmt: skip
        robot = self._cloud(self._message("robot", stamp, i), where("robot"), "world",
                            colors=False)  # fmt: skip
        values = {}
        for key in ("wrench", "tip"):
            msg = self._message(key, stamp, i)
            vec = msg.wrench.force if key == "wrench" else msg.point
            values[key] = np.array([vec.x, vec.y, vec.z], dtype=float)
            if not np.isfinite(values[key]).all():
                raise FileFormatError(
                    f"{where(key)}: holds NaN or infinite values {values[key].tolist()}")
            frame = str(msg.header.frame_id)
            if frame != "world":  # a sensor's own frame: the bag's /tf and /tf_static take it there
                rot, trans = self._frame_to_world(frame, header_stamp_ns(msg.header), where(key))
                values[key] = rot @ values[key] + (trans if key == "tip" else 0.0)
        return PressParts(cloud, values["tip"], values["wrench"], np.asarray(robot.points),
                          self._force_travel(stamp), self._released(stamp))


def _phased_record(rows: NDArray[np.float64]) -> ForceTravel:
    """A record from ``time_s, travel_m, force_n, phase`` rows (module docstring)."""
    phase = rows[:, 3]
    if not np.all(np.isin(phase, (0.0, 1.0, 2.0))) or np.any(np.diff(phase) < 0):
        raise FileFormatError(
            "`phase` must be 0 (ramp), 1 (hold) or 2 (unloading), in that order; got "
            f"{len(phase)} rows whose codes run {phase[:12].tolist()}"
            + (" ..." if len(phase) > 12 else ""))
    parts = {}
    for code, name in ((1.0, "hold"), (2.0, "unloading")):
        sel = rows[phase == code]
        if len(sel):
            parts[name] = PressPhase(time_s=sel[:, 0], travel_m=sel[:, 1], force_n=sel[:, 2])
    ramp = rows[phase == 0.0]
    return ForceTravel(travel_m=ramp[:, 1], force_n=ramp[:, 2], time_s=ramp[:, 0], **parts)


def _point_message(stamp_ns: int, point: Any) -> Any:
    types = typestore().types
    xyz = types["geometry_msgs/msg/Point"](*map(float, point))
    return types["geometry_msgs/msg/PointStamped"](header=header_message(stamp_ns, "world"),
                                                   point=xyz)


def force_travel_message(record: ForceTravel) -> Any:
    """The record as a ``std_msgs/msg/Float64MultiArray`` (see the module docstring)."""
    types = typestore().types
    n, dim = len(record), types["std_msgs/msg/MultiArrayDimension"]
    dims = [dim(label=FORCE_TRAVEL_DIMS[0], size=n, stride=2 * n),
            dim(label=FORCE_TRAVEL_DIMS[1], size=2, stride=2)]
    layout = types["std_msgs/msg/MultiArrayLayout"](dim=dims, data_offset=0)
    data = np.column_stack([record.travel_m, record.force_n]).ravel()
    if record.time_s is not None:
        blocks = [np.column_stack([record.time_s, record.travel_m, record.force_n,
                                   np.zeros(n)])]
        for code, phase in ((1.0, record.hold), (2.0, record.unloading)):
            if phase is not None:
                blocks.append(np.column_stack([phase.time_s, phase.travel_m, phase.force_n,
                                               np.full(len(phase), code)]))
        rows = np.vstack(blocks)
        n = len(rows)
        dims = [dim(label=FORCE_TRAVEL_PHASED_DIMS[0], size=n, stride=4 * n),
                dim(label=FORCE_TRAVEL_PHASED_DIMS[1], size=4, stride=4)]
        layout = types["std_msgs/msg/MultiArrayLayout"](dim=dims, data_offset=0)
        data = rows.ravel()
    return types["std_msgs/msg/Float64MultiArray"](layout=layout, data=data)


def write_session_bag(path: Path, *, storage: str, observation: PointCloud,
                      presses: Sequence[PressObservation], stamps_ns: Sequence[int]) -> None:
    """Write the observation and the presses (world frame, float64; colours as a packed
    ``rgb``, none for the robot's points) to a new bag at ``path``."""
    store = typestore()
    # the record's topic only where a press has one: a bag of presses without stays as before
    topics = dict(TOPICS)
    if any(obs.force_travel is not None for obs in presses):
        topics["force_travel"] = OPTIONAL_TOPICS["force_travel"]
    if any(obs.released is not None for obs in presses):
        topics["released"] = OPTIONAL_TOPICS["released"]
    with bag_writer(path, storage) as writer:
        conns = {key: writer.add_connection(topic, msgtype, typestore=store)
                 for key, (topic, msgtype) in topics.items()}  # fmt: skip

        def put(key: str, stamp: int, msg: Any) -> None:
            writer.write(conns[key], stamp, store.serialize_cdr(msg, topics[key][1]))

        def cloud(key: str, stamp: int, points: Any, colors: Any = None) -> None:
            put(key, stamp, array_to_pointcloud2(points, colors=colors, frame_id="world",
                                                 stamp_ns=stamp, dtype="float64"))

        cloud("observation", 0, observation.points, observation.colors)
        for stamp, obs in zip(stamps_ns, presses, strict=True):
            cloud("cloud", stamp, obs.cloud.points, obs.cloud.colors)
            put("wrench", stamp, wrench_message(stamp, "world", obs.contact.force, np.zeros(3)))
            put("tip", stamp, _point_message(stamp, obs.contact.tip_center))
            cloud("robot", stamp, np.vstack(obs.robot_hulls))  # one hull: the parts' common one
            if obs.force_travel is not None:
                put("force_travel", stamp, force_travel_message(obs.force_travel))
            if obs.released is not None:
                cloud("released", stamp, obs.released.points, obs.released.colors)
