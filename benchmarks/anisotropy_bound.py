"""How well one press's dent can tell an in-plane anisotropy at all: the Cramér–Rao bound on the
stiff-over-soft ratio and the stiff axis that a camera's points about the tip give, beside what
the shipped estimator (``deformap.stiffness.dent_anisotropy`` through
``deformap.explore.poke_behaviour``) reads from the same camera in the same run.

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/anisotropy_bound.py [--seeds 5]

For each camera preset, thickness (3 and 10 cm) and ratio (1.5 and 3, stiff axis 30° from x; the
behaviour study's foams, 60 N, 0.6 N press at the study's first place):

- the *profile* is the world's own isotropic dent: the same block made isotropic, pressed, seen by
  the camera with its noise turned off, its height binned by the distance from the tip (0.5 mm);
- the *oracle model* is that profile on elliptic contours, ``z = z₀ + A f(ρ)``,
  ``ρ² = (u / (s k))² + (v k / s)²`` in axes turned by ``θ``, ``k = ratio^{1/8}`` (Huber's stretch,
  ``deformap.stiffness._anisotropy``'s docstring); fitted to the anisotropic block's noise-free
  points it gives the ratio and axis the oracle reads with no noise (the mesh's own bias);
- the *bound*: the inverse Fisher information of ``(z₀, A, log s, log ratio, θ)`` at that fit, over
  the points the camera returns 1.2–6 tip radii from the tip (the estimator's window, the probe's
  own points left out), each with the camera's axial noise
  ``σ = sigma_base + sigma_quadratic (depth − sigma_reference)²`` carried along its ray, which a
  height field read at the moved point sees as ``σ_ray |r_z − ∇h · r_xy|`` (``r̂`` the ray's
  direction, ``∇h`` the dent's slope). Quantisation and flying pixels are left out and the profile
  is known exactly: under this model of the camera no unbiased reading of one press has a smaller
  σ;
- the *shipped* columns: the camera with its noise, ``--seeds`` worlds, the median ratio σ the
  estimator claims and how many of its readings fall within 15 % of the ratio and 10° of the axis.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import math

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from deformap.cloud import points_in_hull
from deformap.environment import PressObservation, Workspace
from deformap.eval import DEFAULT_POSITIONS, BehaviourMaterial, material_scenario
from deformap.explore import poke_behaviour
from deformap.world import Orthotropic, SimulatedWorld, WorldConfig, camera_preset

AXIS_DEG = 30.0
FORCE_N = 0.6
HARDNESS_N = 60.0
PROBE_MARGIN_M = 3e-3  # the probe's own points, as deformap.explore's poke_behaviour leaves them
INNER, OUTER = 1.2, 6.0  # the estimator's window, tip radii


def _window(obs: PressObservation) -> NDArray[np.float64]:
    """The points 1.2–6 tip radii from the tip, the probe's own left out."""
    pts, contact = obs.cloud.points, obs.contact
    d = np.linalg.norm(pts[:, :2] - contact.tip_center[:2], axis=1)
    keep = (d >= INNER * contact.tip_radius_m) & (d <= OUTER * contact.tip_radius_m)
    keep &= np.linalg.norm(pts - contact.tip_center, axis=1) > contact.tip_radius_m + PROBE_MARGIN_M
    keep &= ~points_in_hull(pts, obs.robot_points, tolerance_m=PROBE_MARGIN_M)
    return np.asarray(pts[keep])


def _model(p: NDArray[np.float64], q: NDArray[np.float64], rr: NDArray[np.float64],
           ff: NDArray[np.float64]) -> NDArray[np.float64]:
    z0, amplitude, log_s, log_ratio, theta = p
    c, s = math.cos(theta), math.sin(theta)
    u, v = c * q[:, 0] + s * q[:, 1], -s * q[:, 0] + c * q[:, 1]
    k, scale = math.exp(log_ratio / 8.0), math.exp(log_s)
    rho = np.sqrt((u / (scale * k)) ** 2 + (v * k / scale) ** 2)
    return np.asarray(z0 + amplitude * np.interp(rho, rr, ff))


def _press(material: BehaviourMaterial, config: WorldConfig, thickness: float, seed: int
           ) -> tuple[SimulatedWorld, PressObservation]:
    world = SimulatedWorld(material_scenario(material, Workspace(), thickness), config=config,
                           rng=np.random.default_rng(seed))
    return world, world.press(np.asarray(DEFAULT_POSITIONS[0], dtype=float), FORCE_N)


def _row(camera: str, thickness: float, ratio: float, seeds: int) -> list[str]:
    quiet = WorldConfig(camera=dataclasses.replace(camera_preset(camera), noise=False))
    iso = BehaviourMaterial("isotropic", HARDNESS_N)
    aniso = BehaviourMaterial(f"anisotropic {ratio:g}", HARDNESS_N,
                              anisotropy=Orthotropic(ratio=ratio, axis_deg=AXIS_DEG))
    _, obs = _press(iso, quiet, thickness, 0)
    pts, tip, radius = _window(obs), obs.contact.tip_center, obs.contact.tip_radius_m
    r = np.linalg.norm(pts[:, :2] - tip[:2], axis=1)
    top = float(np.median(pts[r > 5.0 * radius, 2]))
    edges = np.arange(INNER * radius - 5e-4, OUTER * radius * 1.5, 5e-4)
    rr, ff = [], []
    for a, b in itertools.pairwise(edges):
        inside = (r >= a) & (r < b)
        if inside.any():
            rr.append(0.5 * (a + b))
            ff.append(float(np.median(pts[inside, 2])) - top)
    rr_a, ff_a = np.array([*rr, 20.0 * radius]), np.array([*ff, 0.0])
    world, obs = _press(aniso, quiet, thickness, 0)
    pts = _window(obs)
    q, z = pts[:, :2] - obs.contact.tip_center[:2], pts[:, 2]
    fit = least_squares(lambda p: _model(p, q, rr_a, ff_a) - z,
                        [top, 1.0, 0.0, math.log(ratio), math.radians(AXIS_DEG)],
                        x_scale=[1e-3, 0.1, 0.1, 0.1, 0.1])
    p = fit.x
    cam = world.camera
    c = cam.config
    ray = pts - cam.origin
    dist = np.linalg.norm(ray, axis=1)
    direction = ray / dist[:, None]
    forward = cam.cam2world[:3, 2]
    depth = ray @ forward
    sigma_axis = c.sigma_base_m + c.sigma_quadratic_m * (depth - c.sigma_reference_m) ** 2
    # a depth error e along the ray moves the point by e·r̂; read as a height field at the moved
    # (x, y), the residual is e (r_z − ∇h · r_xy)
    grad = np.empty((z.size, 2))
    for i, shift in enumerate((np.array([1e-5, 0.0]), np.array([0.0, 1e-5]))):
        grad[:, i] = (_model(p, q + shift, rr_a, ff_a) - _model(p, q - shift, rr_a, ff_a)) / 2e-5
    along = sigma_axis / (direction @ forward)
    sigma_v = along * np.abs(direction[:, 2] - np.sum(grad * direction[:, :2], axis=1))
    step = np.array([1e-6, 1e-4, 1e-4, 1e-4, 1e-4])
    jac = np.empty((z.size, 5))
    for i in range(5):
        e = np.zeros(5)
        e[i] = step[i]
        jac[:, i] = (_model(p + e, q, rr_a, ff_a) - _model(p - e, q, rr_a, ff_a)) / (2.0 * step[i])
    weighted = jac / sigma_v[:, None]
    cov = np.linalg.inv(weighted.T @ weighted)
    oracle = math.exp(p[3])
    bound_ratio = oracle * math.sqrt(cov[3, 3])
    bound_axis = math.degrees(math.sqrt(cov[4, 4]))
    claimed, within, axis_within, read = [], 0, 0, 0
    for seed in range(seeds):
        _, obs = _press(aniso, WorldConfig(camera=camera_preset(camera)), thickness, 100 + seed)
        got = poke_behaviour(obs)
        if got.anisotropy_ratio is None:
            continue
        read += 1
        claimed.append(got.anisotropy_ratio_sigma)
        within += abs(got.anisotropy_ratio - ratio) <= 0.15 * ratio
        off = (got.anisotropy_axis_deg - AXIS_DEG + 90.0) % 180.0 - 90.0
        axis_within += abs(off) <= 10.0
    axis_read = (math.degrees(p[4]) + 90.0) % 180.0 - 90.0
    return [camera, f"{thickness * 100:.0f} cm", f"{ratio:g}", f"{z.size}",
            f"{np.median(sigma_v) * 1e3:.2f}", f"{oracle:.2f}, {axis_read:.0f}°",
            f"{bound_ratio:.2f} ({100 * bound_ratio / ratio:.0f} %)", f"{bound_axis:.1f}°",
            f"{np.median(claimed):.2g}" if claimed else "–",
            f"{within} / {axis_within} of {read} ({seeds})"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    args = parser.parse_args()
    head = ["camera", "thickness", "ratio", "points", "σ of a height median [mm]",
            "oracle, no noise: ratio, axis", "bound σ(ratio)", "bound σ(axis)",
            "shipped: median claimed σ(ratio)", "shipped: within 15 % / 10° of read (presses)"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for camera in ("primesense", "kinect-v1", "realsense-d435"):
        for thickness in (0.03, 0.10):
            for ratio in (1.5, 3.0):
                print("| " + " | ".join(_row(camera, thickness, ratio, args.seeds)) + " |",
                      flush=True)


if __name__ == "__main__":
    main()
