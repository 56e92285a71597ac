"""A PrimeSense-like depth camera: ray casting plus the sensor's error model.

The camera sits ``height_m`` above the table on the workspace's ``-y`` side and looks at the
workspace centre ``pitch_deg`` below the horizontal. Each pixel casts one ray
(:mod:`deformap.world._raycast`) into the scene. Then, per pixel, in this order:

1. no return when the ray meets the surface at more than ``grazing_deg`` from its normal;
2. flying pixels: where the depth jumps by more than ``edge_jump_m`` to the right or lower
   neighbour, with probability ``flying_probability`` the pixel takes a depth drawn uniformly
   between the two (structured-light mixed returns);
3. axial noise ``σ_z = sigma_base + sigma_quadratic·(z − sigma_reference)²`` (z along the axis);
4. disparity quantisation: ``z = f b / (round(f b / z · subpixel) / subpixel)``.

Points are returned in the world frame, one per valid pixel in row-major order. The colour sensor
(:meth:`DepthCamera.sensor_colors`) applies to the linear light reaching each pixel vignetting
(``1 − vignetting · r²``, ``r`` the distance from the image centre over the half-diagonal; Goldman
2010), white-balance gains, the sRGB encoding, Gaussian noise ``color_noise`` per channel and
clipping to ``[0, 1]``.

References
----------
Khoshelham, K., Elberink, S. O. (2012). Accuracy and resolution of Kinect depth data. Sensors 12(2).
Nguyen, C. V., Izadi, S., Lovell, D. (2012). Modeling Kinect sensor noise. 3DIMPVT.
Grunnet-Jepsen, A., et al. (2018). Tuning Intel RealSense D400 depth cameras. Intel white paper.
Goldman, D. B. (2010). Vignette and exposure calibration and compensation. IEEE TPAMI 32(12).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import numpy as np
import trimesh
from numpy.typing import NDArray

from deformap._validation import check_settings, setting
from deformap.errors import InvalidArgumentError
from deformap.world._appearance import linear_to_srgb
from deformap.world._raycast import cast_rays

__all__ = ["CAMERA_PRESETS", "CameraConfig", "DepthCamera", "Frame", "camera_preset"]


@dataclass(frozen=True, kw_only=True)
class CameraConfig:
    """Settings of the simulated depth camera (defaults: PrimeSense Carmine 1.08 at 45°).

    Parameters
    ----------
    width, height : int
        Pixels per row and per column of the image, one ray each.
    fov_deg : (2,) float, degrees
        Horizontal and vertical field of view, each in ``(0, 180)``.
    height_m : float, metres
        Height of the optical centre above the table.
    pitch_deg : float, degrees
        Angle of the optical axis below the horizontal, in ``(0, 90]`` (90: straight down); the
        axis passes through the workspace centre.
    noise : bool
        False turns off flying pixels, axial noise and quantisation.
    sigma_base_m, sigma_quadratic_m, sigma_reference_m : float, metres
        The terms of the axial noise ``σ_z = sigma_base + sigma_quadratic·(z − sigma_reference)²``.
    baseline_m : float, metres
        Projector–sensor baseline ``b`` of the disparity.
    subpixel : float
        Disparity resolution is ``1 / subpixel`` pixel.
    grazing_deg : float, degrees
        No return beyond this angle between the ray and the surface normal, in ``(0, 90]``.
    edge_jump_m : float, metres
        Depth jump to a neighbour that makes a pixel a flying-pixel candidate.
    flying_probability : float
        Probability in ``[0, 1]`` that a candidate pixel flies.
    use_embree : bool
        Use trimesh's Embree ray caster when ``embreex`` is installed.
    """

    # a ray per pixel, with a few float64 arrays each: 4096 × 4096 rays is gigabytes per frame
    width: int = setting(640, ge=1, le=4096)
    height: int = setting(480, ge=1, le=4096)
    fov_deg: tuple[float, float] = setting((58.0, 45.0), gt=0.0, lt=180.0)
    height_m: float = setting(0.80, gt=0.0)
    pitch_deg: float = setting(45.0, gt=0.0, le=90.0)  # at 0 the camera would sit infinitely far
    noise: bool = True
    sigma_base_m: float = setting(0.0012, ge=0.0)
    sigma_quadratic_m: float = setting(0.0019, ge=0.0)
    sigma_reference_m: float = setting(0.4, ge=0.0)
    baseline_m: float = setting(0.075, gt=0.0)
    subpixel: float = setting(8.0, gt=0.0)
    grazing_deg: float = setting(80.0, gt=0.0, le=90.0)
    edge_jump_m: float = setting(0.02, gt=0.0)
    flying_probability: float = setting(0.3, ge=0.0, le=1.0)
    use_embree: bool = True
    # about 1 % of full scale: an 8-bit webcam-class colour sensor in good light
    color_noise: float = setting(0.01, ge=0.0, le=0.5,
                                 doc="colour noise, standard deviation per channel (sRGB units)")
    # a gain beyond 4 is no white balance but a colour filter
    white_balance: tuple[float, float, float] = setting(
        (1.0, 1.0, 1.0), gt=0.0, le=4.0, doc="white-balance gains on red, green, blue")
    vignetting: float = setting(0.0, ge=0.0, lt=1.0,
                                doc="relative loss of light at the image's corners")

    def __post_init__(self) -> None:
        check_settings(self)


#: Named depth cameras, from the maker's or the literature's figures (the references); the colour
#: noise is our choice by sensor class.
CAMERA_PRESETS: dict[str, Callable[[], CameraConfig]] = {
    "primesense": CameraConfig,
    # its 320 × 240 depth mode, 1 m above the table; random error 1.6 mm · z² (Khoshelham &
    # Elberink 2012, Fig. 9); a VGA Bayer colour sensor, twice the default colour noise
    "kinect-v1": partial(CameraConfig, width=320, height=240, fov_deg=(57.0, 43.0), height_m=1.0,
                         sigma_base_m=0.0, sigma_quadratic_m=0.0016, sigma_reference_m=0.0,
                         baseline_m=0.075, subpixel=8.0, color_noise=0.02),
    # 0.6 m above the table; depth RMS z² · 0.08 px / (f b), f ≈ 447 px: 3.6 mm · z²
    # (Grunnet-Jepsen et al. 2018); a global-shutter colour sensor, a little less noisy
    "realsense-d435": partial(CameraConfig, width=848, height=480, fov_deg=(87.0, 58.0),
                              height_m=0.6, sigma_base_m=0.0, sigma_quadratic_m=0.0036,
                              sigma_reference_m=0.0, baseline_m=0.05, subpixel=32.0,
                              color_noise=0.008),
}


def camera_preset(name: str) -> CameraConfig:
    """The :class:`CameraConfig` of the preset ``name`` (one of :data:`CAMERA_PRESETS`)."""
    if name not in CAMERA_PRESETS:
        raise InvalidArgumentError(
            f"`camera` must be one of {sorted(CAMERA_PRESETS)}; got {name!r}")
    return CAMERA_PRESETS[name]()


class Frame(NamedTuple):
    """Noisy ``points`` ``(n, 3)`` (world, metres) and each one's flat ``pixel``, ``triangle``
    hit, noise-free ``hit`` ``(n, 3)`` and the triangle's unit ``normal`` ``(n, 3)``."""

    points: NDArray[np.float64]
    pixel: NDArray[np.int64]
    triangle: NDArray[np.int64]
    hit: NDArray[np.float64]
    normal: NDArray[np.float64]


class DepthCamera:
    """The camera at its pose over a workspace centre: optical centre ``origin`` ``(3,)`` (world,
    metres) and pose ``cam2world`` ``(4, 4)`` (x right, y down, z forward, OpenCV convention)."""

    def __init__(self, config: CameraConfig, center_xy: tuple[float, float]) -> None:
        self.config = config
        pitch = np.radians(config.pitch_deg)
        target = np.array([center_xy[0], center_xy[1], 0.0])
        self.origin = target + np.array([0.0, -config.height_m / np.tan(pitch), config.height_m])
        forward = (target - self.origin) / np.linalg.norm(target - self.origin)
        right = np.array([1.0, 0.0, 0.0])
        down = np.cross(forward, right)
        self.cam2world = np.eye(4)
        self.cam2world[:3, :3] = np.column_stack([right, down, forward])
        self.cam2world[:3, 3] = self.origin
        self.focal_px = 0.5 * config.width / np.tan(np.radians(config.fov_deg[0]) / 2)
        u = np.arange(config.width) + 0.5 - config.width / 2
        v = np.arange(config.height) + 0.5 - config.height / 2
        gu, gv = np.meshgrid(u, v)
        cam = np.column_stack([gu.ravel() / self.focal_px,
                               gv.ravel() * np.tan(np.radians(config.fov_deg[1]) / 2)
                               / (config.height / 2), np.ones(gu.size)])
        self._cos_axis = 1.0 / np.linalg.norm(cam, axis=1)
        self.directions = (cam * self._cos_axis[:, None]) @ self.cam2world[:3, :3].T
        self._forward = forward

    def _cast(self, mesh: trimesh.Trimesh
              ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
        """Noise-free depth image, and per pixel the triangle hit (-1: none) and the hit point."""
        c = self.config
        origins = np.broadcast_to(self.origin, self.directions.shape)
        ray, tri, loc = cast_rays(mesh, np.ascontiguousarray(origins), self.directions,
                                  use_embree=c.use_embree)
        depth = np.full(c.width * c.height, np.nan)
        cos_incidence = np.abs(np.einsum("ij,ij->i", mesh.face_normals[tri], self.directions[ray]))
        ok = cos_incidence >= np.cos(np.radians(c.grazing_deg))
        depth[ray[ok]] = (loc[ok] - self.origin) @ self._forward
        triangle = np.full(c.width * c.height, -1, dtype=np.int64)
        triangle[ray[ok]] = tri[ok]
        hit = np.full((c.width * c.height, 3), np.nan)
        hit[ray[ok]] = loc[ok]
        return depth.reshape(c.height, c.width), triangle, hit

    def capture(self, mesh: trimesh.Trimesh, rng: np.random.Generator) -> Frame:
        """One frame of ``mesh``: world points and what each one's ray hit (module docstring)."""
        c = self.config
        depth, triangle, hit = self._cast(mesh)
        # draw every random number for every pixel so the stream never depends on the scene
        mix = rng.uniform(size=(2, c.height, c.width))
        gauss = rng.standard_normal(size=(c.height, c.width))
        if c.noise:
            depth = self._flying_pixels(depth, mix)
            sigma = c.sigma_base_m + c.sigma_quadratic_m * (depth - c.sigma_reference_m) ** 2
            depth = depth + sigma * gauss
            fb = self.focal_px * c.baseline_m
            depth = fb / (np.round(fb / depth * c.subpixel) / c.subpixel)
        flat = depth.ravel()
        valid = np.isfinite(flat) & (flat > 0)
        rng_along = flat[valid] / self._cos_axis[valid]
        points = np.asarray(self.origin + self.directions[valid] * rng_along[:, None])
        return Frame(points=points, pixel=np.flatnonzero(valid), triangle=triangle[valid],
                     hit=hit[valid], normal=np.asarray(mesh.face_normals)[triangle[valid]])

    def sensor_colors(self, light: NDArray[np.float64], pixel: NDArray[np.int64],
                      rng: np.random.Generator) -> NDArray[np.float64]:
        """``(n, 3)`` sRGB in ``[0, 1]`` of the ``(n, 3)`` linear ``light`` reaching the flat
        ``pixel`` indices (module docstring); noise drawn for every pixel of the image."""
        c = self.config
        u = pixel % c.width + 0.5 - c.width / 2
        v = pixel // c.width + 0.5 - c.height / 2
        r2 = (u * u + v * v) / ((c.width / 2) ** 2 + (c.height / 2) ** 2)
        linear = light * (1.0 - c.vignetting * r2)[:, None] * np.array(c.white_balance)
        out = linear_to_srgb(linear)
        noise = rng.standard_normal(size=(c.height * c.width, 3))
        if c.noise:
            out = out + c.color_noise * noise[pixel]
        return np.asarray(np.clip(out, 0.0, 1.0))

    def _flying_pixels(self, depth: NDArray[np.float64], mix: NDArray[np.float64]
                       ) -> NDArray[np.float64]:
        c = self.config
        out = depth.copy()
        for here, right_or_below in ((np.s_[:, :-1], np.s_[:, 1:]), (np.s_[:-1, :], np.s_[1:, :])):
            nxt = np.full_like(depth, np.nan)
            nxt[here] = depth[right_or_below]
            with np.errstate(invalid="ignore"):
                edge = np.abs(nxt - depth) > c.edge_jump_m
            fly = edge & (mix[0] < c.flying_probability) & np.isfinite(out)
            out[fly] = depth[fly] + mix[1][fly] * (nxt[fly] - depth[fly])
        return out
