"""A raw bag's press read against its camera: a tip frame that never moves, and a record whose
travel and the dent the camera sees disagree (:class:`deformap.replay.RawBagReader`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from deformap.cloud import PointCloud, points_in_hull
from deformap.environment import TRAVEL_BACKWARDS_TOLERANCE_M, ForceTravel
from deformap.errors import DeformapError
from deformap.replay._rawfind import BagDiscovery

__all__ = ["DENT_SIGMAS", "CameraCheck"]

#: A dent the camera sees lies this many of its σ below the observation (a 1e-4 chance of noise).
DENT_SIGMAS = 4.0

#: A Hertz dent of travel δ sinks the surface within two tip radii of the contact by about an
#: eighth of δ or more on average (the visible part, outside the contact radius √(Rδ)).
HERTZ_DISC_FRACTION = 0.125

#: A tip frame whose poses through a press's rise all lie within this [m] did not move: a
#: measured pose jitters by its encoders' noise (micrometres), a commanded one does not.
STILL_TIP_M = 1e-9


class CameraCheck(BagDiscovery):
    """The checks of a press against the camera; :class:`RawBagReader` gives the observation."""

    tip_still: bool  # :meth:`_tip_still`, found once when the bag is opened

    def observation(self) -> PointCloud:
        """The surface before the presses (:meth:`RawBagReader.observation`)."""
        raise NotImplementedError

    def _tip_still(self) -> bool:
        """Whether the tip frame stays within :data:`STILL_TIP_M` over the second half of every
        usable press's rise (first contact to the hold): a commanded pose. A measured one moves
        into a soft surface, or by its encoders' noise; a bag of presses on rigid surfaces only,
        recorded without that noise, reads as still too, and loses its records, not its map."""
        usable = [p for p in self.presses if p.error is None and p.hold_start > p.start + 1]
        for press in usable:
            stamps = self.wrench_ns[(press.start + press.hold_start) // 2: press.hold_start]
            try:
                _, tips = self.tree.lookup(self.world_frame, self.tip_frame, stamps, what="")
            except DeformapError:
                return False  # the press's own reading names what is missing
            if float(np.ptp(tips, axis=0).max()) > STILL_TIP_M:
                return False
        return bool(usable)

    def against_camera(self, notes: dict[str, str], record: ForceTravel | None,
                       travel: NDArray[np.float64], cloud: PointCloud,
                       contact: NDArray[np.float64], robot: tuple[NDArray[np.float64], ...]
                       ) -> ForceTravel | None:
        """``record``, or ``None`` when the tip never moves (:meth:`_tip_still`) or the record
        shows no travel where the camera sees a dent; ``notes`` gain the camera's dent, the
        record's travel and any disagreement (also a record with travel the camera sees no dent
        for, which is kept)."""
        dent, dent_std = self._camera_dent(cloud, contact, robot)
        moved = float(travel[-1]) if travel.size else 0.0
        notes["camera_dent_m"] = f"{dent:.5f} ± {dent_std:.5f}"
        notes["record_travel_m"] = f"{moved:.5f}"
        seen = dent > DENT_SIGMAS * dent_std and dent > TRAVEL_BACKWARDS_TOLERANCE_M
        if record is not None and self.tip_still:
            notes["disagreement"] = (
                f"the tip frame {self.tip_frame!r} did not move at all while the force rose, in "
                "any press (not even by encoder noise: a commanded pose, not the measured one?); "
                "its travel cannot tell a rigid surface from a soft one, so the record is "
                "not used: β from the camera alone, no modulus")
            notes["force_travel"] = notes["disagreement"]
            record = None
        elif record is not None and moved <= TRAVEL_BACKWARDS_TOLERANCE_M and seen:
            notes["disagreement"] = (
                f"the record shows no travel ({moved * 1e3:.2f} mm) but the camera sees a dent of "
                f"{dent * 1e3:.2f} ± {dent_std * 1e3:.2f} mm around the contact; is the tip frame "
                f"{self.tip_frame!r} the measured pose (a commanded one does not move)? The "
                "record is not used: β from the camera alone, no modulus")
            notes["force_travel"] = notes["disagreement"]
            record = None
        elif record is not None and moved > 4 * TRAVEL_BACKWARDS_TOLERANCE_M and (
                dent + DENT_SIGMAS * dent_std < moved * HERTZ_DISC_FRACTION / 2):
            notes["disagreement"] = (
                f"the record shows {moved * 1e3:.2f} mm of travel but the camera sees no dent "
                f"({dent * 1e3:.2f} ± {dent_std * 1e3:.2f} mm) within two tip radii of the "
                "contact: a camera too coarse to see it there, or its extrinsics or the tip frame "
                "are off")
        return record

    def _camera_dent(self, cloud: PointCloud, contact: NDArray[np.float64],
                     robot: tuple[NDArray[np.float64], ...]) -> tuple[float, float]:
        """How far [m] the camera sees the surface sink within two tip radii of ``contact``, and
        its σ: each point of ``cloud`` there (below the tip's top, outside the robot's hulls)
        paired with the observation's point nearest in ``x``–``y`` (the same surface patch for a
        still camera); the mean of their height differences, a fifth cut off at each end (the
        robot's edges, a block's side), σ that mean's (a mean, not a median: a depth camera's
        heights come in disparity steps of millimetres, which a median keeps)."""
        from scipy.spatial import cKDTree

        radius, before = self.config.tip_radius_m, self.observation().points
        pts = cloud.points
        r = np.linalg.norm(pts[:, :2] - contact[:2], axis=1)
        # below the tip's top: what is higher there is the probe, the hand or the arm
        near = pts[(r <= 2 * radius) & (pts[:, 2] <= contact[2] + 2 * radius)]
        if len(near):
            near = near[~points_in_hull(near, robot)]
        if len(near) < 3:
            return 0.0, float("inf")
        gap, j = cKDTree(before[:, :2]).query(near[:, :2])
        dz = np.sort((before[j, 2] - near[:, 2])[gap <= radius / 2])
        cut = len(dz) // 5
        kept = dz[cut: len(dz) - cut]
        if len(kept) < 3:
            return 0.0, float("inf")
        return float(kept.mean()), float(kept.std(ddof=1) / np.sqrt(len(kept)))
