"""``check_*`` validators used at the public boundary, and the one validator of settings.

A validator takes the argument's ``name`` as the caller wrote it and the ``value`` that came, and
returns a clean value (arrays: float64, C-contiguous, a copy when converted) or raises
:class:`~deformap.errors.InvalidArgumentError` naming the argument, what was expected and what
came. Every settings dataclass calls :func:`check_settings` first in its ``__post_init__``; the
YAML loader adds no rule of its own.
"""

from __future__ import annotations

import math
import operator
import sys
from collections.abc import Sequence
from dataclasses import Field, field, fields, is_dataclass
from functools import cache
from pathlib import Path
from types import UnionType
from typing import Any, Literal, TypeVar, Union, get_args, get_origin, get_type_hints

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError

__all__ = ["LIMITS", "SettingError", "check_array", "check_finite_scalar", "check_in_range",
           "check_instance", "check_int", "check_limit", "check_path", "check_points",
           "check_positive", "check_rigid_transform", "check_settings", "check_slope_deg",
           "check_vector", "describe", "setting", "setting_metadata"]

_T = TypeVar("_T")


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


def check_array(name: str, value: Any, shape: Sequence[int | None], *, what: str = "floats",
                min_rows: int = 0, finite: bool = True) -> NDArray[np.float64]:
    """Validate a float array of ``shape`` (``None``: any length on that axis) with at least
    ``min_rows`` rows, NaN and infinities refused when ``finite``; ``what`` names the unit or
    meaning in the message (``"points in metres"``)."""
    expected = f"a {_shape_text(shape)} array of finite {what}"
    if isinstance(value, (str, bytes)) or value is None:
        raise InvalidArgumentError(f"`{name}` must be {expected}; got {describe(value)}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(
            f"`{name}` must be {expected}; got {describe(value)} that numpy cannot read ({exc})"
        ) from None
    if arr.dtype == object or not (  # booleans are not numbers: a mask passed as points
        np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)
    ):
        raise InvalidArgumentError(f"`{name}` must be {expected}; got dtype {arr.dtype}")
    if arr.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(arr.shape, shape, strict=False)
    ):
        raise InvalidArgumentError(f"`{name}` must be {expected}; got shape {arr.shape}")
    if arr.ndim and arr.shape[0] < min_rows:
        raise InvalidArgumentError(
            f"`{name}` must have at least {min_rows} rows; got {arr.shape[0]}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if finite and not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise InvalidArgumentError(
            f"`{name}` must be {expected}; got {bad} NaN or infinite value(s)")
    return arr


def check_path(name: str, value: Any) -> Path:
    """Validate a file-system path given as a ``str`` or :class:`~pathlib.Path`."""
    if not isinstance(value, (str, Path)):
        raise InvalidArgumentError(
            f"`{name}` must be a str or pathlib.Path; got {type(value).__name__}")
    return Path(value)


def check_instance(name: str, value: Any, cls: type[_T]) -> _T:
    """Validate an instance of ``cls``."""
    if not isinstance(value, cls):
        article = "an" if cls.__name__[0] in "AEIOU" else "a"
        raise InvalidArgumentError(
            f"`{name}` must be {article} {cls.__name__}; got {type(value).__name__}")
    return value


def check_points(name: str, value: Any, *, min_rows: int = 1) -> NDArray[np.float64]:
    """Validate ``(n, 3)`` points in metres with at least ``min_rows`` rows."""
    return check_array(name, value, (None, 3), what="points (x, y, z) in metres", min_rows=min_rows)


def check_rigid_transform(name: str, value: Any) -> NDArray[np.float64]:
    """Validate a 4×4 homogeneous rigid transform: an orthonormal rotation with determinant +1
    (to 1e-6), a finite translation, last row ``0 0 0 1``."""
    mat = check_array(name, value, (4, 4), what="homogeneous transform entries")
    rot = mat[:3, :3]
    if not (np.allclose(mat[3], [0.0, 0.0, 0.0, 1.0], atol=1e-9)
            and np.allclose(rot @ rot.T, np.eye(3), atol=1e-6) and np.linalg.det(rot) > 0):
        raise InvalidArgumentError(
            f"`{name}` must be a rigid transform (orthonormal rotation with det +1, last row "
            f"0 0 0 1); got rotation det {np.linalg.det(rot):.3g}, last row {mat[3].tolist()}")
    return mat


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


def check_in_range(name: str, value: Any, low: float, high: float) -> float:
    """Validate ``low <= value <= high``."""
    out = check_finite_scalar(name, value)
    if not low <= out <= high:
        raise InvalidArgumentError(f"`{name}` must lie in [{low}, {high}]; got {out}")
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


# -- settings dataclasses -------------------------------------------------------------------------

_BOUNDS = "deformap.bounds"
_DOC = "deformap.doc"
_BOUND_TEXT = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}


class SettingError(InvalidArgumentError):
    """A field of a settings dataclass has a bad value: ``field`` names it (dotted for a rule over
    nested settings; the YAML loader prefixes the section's path), ``detail`` says what was expected
    and what came."""

    def __init__(self, field: str, detail: str) -> None:
        super().__init__(f"`{field}` {detail}")
        self.field = field
        self.detail = detail

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.field, self.detail))


#: Physical bounds of quantities that several settings and files give, each with the reason a
#: message states: ``setting(..., limit=NAME)`` and :func:`check_limit` read them from here, so a
#: probe's tip or a session's pokes obey one rule wherever they come from.
LIMITS: dict[str, dict[str, Any]] = {
    # below a micrometre no camera sees the dent and Hertz contact's radius underflows; a metre is
    # no probe an arm holds
    "tip_radius_m": {"ge": 1e-6, "le": 1.0,
                     "why": "a probe's spherical tip, from a micrometre to a metre"},
    # every poke is a press and a β sweep (seconds), and the fields' and the planner's matrices grow
    # with the pokes
    "pokes": {"ge": 1, "le": 1000, "why": "the pokes one map is made of"},
}


def setting(default: Any, *, gt: float | None = None, ge: float | None = None,
            lt: float | None = None, le: float | None = None, finite: bool = True,
            doc: str | None = None, limit: str | None = None) -> Any:
    """A dataclass field whose bounds and description are declared beside it.

    ``default`` is immutable. Each bound given (``value > gt``, ``>= ge``, ``< lt``, ``<= le``) is
    checked in that order, on every entry of a tuple and on a value that is not ``None``; ``finite``
    refuses NaN and infinities of a float. ``limit`` names an entry of :data:`LIMITS` whose bounds
    (and reason, in the message) apply besides. ``doc``, one line, is what ``deformap config dump``
    shows instead of the class docstring's "Parameters" entry.
    """
    bounds: dict[str, Any] = dict(LIMITS[limit]) if limit is not None else {}
    bounds.update({key: bound for key, bound in (("gt", gt), ("ge", ge), ("lt", lt), ("le", le))
                   if bound is not None})
    metadata: dict[str, Any] = {_BOUNDS: {"finite": finite, **bounds}}
    if doc is not None:
        metadata[_DOC] = doc
    return field(default=default, metadata=metadata)


def setting_metadata(f: Field[Any]) -> tuple[dict[str, Any], str | None]:
    """The bounds and description :func:`setting` declared for the field ``f``."""
    return dict(f.metadata.get(_BOUNDS, {"finite": True})), f.metadata.get(_DOC)


@cache
def _settings_fields(cls: Any) -> tuple[tuple[str, Any, dict[str, Any]], ...]:
    hints = get_type_hints(cls)
    return tuple((f.name, hints[f.name], setting_metadata(f)[0]) for f in fields(cls))


def check_settings(obj: Any) -> None:
    """Check every field of the settings dataclass ``obj`` against its annotation and bounds.

    By annotation: ``bool``, ``int`` (not a bool), ``float`` (finite unless ``setting(finite=False)``),
    ``str``; ``Literal[...]`` one of its choices; ``tuple[X, Y]`` and ``tuple[X, ...]`` a sequence of
    such; ``X | None``; a dataclass an instance of it; any other annotation is left to the class's own
    checks. Then the :func:`setting` bounds. Accepted values are stored in their canonical type (an
    int in a float field as ``float``, a list in a tuple field as a ``tuple``), so that equal settings
    compare and serialise equal. The first bad field raises :class:`SettingError`.
    """
    for name, hint, bounds in _settings_fields(obj.__class__):
        value = getattr(obj, name)
        clean = _check_value(name, value, hint, bounds)
        if clean is not value:
            object.__setattr__(obj, name, clean)


def _check_value(name: str, value: Any, hint: Any, bounds: dict[str, Any]) -> Any:
    origin = get_origin(hint)
    if origin in (Union, UnionType):
        options = [a for a in get_args(hint) if a is not type(None)]
        if value is None and len(options) < len(get_args(hint)):
            return None
        if len(options) == 1:
            return _check_value(name, value, options[0], bounds)
        for option in options:  # no settings field has such a union today; first fit wins
            try:
                return _check_value(name, value, option, bounds)
            except SettingError:
                continue
        raise SettingError(name, f"must be one of the types {options}; got {describe(value)}")
    if origin is Literal:
        choices = get_args(hint)
        if not any(type(value) is type(c) and value == c for c in choices):
            raise SettingError(name, f"must be one of {list(choices)}; got {value!r}")
        return value
    if origin is tuple:
        return _check_tuple(name, value, get_args(hint), bounds)
    if isinstance(hint, type) and is_dataclass(hint):
        if not isinstance(value, hint):
            raise SettingError(name, f"must be a {hint.__name__}; got {describe(value)}")
        return value
    if hint is bool:
        if not isinstance(value, (bool, np.bool_)):
            raise SettingError(name, f"must be True or False; got {describe(value)}")
        return value if isinstance(value, bool) else bool(value)
    if hint is int:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise SettingError(name, f"must be an integer; got {describe(value)}")
        out: int | float = value if type(value) is int else int(value)
        return _check_bounds(name, out, bounds, "an integer ")
    if hint is float:
        if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)
        ):
            raise SettingError(name, f"must be a real number; got {describe(value)}")
        try:
            out = value if type(value) is float else float(value)
        except OverflowError:  # an integer with hundreds of digits
            raise SettingError(name, f"must be a real number within ±{sys.float_info.max:.3g}; "
                               f"got an integer of {len(str(abs(int(value))))} digits") from None
        if bounds.get("finite", True) and not math.isfinite(out):
            raise SettingError(name, f"must be finite; got {out}")
        return _check_bounds(name, out, bounds, "")
    if hint is str:
        if not isinstance(value, str):
            raise SettingError(name, f"must be a string; got {describe(value)}")
        return value
    return value


def _check_tuple(name: str, value: Any, args: tuple[Any, ...], bounds: dict[str, Any]) -> Any:
    if not isinstance(value, (tuple, list, np.ndarray)) or np.ndim(value) != 1:
        raise SettingError(name, f"must be a tuple; got {describe(value)}")
    items = list(value)
    if len(args) == 2 and args[1] is Ellipsis:
        hints = [args[0]] * len(items)
    else:
        if len(items) != len(args):
            raise SettingError(name, f"must have {len(args)} entries; got {len(items)}")
        hints = list(args)
    out = []
    for i, (item, hint) in enumerate(zip(items, hints, strict=True)):
        try:
            out.append(_check_value(name, item, hint, bounds))
        except SettingError as exc:
            raise SettingError(name, f"entry {i} {exc.detail}") from None
    clean = tuple(out)
    if type(value) is tuple and all(a is b for a, b in zip(clean, value, strict=True)):
        return value
    return clean


def _check_bounds(name: str, value: float, bounds: dict[str, Any], kind: str) -> float:
    for key, holds in (("gt", operator.gt), ("ge", operator.ge), ("lt", operator.lt),
                       ("le", operator.le)):
        bound = bounds.get(key)
        if bound is not None and not holds(value, bound):
            why = f" ({bounds['why']})" if "why" in bounds else ""
            raise SettingError(
                name, f"must be {kind}{_BOUND_TEXT[key]} {bound:g}{why}; got {value!r}")
    return value


def check_limit(name: str, value: Any, limit: str) -> Any:
    """Validate a number read outside a settings dataclass (a session file's entry, a count)
    against the :data:`LIMITS` entry ``limit``, by the rules of :func:`check_settings`: a real
    number (an integer where the limit's bounds are integers), finite, within the bounds.

    Raises
    ------
    SettingError
        Naming ``name``, the bound with its reason, and what came.
    """
    bounds = LIMITS[limit]
    integral = all(isinstance(bounds[k], int) for k in _BOUND_TEXT if k in bounds)
    return _check_value(name, value, int if integral else float, {"finite": True, **bounds})
