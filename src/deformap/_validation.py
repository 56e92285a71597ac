"""``check_*`` validators used at the public boundary.

Each returns a clean array (float64, C-contiguous, a copy when it had to convert) or raises
:class:`~deformap.errors.InvalidArgumentError` with a message that names the argument, what was
expected and what came. Internal code calls them once at the entry of a public function and then
trusts its arrays.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError

__all__ = [
    "check_array",
    "check_finite_scalar",
    "check_in_range",
    "check_int",
    "check_points",
    "check_positive",
    "check_slope_deg",
    "check_vector",
    "describe",
]


def describe(value: Any) -> str:
    """Say briefly what ``value`` is, for an error message."""
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    if isinstance(value, (list, tuple)):
        return f"a {type(value).__name__} of length {len(value)}"
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def _shape_text(shape: Sequence[int | None]) -> str:
    dims = ["n" if d is None else str(d) for d in shape]
    return "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"


def check_array(
    name: str,
    value: Any,
    shape: Sequence[int | None],
    *,
    what: str = "floats",
    min_rows: int = 0,
    finite: bool = True,
) -> NDArray[np.float64]:
    """Validate a float array of a given shape; ``None`` in ``shape`` means any size.

    Parameters
    ----------
    name : str
        The argument's name, as the caller wrote it.
    value : array_like
        What came.
    shape : sequence of int or None
        The expected shape; ``None`` matches any length on that axis.
    what : str
        Words for the unit or meaning, used in the message (``"points in metres"``).
    min_rows : int
        Smallest accepted length of the first axis.
    finite : bool
        Refuse NaN and infinite values.
    """
    expected = f"a {_shape_text(shape)} array of finite {what}"
    if isinstance(value, (str, bytes)) or value is None:
        raise InvalidArgumentError(f"`{name}` must be {expected}; got {describe(value)}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(
            f"`{name}` must be {expected}; got {describe(value)} that numpy cannot read ({exc})"
        ) from None
    if arr.dtype == object or not (
        np.issubdtype(arr.dtype, np.floating)
        or np.issubdtype(arr.dtype, np.integer)
        or arr.dtype == np.bool_
    ):
        raise InvalidArgumentError(f"`{name}` must be {expected}; got dtype {arr.dtype}")
    if arr.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(arr.shape, shape, strict=False)
    ):
        raise InvalidArgumentError(f"`{name}` must be {expected}; got shape {arr.shape}")
    if arr.ndim and arr.shape[0] < min_rows:
        raise InvalidArgumentError(
            f"`{name}` must have at least {min_rows} rows; got {arr.shape[0]}"
        )
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if finite and not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise InvalidArgumentError(
            f"`{name}` must be {expected}; got {bad} NaN or infinite value(s)"
        )
    return arr


def check_points(name: str, value: Any, *, min_rows: int = 1) -> NDArray[np.float64]:
    """Validate ``(n, 3)`` points in metres with at least ``min_rows`` rows."""
    return check_array(name, value, (None, 3), what="points (x, y, z) in metres", min_rows=min_rows)


def check_vector(name: str, value: Any, size: int, *, what: str = "floats") -> NDArray[np.float64]:
    """Validate a 1-D vector of ``size`` finite floats."""
    return check_array(name, value, (size,), what=what)


def check_finite_scalar(name: str, value: Any) -> float:
    """Validate a finite real number and return it as ``float``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidArgumentError(f"`{name}` must be a real number; got {describe(value)}")
    out = float(value)
    if not np.isfinite(out):
        raise InvalidArgumentError(f"`{name}` must be finite; got {out}")
    return out


def check_positive(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """Validate a finite number that is > 0 (or >= 0 with ``allow_zero``)."""
    out = check_finite_scalar(name, value)
    if out < 0 or (out == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise InvalidArgumentError(f"`{name}` must be {bound}; got {out}")
    return out


def check_in_range(
    name: str,
    value: Any,
    low: float,
    high: float,
    *,
    closed_high: bool = False,
) -> float:
    """Validate ``low <= value < high`` (``<= high`` with ``closed_high``)."""
    out = check_finite_scalar(name, value)
    ok = low <= out <= high if closed_high else low <= out < high
    if not ok:
        interval = f"[{low}, {high}]" if closed_high else f"[{low}, {high})"
        raise InvalidArgumentError(f"`{name}` must lie in {interval}; got {out}")
    return out


def check_slope_deg(name: str, value: Any) -> float:
    """Validate a surface slope limit in degrees from horizontal, in ``(0, 90]``."""
    out = check_finite_scalar(name, value)
    if not 0.0 < out <= 90.0:
        raise InvalidArgumentError(f"`{name}` must lie in (0, 90] degrees; got {out}")
    return out


def check_int(name: str, value: Any, *, minimum: int | None = None) -> int:
    """Validate an integer (not a bool), optionally ``>= minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InvalidArgumentError(f"`{name}` must be an integer; got {describe(value)}")
    out = int(value)
    if minimum is not None and out < minimum:
        raise InvalidArgumentError(f"`{name}` must be an integer >= {minimum}; got {out}")
    return out
