"""Textures of the simulated world: brightness patterns in metres on a surface.

Each texture maps ``(n, 2)`` surface coordinates ``uv`` in metres to ``(n,)`` values in
``[-1, 1]`` with a mean near 0 (``plain``: 0 everywhere):

* ``noise``: fractal value noise (Perlin 1985; Ebert et al. 2003, ch. 2), random values on a
  lattice of pitch ``scale_m`` interpolated by smoothstep, over three octaves of half the pitch
  and half the weight each.
* ``stripes``: a square wave of period ``scale_m`` across the direction ``angle_deg``.
* ``photo``: a grey photograph bundled with scikit-image (``brick``, ``grass``, ``gravel``), one
  per ``scale_m`` square, repeated, sampled bilinearly, centred and scaled into ``[-1, 1]``.

References
----------
Perlin, K. (1985). An image synthesizer. SIGGRAPH '85, 287–296.
Ebert, D. S., et al. (2003). Texturing and Modeling: A Procedural Approach, 3rd ed.
"""

from __future__ import annotations

from functools import cache
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

__all__ = ["TEXTURES", "Photo", "Texture", "texture_values"]

Texture = Literal["plain", "noise", "stripes", "photo"]
TEXTURES: tuple[str, ...] = get_args(Texture)
Photo = Literal["brick", "grass", "gravel"]

_LATTICE = 256  # lattice values per side; the noise repeats every 256 pitches
_OCTAVES = 3


@cache
def _lattice(seed: int) -> NDArray[np.float64]:
    values = np.random.default_rng(seed).uniform(-1.0, 1.0, size=(_LATTICE, _LATTICE))
    values.setflags(write=False)
    return values


@cache
def _photo(name: str) -> NDArray[np.float64]:
    try:
        from skimage import data
    except ImportError as exc:  # a dependency of deformap: only a broken install lacks it
        raise ImportError("the `photo` texture needs scikit-image: pip install "
                          "'scikit-image>=0.22,<1'") from exc
    grey = np.asarray(getattr(data, name)(), dtype=float)
    centred = grey - grey.mean()
    out = centred / np.abs(centred).max()
    out.setflags(write=False)
    return out


def _bilinear(image: NDArray[np.float64], p: NDArray[np.float64], *, smooth: bool
              ) -> NDArray[np.float64]:
    """``image`` sampled at the ``(n, 2)`` pixel coordinates ``p`` (column, row), repeated."""
    rows, cols = image.shape
    base = np.floor(p)
    f = p - base
    if smooth:
        f = f * f * (3.0 - 2.0 * f)
    i0 = base[:, 0].astype(np.int64) % cols
    j0 = base[:, 1].astype(np.int64) % rows
    i1, j1 = (i0 + 1) % cols, (j0 + 1) % rows
    top = image[j0, i0] * (1 - f[:, 0]) + image[j0, i1] * f[:, 0]
    bottom = image[j1, i0] * (1 - f[:, 0]) + image[j1, i1] * f[:, 0]
    return np.asarray(top * (1 - f[:, 1]) + bottom * f[:, 1])


def _noise(uv: NDArray[np.float64], scale_m: float, seed: int) -> NDArray[np.float64]:
    lattice = _lattice(seed)
    total = np.zeros(len(uv))
    weight = 1.0
    for octave in range(_OCTAVES):
        # each octave shifted by a fraction of the lattice so that their knots do not coincide
        p = uv / (scale_m / 2**octave) + 37.17 * octave
        total += weight * _bilinear(lattice, p, smooth=True)
        weight *= 0.5
    return total / (2.0 - 2.0 ** (1 - _OCTAVES))  # the weights' sum: values stay in [-1, 1]


def texture_values(texture: str, uv: NDArray[np.float64], *, scale_m: float,
                   angle_deg: float = 0.0, photo: str = "brick", seed: int = 0
                   ) -> NDArray[np.float64]:
    """``(n,)`` values in ``[-1, 1]`` of ``texture`` at the ``(n, 2)`` coordinates ``uv`` (metres;
    the parameters as in the module docstring, ``seed`` drawing the noise lattice)."""
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    if texture == "plain":
        return np.zeros(len(uv))
    if texture == "noise":
        return _noise(uv, scale_m, seed)
    if texture == "stripes":
        a = np.radians(angle_deg)
        phase = (uv @ np.array([np.cos(a), np.sin(a)])) / scale_m
        return np.where(np.mod(phase, 1.0) < 0.5, 1.0, -1.0)
    if texture == "photo":
        image = _photo(photo)
        return _bilinear(image, uv / scale_m * image.shape[0], smooth=False)
    raise ValueError(f"unknown texture {texture!r}; one of {list(TEXTURES)}")
