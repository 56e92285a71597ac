"""Ground truth of a session recorded from a simulation, ``ground_truth.npz`` (never pickled):
``xs`` (nx,), ``ys`` (ny,) cell centres [m], ``labels`` (ny, nx) integers and ``hardness``
(ny, nx) [N] (``inf`` rigid, ``nan`` no region)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._files import atomic_path
from deformap._validation import check_array, check_instance
from deformap.cloud.io import load_npz_arrays, path_kind
from deformap.errors import FileFormatError, InvalidArgumentError

__all__ = ["GroundTruth", "read_ground_truth", "write_ground_truth"]


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Region labels and hardness on a regular grid (``xs``, ``ys`` increasing), looked up by
    nearest cell; ``hardness`` is constant over each label."""

    xs: NDArray[np.float64]
    ys: NDArray[np.float64]
    labels: NDArray[np.int64]
    hardness: NDArray[np.float64]

    def __post_init__(self) -> None:
        xs = check_array("xs", self.xs, (None,), what="metres", min_rows=1)
        ys = check_array("ys", self.ys, (None,), what="metres", min_rows=1)
        for name, axis in (("xs", xs), ("ys", ys)):
            if np.any(np.diff(axis) <= 0):
                raise InvalidArgumentError(f"`{name}` must be strictly increasing")
        labels = np.asarray(self.labels)
        if labels.shape != (ys.size, xs.size) or labels.dtype.kind not in "iu":
            raise InvalidArgumentError(
                f"`labels` must be ({ys.size}, {xs.size}) integers; got shape {labels.shape} "
                f"and dtype {labels.dtype}")
        hard = check_array("hardness", self.hardness, (ys.size, xs.size), what="newtons",
                           finite=False)  # fmt: skip
        if np.any(hard <= 0) or np.any(np.isneginf(hard)):
            raise InvalidArgumentError("`hardness` must be > 0 (inf for rigid, nan for none)")
        for label in np.unique(labels):
            values = hard[labels == label]
            if not (np.all(values == values[0]) or np.all(np.isnan(values))):
                raise InvalidArgumentError(
                    f"`hardness` must be constant over each label; label {label} has "
                    f"{np.unique(values).size} values")
        for name, value in (("xs", xs), ("ys", ys), ("labels", labels.astype(np.int64)),
                            ("hardness", hard)):  # fmt: skip
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def _cells(self, xs: Any, ys: Any) -> Any:
        """``np.ix_`` of the stored cells nearest the grid ``xs`` × ``ys``."""
        qx = check_array("xs", xs, (None,), what="metres")
        qy = check_array("ys", ys, (None,), what="metres")
        return np.ix_(np.abs(self.ys[None, :] - qy[:, None]).argmin(axis=1),
                      np.abs(self.xs[None, :] - qx[:, None]).argmin(axis=1))

    def ground_truth_labels(self, xs: Any, ys: Any) -> NDArray[np.int64]:
        """``(ny, nx)`` labels at the grid ``xs`` × ``ys`` (nearest stored cell)."""
        return self.labels[self._cells(xs, ys)]

    def ground_truth_hardness(self, xs: Any, ys: Any) -> NDArray[np.float64]:
        """``(ny, nx)`` hardness in newtons at the grid ``xs`` × ``ys`` (nearest stored cell)."""
        return self.hardness[self._cells(xs, ys)]


def write_ground_truth(path: str | Path, truth: GroundTruth) -> None:
    """Write ``truth`` to an NPZ archive (compressed, no pickle), atomically
    (:func:`deformap._files.atomic_path`)."""
    check_instance("truth", truth, GroundTruth)
    with atomic_path(path) as tmp, open(tmp, "xb") as fh:
        np.savez_compressed(fh, xs=truth.xs, ys=truth.ys, labels=truth.labels,
                            hardness=truth.hardness)  # fmt: skip


def read_ground_truth(path: str | Path) -> GroundTruth:
    """Read a ``ground_truth.npz``; every problem is a FileFormatError naming the file."""
    p = Path(path)
    if path_kind(p) != "file":
        raise FileFormatError(f"{p}: no such file (the session's `ground_truth`)")
    arrays = load_npz_arrays(p, "the ground-truth NPZ archive")
    missing = sorted({"xs", "ys", "labels", "hardness"} - set(arrays))
    if missing:
        raise FileFormatError(f"{p}: ground truth lacks array(s) {missing} (has {sorted(arrays)})")
    try:
        return GroundTruth(arrays["xs"], arrays["ys"], arrays["labels"], arrays["hardness"])
    except InvalidArgumentError as exc:
        raise FileFormatError(f"{p}: {exc}") from None
