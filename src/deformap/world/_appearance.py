"""How a surface of the simulated world looks: a colour, a texture and, optionally, a second look
painted over part of it.

An :class:`Appearance`'s albedo at a point is its sRGB ``color`` turned linear (IEC 61966-2-1)
times ``1 + amplitude · t``, ``t`` in ``[-1, 1]`` its texture (:mod:`deformap.world._texture`) at
the point's surface coordinates in metres (``(x, y)`` on a face that looks up, ``(s, z)`` on a side
face). A :class:`Split` paints another look over a half-plane of the table: a look boundary that
is no material boundary. :func:`lambert` shades an albedo: ambient plus Lambert's cosine law for
one distant light (Foley et al. 1996, §16.1), 1 on a face that looks straight up.

References
----------
IEC 61966-2-1:1999. Default RGB colour space — sRGB.
Foley, J. D., et al. (1996). Computer Graphics: Principles and Practice, 2nd ed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from deformap._validation import SettingError, check_settings, setting
from deformap.world._texture import Photo, Texture, texture_values

__all__ = ["DEFAULT_APPEARANCE", "DEFAULT_TABLE_APPEARANCE", "Appearance", "Split",
           "appearance_from_dict", "lambert", "linear_to_srgb", "parse_color", "srgb_to_linear"]

RGB = tuple[float, float, float]


def parse_color(value: Any, name: str = "color") -> Any:
    """An sRGB colour ``"#rrggbb"`` as ``(r, g, b)`` in ``[0, 1]``; anything else unchanged."""
    if not isinstance(value, str):
        return value
    text = value.strip()
    digits = text[1:] if text.startswith("#") else ""
    try:
        if len(digits) != 6:
            raise ValueError
        return tuple(int(digits[i:i + 2], 16) / 255.0 for i in (0, 2, 4))
    except ValueError:
        raise SettingError(name, f"must be '#rrggbb' or [r, g, b] in [0, 1]; got {value!r}"
                           ) from None


def _hex(color: RGB) -> str | None:
    """``"#rrggbb"`` when the colour is exactly such a one, else None."""
    levels = [round(c * 255) for c in color]
    if all(abs(level / 255.0 - c) < 1e-12 for level, c in zip(levels, color, strict=True)):
        return "#" + "".join(f"{level:02x}" for level in levels)
    return None


def srgb_to_linear(c: NDArray[np.float64]) -> NDArray[np.float64]:
    """sRGB values in ``[0, 1]`` to linear light (IEC 61966-2-1)."""
    c = np.asarray(c, dtype=float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: NDArray[np.float64]) -> NDArray[np.float64]:
    """Linear light (clipped to ``[0, 1]``) to sRGB values (IEC 61966-2-1)."""
    c = np.clip(np.asarray(c, dtype=float), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


@dataclass(frozen=True, kw_only=True)
class Appearance:
    """The look of a surface (module docstring): a ``texture`` of :mod:`deformap.world._texture`
    (``photo`` names scikit-image's sample photograph) and an optional ``split``."""

    color: tuple[float, float, float] = setting((0.6, 0.6, 0.6), ge=0.0, le=1.0,
                                                doc="base colour, sRGB in [0, 1]")
    texture: Texture = "plain"
    # finer than a millimetre no camera over a table resolves; coarser than the table is no pattern
    scale_m: float = setting(0.02, ge=0.001, le=10.0, doc="texture pitch, period or photo side [m]")
    amplitude: float = setting(0.15, ge=0.0, le=1.0, doc="largest relative change of brightness")
    angle_deg: float = setting(0.0, ge=-360.0, le=360.0, doc="stripes' normal from the x axis")
    photo: Photo = "brick"
    seed: int = setting(0, ge=0, le=2**32 - 1, doc="seed of the noise lattice")
    split: Split | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "color", parse_color(self.color))
        check_settings(self)
        if self.split is not None and self.split.look.split is not None:
            raise SettingError("split", "must paint a look without a split of its own")

    def albedo(self, xy: NDArray[np.float64], uv: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n, 3)`` linear albedo at table-plane positions ``xy`` (which the split reads) and
        surface coordinates ``uv`` (both ``(n, 2)``, metres)."""
        t = texture_values(self.texture, uv, scale_m=self.scale_m, angle_deg=self.angle_deg,
                           photo=self.photo, seed=self.seed)
        out = srgb_to_linear(np.array(self.color))[None, :] * (1.0 + self.amplitude * t)[:, None]
        if self.split is not None:
            other = self.split.covers(xy)
            if np.any(other):
                out[other] = self.split.look.albedo(xy[other], uv[other])
        return np.asarray(out)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"color": _hex(self.color) or list(self.color),
                               "texture": self.texture}
        if self.texture != "plain":
            out.update(scale_m=self.scale_m, amplitude=self.amplitude)
            if self.texture == "stripes":
                out["angle_deg"] = self.angle_deg
            elif self.texture == "photo":
                out["photo"] = self.photo
            else:
                out["seed"] = self.seed
        if self.split is not None:
            out["split"] = self.split.to_dict()
        return out


@dataclass(frozen=True, kw_only=True)
class Split:
    """A second ``look`` (without a split of its own) over the half-plane
    ``(p − through) · (cos a, sin a) > 0``, ``a = normal_deg``."""

    through: tuple[float, float] = setting((0.0, 0.0), ge=-10.0, le=10.0, doc="a point [m]")
    normal_deg: float = setting(0.0, ge=-360.0, le=360.0, doc="the painted side's direction")
    look: Appearance

    def __post_init__(self) -> None:
        check_settings(self)

    def covers(self, xy: NDArray[np.float64]) -> NDArray[np.bool_]:
        a = np.radians(self.normal_deg)
        return np.asarray((xy - np.array(self.through)) @ np.array([np.cos(a), np.sin(a)]) > 0)

    def to_dict(self) -> dict[str, Any]:
        return {"through": list(self.through), "normal_deg": self.normal_deg, **self.look.to_dict()}


#: A block without an appearance: neutral grey, plain.
DEFAULT_APPEARANCE = Appearance()
#: The table without an appearance: a darker warm grey, plain, so that blocks stand out on it.
DEFAULT_TABLE_APPEARANCE = Appearance(color=parse_color("#5a5550"))

_KEYS = {"color", "texture", "scale_m", "amplitude", "angle_deg", "photo", "seed", "split"}
_SPLIT_KEYS = {"through", "normal_deg"}


def appearance_from_dict(data: Any, where: str) -> Appearance:
    """An :class:`Appearance` from its YAML mapping (``split`` holds ``through``, ``normal_deg``
    and the painted look's own keys); a ValueError names ``where`` and the bad key or value."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: must be a mapping; got {type(data).__name__}")
    extra = sorted(set(data) - _KEYS)
    if extra:
        raise ValueError(f"{where}: unknown key(s) {extra}; allowed: {sorted(_KEYS)}")
    fields = dict(data)
    split = fields.pop("split", None)
    try:
        if split is not None:
            if not isinstance(split, dict):
                raise ValueError(f"{where}.split: must be a mapping; got {type(split).__name__}")
            extra = sorted(set(split) - (_KEYS | _SPLIT_KEYS) | ({"split"} & set(split)))
            if extra:
                raise ValueError(f"{where}.split: unknown key(s) {extra}; allowed: "
                                 f"{sorted((_KEYS - {'split'}) | _SPLIT_KEYS)}")
            look = {k: v for k, v in split.items() if k not in _SPLIT_KEYS}
            fields["split"] = Split(look=Appearance(**look),
                                    **{k: v for k, v in split.items() if k in _SPLIT_KEYS})
        return Appearance(**fields)
    except SettingError as exc:
        raise ValueError(f"{where}: {exc}") from None


def lambert(normals: NDArray[np.float64], light: NDArray[np.float64], ambient: float
            ) -> NDArray[np.float64]:
    """``(n,)`` shading of faces of unit ``normals`` ``(n, 3)`` lit from the unit direction
    ``light`` with the ``ambient`` share (module docstring)."""
    diffuse = np.clip(normals @ light, 0.0, None)
    return np.asarray((ambient + (1.0 - ambient) * diffuse) / (ambient + (1.0 - ambient) * light[2]))
