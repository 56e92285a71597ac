"""The transforms of a bag (``/tf`` and ``/tf_static``), looked up at any time.

Each TransformStamped gives ``child2parent`` at its stamp. A lookup composes the edges from each
frame up to their common ancestor, each interpolated at the times asked as ``tf2`` does
(translation linearly, rotation by Slerp); a dynamic edge needs a sample within the tolerance of
each time, a static one holds at all times.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.cloud.io._bag_reader import header_stamp_ns
from deformap.errors import FileFormatError

__all__ = ["MAX_TRANSLATION_M", "TransformTree"]

#: The farthest [m] a transform may move a frame (a UTM map frame holds a few 10⁶ m): a larger
#: or non-finite translation is a damaged message.
MAX_TRANSLATION_M = 1e9


@dataclass
class _Edge:
    parent: str
    static: bool
    stamps: list[int] = field(default_factory=list)
    translations: list[tuple[float, float, float]] = field(default_factory=list)
    quaternions: list[tuple[float, float, float, float]] = field(default_factory=list)


@dataclass(frozen=True)
class _Series:
    stamps: NDArray[np.int64]
    translations: NDArray[np.float64]
    rotations: Any  # scipy Rotation of len(stamps)


class TransformTree:
    """The frames of ``/tf`` (``topic``, named in messages) and ``/tf_static`` over time;
    ``tolerance_ns`` is the largest gap to a dynamic edge's nearest sample, and times in messages
    are seconds after ``origin_ns``."""

    def __init__(self, topic: str, tolerance_ns: int, origin_ns: int = 0) -> None:
        self.topic = topic
        self.tolerance_ns = tolerance_ns
        self.origin_ns = origin_ns
        self._edges: dict[str, _Edge] = {}
        self._series: dict[str, _Series] = {}

    def add(self, msg: Any, *, static: bool, where: str) -> None:
        """Add every transform of a ``tf2_msgs/msg/TFMessage``."""
        for tf in msg.transforms:
            child, parent = str(tf.child_frame_id), str(tf.header.frame_id)
            q, t = tf.transform.rotation, tf.transform.translation
            quat = (float(q.x), float(q.y), float(q.z), float(q.w))
            trans = (float(t.x), float(t.y), float(t.z))
            # ranges first (NaN fails them), so that the norm cannot overflow
            in_range = (all(abs(v) <= 1.0 + 1e-3 for v in quat)
                        and all(abs(v) <= MAX_TRANSLATION_M for v in trans))  # fmt: skip
            if not in_range or abs(float(np.linalg.norm(quat)) - 1) > 1e-3:
                raise FileFormatError(
                    f"{where}: transform {parent!r} -> {child!r} must have a finite translation "
                    f"within {MAX_TRANSLATION_M:g} m and a unit quaternion; got translation "
                    f"{trans}, quaternion {quat}")
            edge = self._edges.setdefault(child, _Edge(parent=parent, static=static))
            if edge.parent != parent:
                raise FileFormatError(
                    f"{where}: frame {child!r} has two parents, {edge.parent!r} and {parent!r}")
            edge.static = edge.static and static
            edge.stamps.append(header_stamp_ns(tf.header))
            edge.translations.append(trans)
            edge.quaternions.append(quat)
        self._series.clear()

    @property
    def frames(self) -> list[str]:
        """Every frame named, child or parent."""
        return sorted(set(self._edges) | {e.parent for e in self._edges.values()})

    def rigid_group(self, frame: str) -> list[str]:
        """The frames joined to ``frame`` by static transforms only (``frame`` included): the
        parts of one rigid body, in name order."""
        group, todo = {frame}, [frame]
        while todo:
            f = todo.pop()
            near = [e.parent for c, e in self._edges.items() if c == f and e.static]
            near += [c for c, e in self._edges.items() if e.parent == f and e.static]
            for g in near:
                if g not in group:
                    group.add(g)
                    todo.append(g)
        return sorted(group)

    def moves(self, frame: str) -> bool:
        """Whether a dynamic transform lies between ``frame`` and its root."""
        return any(not self._edges[c].static for c in self._chain(frame)[:-1])

    def root(self, frame: str) -> str:
        """The topmost ancestor of ``frame``."""
        return self._chain(frame)[-1]

    def _chain(self, frame: str) -> list[str]:
        """``frame`` and its ancestors up to the root."""
        chain = [frame]
        while chain[-1] in self._edges:
            chain.append(self._edges[chain[-1]].parent)
            if len(chain) > len(self._edges) + 1:
                raise FileFormatError(f"{self.topic}: the frames above {frame!r} form a loop")
        return chain

    def _edge_series(self, child: str) -> _Series:
        if child not in self._series:
            from scipy.spatial.transform import Rotation

            edge = self._edges[child]
            order = np.argsort(np.asarray(edge.stamps, dtype=np.int64), kind="stable")
            stamps = np.asarray(edge.stamps, dtype=np.int64)[order]
            keep = np.concatenate([[True], np.diff(stamps) > 0])  # a repeated stamp: first kept
            rot = Rotation.from_quat(np.asarray(edge.quaternions)[order][keep])
            self._series[child] = _Series(stamps[keep],
                                          np.asarray(edge.translations)[order][keep], rot)
        return self._series[child]

    def _edge_at(self, child: str, times_ns: NDArray[np.int64], what: str
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
        """Rotations ``(n, 3, 3)`` and translations ``(n, 3)`` of ``child2parent`` at the times."""
        from scipy.spatial.transform import Slerp

        edge, series = self._edges[child], self._edge_series(child)
        n = times_ns.size
        if not edge.static:
            self._check_gap(child, series.stamps, times_ns, what)
        if edge.static or series.stamps.size == 1:
            mat = series.rotations[-1].as_matrix()
            return np.broadcast_to(mat, (n, 3, 3)).copy(), np.tile(series.translations[-1], (n, 1))
        t = np.clip(times_ns, series.stamps[0], series.stamps[-1])
        rel = (t - series.stamps[0]).astype(np.float64)
        knots = (series.stamps - series.stamps[0]).astype(np.float64)
        rot = Slerp(knots, series.rotations)(rel).as_matrix()
        trans = np.column_stack([np.interp(rel, knots, series.translations[:, i])
                                 for i in range(3)])  # fmt: skip
        return rot, trans

    def _check_gap(self, child: str, stamps: NDArray[np.int64], times: NDArray[np.int64],
                   what: str) -> None:  # fmt: skip
        idx = np.clip(np.searchsorted(stamps, times), 1, max(stamps.size - 1, 1))
        before = stamps[np.maximum(idx - 1, 0)]
        after = stamps[np.minimum(idx, stamps.size - 1)]
        gap = np.minimum(np.abs(times - before), np.abs(times - after))
        worst = int(np.argmax(gap))
        if gap[worst] > self.tolerance_ns:
            raise FileFormatError(
                f"{what}: topic {self.topic!r} has no transform {self._edges[child].parent!r} -> "
                f"{child!r} within {self.tolerance_ns / 1e9:g} s of t = "
                f"{(times[worst] - self.origin_ns) / 1e9:.3f} s "
                f"(nearest {gap[worst] / 1e9:.3f} s away)")

    def lookup(self, target: str, source: str, times_ns: Any, *, what: str
               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
        """``source2target`` at each time: rotations ``(n, 3, 3)`` and translations ``(n, 3)``,
        ``p_target = R @ p_source + t``; ``what`` starts every refusal.

        Raises
        ------
        FileFormatError
            An unknown frame, two frames not connected, or a dynamic edge without a sample
            within the tolerance of a time.
        """
        times = np.atleast_1d(np.asarray(times_ns, dtype=np.int64))
        for frame in (target, source):
            if frame not in self.frames:
                raise FileFormatError(
                    f"{what}: no frame {frame!r} on {self.topic!r} or its static topic "
                    f"(frames: {self.frames})")

        up_source, up_target = self._chain(source), self._chain(target)
        if up_source[-1] != up_target[-1]:
            raise FileFormatError(
                f"{what}: frames {source!r} and {target!r} are not connected by the transforms "
                f"(roots {up_source[-1]!r} and {up_target[-1]!r})")
        common = next(f for f in up_source if f in up_target)
        rs, ts = self._to_ancestor(up_source, common, times, what)
        rt, tt = self._to_ancestor(up_target, common, times, what)
        # source2target = inverse(target2common) @ source2common
        rt_inv = np.transpose(rt, (0, 2, 1))
        rot = rt_inv @ rs
        trans = np.einsum("nij,nj->ni", rt_inv, ts - tt)
        return rot, trans

    def _to_ancestor(self, chain: list[str], ancestor: str, times: NDArray[np.int64], what: str
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
        n = times.size
        rot, trans = np.broadcast_to(np.eye(3), (n, 3, 3)).copy(), np.zeros((n, 3))
        for child in chain[: chain.index(ancestor)]:
            r_edge, t_edge = self._edge_at(child, times, what)
            # child2grandparent = edge @ (frame2child): apply the edge after what came before
            trans = np.einsum("nij,nj->ni", r_edge, trans) + t_edge
            rot = r_edge @ rot
        return rot, trans
