"""The stretches of one press read for :mod:`deformap.stiffness._behaviour`: the record's noise,
the hold's exponential fit, the loop's loss and the unloading's travel at zero force, each a value
with its standard error (the algorithms are stated in that module's docstring)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from deformap._validation import check_points
from deformap.errors import InvalidArgumentError

__all__ = [
    "MAD_TO_SIGMA",
    "MIN_FIT_SAMPLES",
    "MIN_NOISE_DIFFERENCES",
    "N_SIGMA",
    "ForceNoise",
    "Measure",
    "PressRecord",
    "Stretch",
    "force_noise",
    "hold_fraction",
    "hold_travel",
    "hold_with_start",
    "loop_loss",
    "noise",
    "press_surface",
    "zero_force_travel",
]

#: A quantity shows a behaviour only beyond this many of its standard errors.
N_SIGMA = 3.0
#: Fewest hold samples for the exponential fit (three parameters and a residual).
MIN_FIT_SAMPLES = 4

#: A normal sample's standard deviation over its median absolute deviation.
MAD_TO_SIGMA = 1.4826
#: Fewest second differences for the load-dependent force noise (two parameters, five per
#: parameter); fewer keep the pooled constant.
MIN_NOISE_DIFFERENCES = 10
#: A second difference beyond this many of its model σ is left out of the force noise fit: a
#: normal draw lies there once in about 16 000.
_NOISE_TRIM_SIGMA = 4.0


class _Phase(Protocol):
    time_s: NDArray[np.float64]
    travel_m: NDArray[np.float64]
    force_n: NDArray[np.float64]

    def __len__(self) -> int: ...


class PressRecord(Protocol):
    """What :func:`deformap.stiffness.press_behaviour` reads of a press's record: a
    :class:`deformap.environment.ForceTravel` (checked there: times that increase, stretches with
    samples, an unloading that falls, finite values)."""

    @property
    def travel_m(self) -> NDArray[np.float64]: ...
    @property
    def force_n(self) -> NDArray[np.float64]: ...
    @property
    def time_s(self) -> NDArray[np.float64] | None: ...
    @property
    def hold(self) -> Any: ...
    @property
    def unloading(self) -> Any: ...


@dataclass(frozen=True)
class Measure:
    """A value and its standard error, tested against a physical floor."""

    value: float
    sigma: float

    def shows(self, floor: float) -> bool:
        return self.value > N_SIGMA * self.sigma and self.value > floor

    def rules_out(self, floor: float) -> bool:
        return self.value + 2.0 * self.sigma < floor

    def text(self, name: str, unit: float = 1.0, suffix: str = "") -> str:
        return f"{name} {self.value * unit:.3g} ± {self.sigma * unit:.2g}{suffix}"


def noise(parts: list[NDArray[np.float64]]) -> float:
    """Sample noise pooled from the second differences of each stretch (module docstring)."""
    diffs = [np.diff(p, n=2) for p in parts if p.size >= 3]
    if not diffs:
        return 0.0
    return float(MAD_TO_SIGMA * np.median(np.abs(np.concatenate(diffs))) / math.sqrt(6.0))


@dataclass(frozen=True)
class ForceNoise:
    """A force sensor's sample noise at force ``F``: ``σ_F(F) = √(a² + (b F)²)`` [N]."""

    a: float
    b: float = 0.0

    def at(self, force: Any) -> NDArray[np.float64]:
        f = np.maximum(np.asarray(force, dtype=np.float64), 0.0)
        return np.asarray(np.sqrt(self.a**2 + (self.b * f) ** 2))


def force_noise(parts: list[NDArray[np.float64]]) -> ForceNoise:
    """The force's sample noise as a function of the load, ``σ_F(F)² = a² + (b F)²``, fitted to the
    squared second differences of each stretch (module docstring of
    :mod:`deformap.stiffness._behaviour`); the pooled constant (:func:`noise`) when the record
    cannot fit it."""
    pooled = ForceNoise(noise(parts))
    usable = [p for p in parts if p.size >= 3]
    if not usable or pooled.a <= 0.0:
        return pooled
    # E[(F₋ − 2F + F₊)²] = σ₋² + 4σ² + σ₊² ≈ 6 σ²(F) where the trend is linear in time
    y = np.concatenate([np.diff(p, n=2) ** 2 / 6.0 for p in usable])
    f2 = np.concatenate([np.maximum(p[1:-1], 0.0) ** 2 for p in usable])
    top = float(f2.max())
    if top <= 0.0:  # no load anywhere: nothing for b to grow with
        return pooled
    u = f2 / top  # the load's share of its largest, so the design's scale is the record's own
    model = pooled
    for _ in range(50):
        var = model.at(np.sqrt(f2)) ** 2
        keep = y <= _NOISE_TRIM_SIGMA**2 * var
        if int(keep.sum()) < MIN_NOISE_DIFFERENCES:
            return pooled
        # weighted least squares of y on [1, F²], weights 1/var² (y's variance is 2 var²):
        # the normal likelihood's scoring step; var > 0 as a > 0 below
        w = keep / var**2
        design = np.column_stack([np.ones(y.size), u])
        normal = design.T @ (design * w[:, None])
        if np.linalg.cond(normal) > 1e12:  # one force only: a and b cannot be told apart
            return pooled
        try:
            a2, c2 = np.linalg.solve(normal, design.T @ (w * y))
        except np.linalg.LinAlgError:
            return pooled
        if not (a2 > 0.0 and c2 >= 0.0):  # no floor or no growth the record shows: the pooled
            return pooled
        new = ForceNoise(math.sqrt(a2), math.sqrt(c2 / top))
        done = abs(new.a - model.a) + abs(new.b - model.b) * math.sqrt(top) \
            <= 1e-9 * (model.a + model.b * math.sqrt(top))
        model = new
        if done:
            break
    return model if math.isfinite(model.a) and math.isfinite(model.b) else pooled


def _fraction(start: float, end: float, grad: NDArray[np.float64], cov: NDArray[np.float64],
              mode: str) -> Measure:
    value = 1.0 - end / start if mode == "force" else 1.0 - start / end
    return Measure(float(value), math.sqrt(max(0.0, float(grad @ cov @ grad))))


@dataclass(frozen=True)
class Stretch:
    """Samples of one stretch of a press (a hold with the ramp's last sample before it)."""

    time_s: NDArray[np.float64]
    travel_m: NDArray[np.float64]
    force_n: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.travel_m.size)


def hold_with_start(record: PressRecord) -> Any:
    """The record's hold, the ramp's last sample (where the commanded force is reached and the
    hold begins) put before it when the ramp has times; the hold alone otherwise."""
    hold = record.hold
    if hold is None or record.time_s is None:
        return hold
    return Stretch(time_s=np.concatenate([[float(record.time_s[-1])], hold.time_s]),
                   travel_m=np.concatenate([[float(record.travel_m[-1])], hold.travel_m]),
                   force_n=np.concatenate([[float(record.force_n[-1])], hold.force_n]))


def _line(t: NDArray[np.float64], y: NDArray[np.float64], sigma: float
          ) -> tuple[float, float, NDArray[np.float64]]:
    """A straight line's values at the stretch's first and last time, fitted to all its samples
    (least squares), and their covariance with the sample noise ``sigma``."""
    span = float(t[-1] - t[0])
    design = np.column_stack([np.ones(t.size), (t - t[0]) / span])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    to_ends = np.array([[1.0, 0.0], [1.0, 1.0]])
    cov = to_ends @ np.linalg.inv(design.T @ design) @ to_ends.T * sigma**2
    return float(coef[0]), float(coef[0] + coef[1]), cov


def _moves(t: NDArray[np.float64], y: NDArray[np.float64], sigma: float) -> bool:
    """Whether a stretch's straight line changes by more than :data:`N_SIGMA` of its σ."""
    start, end, cov = _line(t, y, sigma)
    return abs(end - start) > N_SIGMA * math.sqrt(max(cov[0, 0] + cov[1, 1] - 2.0 * cov[0, 1],
                                                      0.0))


def hold_travel(hold: _Phase, sigma_t: float) -> Measure:
    """The travel the hold added, end less start of a straight line through its samples."""
    t = np.asarray(hold.time_s - hold.time_s[0])
    travel = np.asarray(hold.travel_m)
    a, b, cov = _line(t, travel, sigma_t)
    return Measure(b - a, math.sqrt(max(cov[0, 0] + cov[1, 1] - 2.0 * cov[0, 1], 0.0)))


def hold_fraction(hold: _Phase, sigma_f: float, sigma_t: float
                  ) -> tuple[Measure | None, Measure | None, str, str]:
    """The hold's fraction and time constant, the mode, and a note on what could not be had."""
    t = np.asarray(hold.time_s - hold.time_s[0])
    force, travel = np.asarray(hold.force_n), np.asarray(hold.travel_m)
    # a force sensor's noise grows with the load: the hold's own, when larger than the pooled
    # (the encoders' does not: the travel's stays pooled)
    sigma_f = max(sigma_f, noise([force]))
    lines = {"force": _line(t, force, sigma_f), "travel": _line(t, travel, sigma_t)}

    def z(name: str) -> float:
        a, b, cov = lines[name]
        return abs(b - a) / max(math.sqrt(max(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1], 0.0)),
                                1e-300)

    # neither moving beyond its noise: the force is the held one (docs/robot.md: the press holds
    # the commanded force under force control), so the travel is what would creep
    moving = max(z("force"), z("travel")) > N_SIGMA
    mode = "travel" if (z("travel") > z("force") or not moving) else "force"
    y = force if mode == "force" else travel
    sigma = sigma_f if mode == "force" else sigma_t
    a, b, cov_ab = lines[mode]
    if b <= 0.0 or a <= 0.0:
        return None, None, mode, f"the hold's {mode} is not positive"
    # fallback: the fraction between the ends of a straight line through the whole stretch
    g = np.array([b / a**2, -1.0 / a]) if mode == "force" else np.array([-1.0 / b, a / b**2])
    plain = _fraction(a, b, g, cov_ab, mode)
    if len(hold) < MIN_FIT_SAMPLES:
        return plain, None, mode, (f"a hold of {len(hold)} samples gives no time constant "
                                   f"(needs {MIN_FIT_SAMPLES})")
    if not moving:
        return plain, None, mode, (f"the hold moves within its noise ({N_SIGMA:g} σ): no time "
                                   "constant")
    span = float(t[-1])

    def model(p: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(p[0] + p[1] * np.exp(-t / math.exp(p[2])))

    start = np.array([b, a - b, math.log(span / 3.0)])
    bounds = ([-np.inf, -np.inf, math.log(span * 1e-3)], [np.inf, np.inf, math.log(span * 1e3)])
    try:
        fit = least_squares(lambda p: model(p) - y, start, bounds=bounds, method="trf")
    except (ValueError, np.linalg.LinAlgError):
        return plain, None, mode, "the hold's exponential fit failed"
    dof = y.size - 3
    s2 = float(fit.fun @ fit.fun) / dof if dof > 0 else sigma**2
    s2 = max(s2, sigma**2) if dof < 3 else s2
    jac = np.asarray(fit.jac)
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
    except np.linalg.LinAlgError:
        return plain, None, mode, "the hold's exponential fit is degenerate (no decay to fit)"
    if not (fit.success and np.all(np.isfinite(cov))):
        return plain, None, mode, "the hold's exponential fit did not converge"
    p = fit.x
    decay = math.exp(-span / math.exp(p[2]))
    y0, y1 = p[0] + p[1], p[0] + p[1] * decay
    if y0 <= 0.0 or y1 <= 0.0:
        return plain, None, mode, "the hold's fitted curve is not positive"
    dy0 = np.array([1.0, 1.0, 0.0])
    dy1 = np.array([1.0, decay, p[1] * decay * span / math.exp(p[2])])
    grad = (-dy1 / y0 + y1 * dy0 / y0**2) if mode == "force" else (-dy0 / y1 + y0 * dy1 / y1**2)
    fraction = _fraction(y0, y1, grad, cov, mode)
    tau = math.exp(float(p[2]))
    tau_m = Measure(tau, tau * math.sqrt(max(0.0, float(cov[2, 2]))))
    if not (math.isfinite(fraction.value) and math.isfinite(fraction.sigma)):
        return plain, None, mode, "the hold's exponential fit gave no finite fraction"
    return fraction, tau_m, mode, ""


def _trapz_grad(x: NDArray[np.float64], y: NDArray[np.float64]
                ) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """``∫ y dx`` by trapezoids and its gradient with respect to each ``x`` and ``y``."""
    dx = np.diff(x)
    value = float(np.sum(0.5 * (y[:-1] + y[1:]) * dx))
    gy = np.zeros_like(y)
    gy[:-1] += 0.5 * dx
    gy[1:] += 0.5 * dx
    gx = np.zeros_like(x)
    mid = 0.5 * (y[:-1] + y[1:])
    gx[1:] += mid
    gx[:-1] -= mid
    return value, gx, gy


def loop_loss(record: PressRecord, sigma_f: ForceNoise, sigma_t: float) -> Measure | str:
    """The loop's loss over the work put in, its σ from each sample's force noise at its force
    and the travel's (module docstring of :mod:`deformap.stiffness._behaviour`)."""
    unloading = record.unloading
    assert unloading is not None
    parts = [(record.travel_m, record.force_n)]
    hold = record.hold
    if hold is not None:  # its last sample alone where one of the two is held (module docstring)
        t, d, f = (np.asarray(v, dtype=np.float64) for v in (hold.time_s, hold.travel_m,
                                                              hold.force_n))
        both = t.size >= 3 and t[-1] > t[0] and _moves(t, d, sigma_t) and _moves(
            t, f, float(sigma_f.at(float(np.mean(f)))))
        parts.append((d, f) if both else (d[-1:], f[-1:]))
    n_in = sum(p[0].size for p in parts)
    parts.append((unloading.travel_m, unloading.force_n))
    x = np.concatenate([p[0] for p in parts])
    y = np.concatenate([p[1] for p in parts])
    loop, gx_l, gy_l = _trapz_grad(x, y)
    work, gx_w, gy_w = _trapz_grad(x[:n_in], y[:n_in])
    if work <= 0.0:
        return "the loading ramp did no work (no travel under force)"
    ratio = loop / work
    gx = gx_l.copy()
    gy = gy_l.copy()
    gx[:n_in] -= ratio * gx_w
    gy[:n_in] -= ratio * gy_w
    s2 = sigma_f.at(y) ** 2
    # L − R W is bilinear in the travels and the forces, ``Σ_s w_s (y_s + y_{s+1})(x_{s+1} − x_s)/2``
    # (w_s = 1 − R on the loading's segments, 1 after): the gradients at the noisy samples each
    # carry the product of the two noises once, which the loss carries once in all; one is taken
    # back, ``σ_t² Σ_ij A_ij² σ_F,j²`` with ``A = ∂²/∂x ∂y``
    w = np.ones(x.size - 1)
    w[:n_in - 1] = 1.0 - ratio
    steps = np.diff(np.concatenate([[0.0], w, [0.0]]))
    product = 0.25 * sigma_t**2 * (float(np.sum(w**2 * (s2[:-1] + s2[1:])))
                                   + float(np.sum(steps**2 * s2)))
    var = sigma_t**2 * float(gx @ gx) + float(np.sum(s2 * gy**2)) - product
    return Measure(ratio, math.sqrt(max(var, 0.0)) / work)


def zero_force_travel(record: PressRecord, sigma_f: ForceNoise, sigma_t: float,
                      creep: Measure | None = None) -> Measure | str:
    """The unloading's travel at zero force less the loading's (module docstring of
    :mod:`deformap.stiffness._behaviour`); ``creep`` is the travel the hold added (0 without)."""
    unloading = record.unloading
    assert unloading is not None
    f, t = np.asarray(unloading.force_n), np.asarray(unloading.travel_m)
    lf, lt = np.asarray(record.force_n), np.asarray(record.travel_m)
    order = np.argsort(lf, kind="stable")
    x_l = np.maximum(lf[order], 0.0) ** (2.0 / 3.0)
    t_l = lt[order]
    x = np.maximum(f, 0.0) ** (2.0 / 3.0)
    s_f = sigma_f.at(f)
    # the unloading's samples within the ramp's range of force, above their noise
    use = (f >= np.maximum(float(lf.min()), N_SIGMA * s_f)) & (
        f <= float(lf.max()) + N_SIGMA * s_f)
    if int(use.sum()) < 2:
        floor = N_SIGMA * float(sigma_f.at(0.0))
        return (f"the unloading branch has {int(use.sum())} samples within the ramp's range of "
                f"force and above its noise ({N_SIGMA:g} σ = {floor:.2g} N at zero force); "
                "needs 2")
    x, t, s_f = x[use], t[use], s_f[use]
    gap = t - np.interp(x, x_l, t_l)  # unloading less loading at the same force
    # the loading's local slope dt/dF there: the force noise of both readings moves the gap
    j = np.clip(np.searchsorted(x_l, x), 1, x_l.size - 1)
    f_l = np.maximum(lf[order], 0.0)
    slope = (t_l[j] - t_l[j - 1]) / np.maximum(f_l[j] - f_l[j - 1], 1e-12)
    # a noise-free record (a simulation without noise) weighs its samples alike: the floor is
    # far below any sensor's (1e-15 m), so a real record's weights are its own
    var = np.maximum(2.0 * sigma_t**2 + 2.0 * (slope * s_f) ** 2, 1e-30)
    top = float(np.max(np.maximum(f, 0.0) ** (2.0 / 3.0)))
    u = x / top
    c = Measure(0.0, 0.0) if creep is None else creep
    weight = 1.0 - u
    if float(np.sum(weight**2 / var)) <= 0.0:
        return "the unloading branch has no samples below its top force (no dent to read)"
    y = gap - c.value * u
    info = float(np.sum(weight**2 / var))
    value = float(np.sum(weight * y / var)) / info
    resid = y - value * weight
    dof = y.size - 1
    misfit = float(np.sum(resid**2 / var)) / dof if dof > 0 else 1.0
    sigma2 = max(misfit, 1.0) / info + (c.sigma * float(np.sum(weight * u / var)) / info) ** 2
    if not (math.isfinite(value) and math.isfinite(sigma2)):
        return "the unloading branch gave no finite travel at zero force"
    return Measure(value, math.sqrt(sigma2))


def press_surface(points: Any, tip_center: Any, tip_radius_m: float
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A surface read about a press, checked: ``points`` ``(n, 3)`` (world frame, z up) and the
    tip's centre ``(3,)``, both float64; the tip radius must be positive."""
    center = np.asarray(tip_center, dtype=np.float64)
    if not (center.shape == (3,) and np.all(np.isfinite(center))):
        raise InvalidArgumentError(f"`tip_center` must be 3 finite numbers; got {tip_center!r}")
    if not (math.isfinite(tip_radius_m) and tip_radius_m > 0.0):
        raise InvalidArgumentError(f"`tip_radius_m` must be positive; got {tip_radius_m!r}")
    return check_points("points", points, min_rows=0), center
