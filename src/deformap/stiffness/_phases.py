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

__all__ = ["MAD_TO_SIGMA", "MIN_FIT_SAMPLES", "N_SIGMA", "Measure", "PressRecord", "hold_fraction",
           "loop_loss", "noise", "zero_force_travel"]

#: A quantity shows a behaviour only beyond this many of its standard errors.
N_SIGMA = 3.0
#: Fewest hold samples for the exponential fit (three parameters and a residual).
MIN_FIT_SAMPLES = 4

#: A normal sample's standard deviation over its median absolute deviation.
MAD_TO_SIGMA = 1.4826


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


def _ends(y: NDArray[np.float64], sigma: float) -> tuple[float, float, float]:
    """Means of the first and last fifth of ``y`` and the σ of each mean."""
    k = max(1, y.size // 5)
    return float(y[:k].mean()), float(y[-k:].mean()), sigma / math.sqrt(k)


def _fraction(start: float, end: float, grad: NDArray[np.float64], cov: NDArray[np.float64],
              mode: str) -> Measure:
    value = 1.0 - end / start if mode == "force" else 1.0 - start / end
    return Measure(float(value), math.sqrt(max(0.0, float(grad @ cov @ grad))))


def hold_fraction(hold: _Phase, sigma_f: float, sigma_t: float
          ) -> tuple[Measure | None, Measure | None, str, str]:
    """The hold's fraction and time constant, the mode, and a note on what could not be had."""
    f0, f1, sf = _ends(hold.force_n, sigma_f)
    t0, t1, st = _ends(hold.travel_m, sigma_t)
    z_force = abs(f1 - f0) / max(sf, 1e-300)
    z_travel = abs(t1 - t0) / max(st, 1e-300)
    mode = "travel" if z_travel > z_force else "force"
    y = np.asarray(hold.force_n if mode == "force" else hold.travel_m)
    sigma = sigma_f if mode == "force" else sigma_t
    a, b, s_end = (f0, f1, sf) if mode == "force" else (t0, t1, st)
    if b <= 0.0 or a <= 0.0:
        return None, None, mode, f"the hold's {mode} is not positive"
    # fallback: fraction from the stretch's ends
    g = np.array([b / a**2, -1.0 / a]) if mode == "force" else np.array([-1.0 / b, a / b**2])
    plain = _fraction(a, b, g, np.eye(2) * s_end**2, mode)
    if len(hold) < MIN_FIT_SAMPLES:
        return plain, None, mode, (f"a hold of {len(hold)} samples gives no time constant "
                                   f"(needs {MIN_FIT_SAMPLES})")
    t = np.asarray(hold.time_s - hold.time_s[0])
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


def loop_loss(record: PressRecord, sigma_f: float, sigma_t: float) -> Measure | str:
    unloading = record.unloading
    assert unloading is not None
    parts = [(record.travel_m, record.force_n)]
    if record.hold is not None:
        parts.append((record.hold.travel_m, record.hold.force_n))
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
    var = (sigma_t**2 * float(gx @ gx) + sigma_f**2 * float(gy @ gy)) / work**2
    return Measure(ratio, math.sqrt(var))


def zero_force_travel(unloading: _Phase, sigma_f: float, sigma_t: float) -> Measure | str:
    f = np.asarray(unloading.force_n)
    t = np.asarray(unloading.travel_m)
    reached = np.flatnonzero(f <= N_SIGMA * sigma_f)
    if reached.size and reached[0] > 0:  # contact lost here: the surface's height then
        return Measure(float(t[reached[0]]), sigma_t)
    use = (f > N_SIGMA * sigma_f) & (f <= 0.5 * float(f.max()))
    if int(use.sum()) < 3:
        use = f > N_SIGMA * sigma_f
    n = int(use.sum())
    if n < 2:
        return (f"the unloading branch has {n} samples above its force noise "
                f"({N_SIGMA:g} σ = {N_SIGMA * sigma_f:.2g} N); needs 2")
    x = f[use] ** (2.0 / 3.0)
    yv = t[use]
    design = np.column_stack([np.ones(n), x])
    coef, *_ = np.linalg.lstsq(design, yv, rcond=None)
    resid = yv - design @ coef
    s2 = float(resid @ resid) / (n - 2) if n > 2 else 0.0
    s2 = max(s2, sigma_t**2)
    try:
        cov = np.linalg.inv(design.T @ design) * s2
    except np.linalg.LinAlgError:
        return "the unloading branch's force does not vary (no line to extrapolate)"
    value, sigma = float(coef[0]), math.sqrt(max(0.0, float(cov[0, 0])))
    if not (math.isfinite(value) and math.isfinite(sigma)):
        return "the unloading branch gave no finite travel at zero force"
    return Measure(value, sigma)
