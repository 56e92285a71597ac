"""What one press reveals beyond its stiffness: relaxation, hysteresis, a kept dent, and a class.

From a :class:`~deformap.environment.ForceTravel` (and, optionally, the depth of the dent the
camera sees after release), :func:`press_behaviour` returns each quantity with a standard error
and a behaviour class, every threshold a multiple of the record's own noise or a stated physical
floor. A quantity the record cannot give is ``None``; the class is then ``"unknown"`` with the
reason, never ``"elastic"`` by default.

Noise: the force's and the travel's sample noise ``σ_F``, ``σ_t`` are estimated from the record
itself, ``1.4826 · MAD(Δ²x) / √6`` of the second differences within each stretch (ramp, hold,
unloading) pooled, which a smooth trend barely touches. A force sensor's noise grows with the
load, so the loss and the dent take it as a function of the force, ``σ_F(F)² = a² + (b F)²``,
fitted to the same second differences: on a load-controlled press the ramp and the unloading are
linear in time and the hold constant, so ``E[(Δ²F)²] = 6 σ_F(F)²`` at each interior sample's force
``F``; ``a²``, ``b²`` are the normal likelihood's weighted least squares of ``(Δ²F)²/6`` on
``[1, F²]`` (weights ``1/σ_F(F)⁴``, iterated from the pooled constant), each pass leaving out the
differences beyond 4 of their model σ. A record that cannot fit it (fewer than
:data:`MIN_NOISE_DIFFERENCES` differences, one force only, ``b² < 0`` or ``a² ≤ 0``: a sensor
with no noise at zero load is none a record can show) keeps the pooled constant. The travel's
noise (the encoders') does not grow with the load and stays pooled; the hold takes its own
stretch's force noise (below).

Hold: the ramp's last sample (where the commanded force is reached) starts it. Straight lines
through the force and the travel of the whole stretch (least squares; for the force the larger of
the pooled and the hold's own noise, as a force sensor's grows with the load) say which moves: the
held quantity is the one whose line changes less in units of its σ; when neither changes by
:data:`N_SIGMA` of its σ the force is taken as held (docs/robot.md: the press holds the commanded
force under force control) and the travel is what would creep. The moving one is fitted, least
squares, with ``y(t) = y∞ + A e^{−(t−t₀)/τ}`` (``t₀`` the stretch's first sample, ``log τ`` the
parameter). Force moving (position held): the relaxation fraction is ``1 − F(t_end)/F(t₀)``; travel
moving (force held): the creep fraction ``1 − t(t₀)/t(t_end)``, both from the fitted curve, their σ
by the delta method on the fit's covariance ``s² (JᵀJ)⁻¹``; ``τ`` and its σ from the same
covariance. A stretch that moves within its noise, one of fewer than :data:`MIN_FIT_SAMPLES`
samples, or one whose fit does not converge gives the fraction between the ends of its straight
line and no ``τ``.

Loss ratio: the path ramp → hold → unloading, ``L = ∮ F dδ`` (trapezoids; the return from the
unloading's last travel to zero at zero force adds nothing) over the work put in before
unloading, ``W = ∫ F dδ`` along ramp and hold. Where the hold keeps the force or the position
(the straight line through one of them changes by less than :data:`N_SIGMA` of its σ) it enters
by its last sample alone: ``∫ F dδ`` over it is then ``F Δδ`` (or zero), which the one segment from
the ramp's last sample to the hold's last gives, while each interior sample would add the product
of its force and travel noises, a variance that grows with the hold's length and tells nothing of
the loop; a hold where both move enters by every sample. Its σ by linear propagation of each sample's
``σ_F(F)`` at its force and of ``σ_t`` through both trapezoid sums, the gradients taken at the
noisy samples; ``L − R W`` is bilinear in travel and force, and those gradients each carry the
product of the two noises (the travel's steps under the force's noise, the force's steps under
the travel's), which the ratio carries once: one copy, ``σ_t² Σ_ij (∂²/∂δ_i ∂F_j)² σ_F,j²``, is
taken back.

Residual dent: the unloading's travel at zero force less the loading's, from the gap between the
two branches at the same force. Each unloading sample within the ramp's range of force (and above
``N_SIGMA σ_F(F)``) is set against the ramp's travel at its force (interpolated linearly in
``x = F^{2/3}``). In the contact law's linearised form, ``δ = a + c x`` near zero force (Hertz),
the loading and the unloading are lines that meet at the top but for the hold's creep ``C``, so
the gap is ``r (1 − x/x_top) + C x/x_top``, ``x_top`` the unloading's first sample; ``r``, the dent,
is its weighted least-squares coefficient, ``C`` the travel the hold's straight line adds. A sample's
variance is ``2 σ_t² + 2 (σ_F(F) dt/dF)²`` (both readings' travel and force noise, the force's through
the ramp's local slope); ``r``'s σ is the fit's, widened by ``√(χ²/dof)`` when the samples scatter
more than that (a branch that does not follow the linearised law), plus ``C``'s carried through.
Every sample of the branch enters, not one near zero force, where the contact law's steepness
turns the force noise into large travel errors; samples after contact is lost (force below the
ramp's first) are left out. The camera's dent (:func:`released_dent`) is the median height of
the surface 3–5 tip radii from the press point less the median within one tip radius, σ from both
medians' standard errors.

Class: a quantity *shows* a behaviour when it exceeds :data:`N_SIGMA` of its σ and its physical
floor; it *rules it out* when it lies below the floor by two of its σ. Viscoelastic: the hold
relaxes or creeps; or, with no hold, the loop has loss but no dent remains. Plastic: a dent
remains (record or camera) while a hold shows no relaxation; or a loss with a hold that shows
none. No dent remains when neither dent reading shows one and one of them rules it out, each
against its floor: the camera's :data:`DENT_FLOOR_M`, the record's :func:`record_dent_floor`.
Elastic: every quantity the record holds rules its behaviour out, and the record holds an
unloading branch or a hold with a camera dent. Anything else is ``"unknown"`` with the reason.

Anisotropy: from the dent's shape in the cloud during the press
(:mod:`deformap.stiffness._anisotropy`), its own class ``isotropy`` beside ``behaviour``.

Moduli: the loading ramp's E, given by the caller (:mod:`deformap.stiffness`'s estimate), is the
instantaneous one; the relaxed one follows from it and the hold's fraction
(:func:`relaxed_modulus`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from deformap.errors import InvalidArgumentError
from deformap.stiffness._anisotropy import Anisotropy, Isotropy
from deformap.stiffness._phases import (
    MAD_TO_SIGMA,
    MIN_FIT_SAMPLES,
    MIN_NOISE_DIFFERENCES,
    N_SIGMA,
    Measure,
    PressRecord,
    force_noise,
    hold_fraction,
    hold_travel,
    hold_with_start,
    loop_loss,
    noise,
    press_surface,
    zero_force_travel,
)

__all__ = ["BEHAVIOURS", "DENT_FLOOR_M", "LOSS_FLOOR", "MIN_FIT_SAMPLES",
           "MIN_NOISE_DIFFERENCES", "N_SIGMA",
           "RELAXATION_FLOOR", "Behaviour", "PressBehaviour", "PressRecord", "press_behaviour",
           "record_dent_floor", "relaxed_modulus", "released_dent"]

Behaviour = Literal["elastic", "viscoelastic", "plastic", "unknown"]
BEHAVIOURS: tuple[str, ...] = ("elastic", "viscoelastic", "plastic", "unknown")

#: Smallest relaxation (or creep) fraction taken as the material's: a strain-gauge force sensor
#: and an arm's position loop drift by up to about 1–2 % of the load over a hold.
RELAXATION_FLOOR = 0.02
#: Smallest loss ratio taken as the material's: tip friction and the sensor's own hysteresis
#: (a few per cent of the load) close no loop of an ideal elastic press.
LOSS_FLOOR = 0.05
#: Smallest kept dent [m] taken as the material's: a tenth of a millimetre, about what the tip's
#: contact settles by as the force reaches zero and below what a depth camera resolves at arm's
#: length.
DENT_FLOOR_M = 1e-4


def record_dent_floor(record: PressRecord) -> float:
    """Smallest dent [m] the record's travel at zero force can take as the material's: at least
    :data:`DENT_FLOOR_M`, and the travel that a force of :data:`RELAXATION_FLOOR` of the press's
    largest moves the tip on a Hertz contact, ``RELAXATION_FLOOR^(2/3)`` of the largest travel:
    the force sensor's zero drifting by that much between first contact and release (the drift
    :data:`RELAXATION_FLOOR` allows) shifts where the force reads zero by up to that travel."""
    parts = [np.asarray(record.travel_m)]
    if record.hold is not None:
        parts.append(np.asarray(record.hold.travel_m))
    largest = max(float(np.max(p)) for p in parts)
    return max(DENT_FLOOR_M, RELAXATION_FLOOR ** (2.0 / 3.0) * largest)


@dataclass(frozen=True, kw_only=True)
class PressBehaviour:
    """What one press reveals, each quantity with its standard error (``None`` where the record
    cannot give it).

    ``relaxation`` is the hold's fraction (``relaxation_mode`` ``"force"``: ``1 − F_end/F_start``
    with the position held; ``"travel"``: creep ``1 − t_start/t_end`` with the force held), ``tau_s``
    its time constant [s]; ``loss_ratio`` the hysteresis energy over the loading energy;
    ``residual_dent_m`` the unloading's travel at zero force [m]; ``released_dent_m`` the dent the
    camera sees after release [m]. ``modulus_instantaneous_pa`` is the loading ramp's Young's
    modulus (the modulus at the press's speed, given to :func:`press_behaviour`),
    ``modulus_relaxed_pa`` the modulus at the hold's end (:func:`relaxed_modulus`).
    ``anisotropy_ratio`` is the in-plane stiff-over-soft ratio the dent's shape shows,
    ``anisotropy_axis_deg`` its stiff axis [degrees from x, in (−90, 90]], and ``isotropy``
    (``"isotropic"``, ``"anisotropic"``, ``"unknown"``) their class
    (:func:`~deformap.stiffness._anisotropy.dent_anisotropy`); ``None`` where no cloud during the
    press was read. ``behaviour`` is the class and ``evidence`` the tests that gave it, or why it
    is ``"unknown"``.
    """

    behaviour: Behaviour
    evidence: str
    relaxation: float | None = None
    relaxation_sigma: float | None = None
    relaxation_mode: Literal["force", "travel"] | None = None
    tau_s: float | None = None
    tau_sigma_s: float | None = None
    loss_ratio: float | None = None
    loss_ratio_sigma: float | None = None
    residual_dent_m: float | None = None
    residual_dent_sigma_m: float | None = None
    released_dent_m: float | None = None
    released_dent_sigma_m: float | None = None
    modulus_instantaneous_pa: float | None = None
    modulus_instantaneous_sigma_pa: float | None = None
    modulus_relaxed_pa: float | None = None
    modulus_relaxed_sigma_pa: float | None = None
    isotropy: Isotropy | None = None
    anisotropy_ratio: float | None = None
    anisotropy_ratio_sigma: float | None = None
    anisotropy_axis_deg: float | None = None
    anisotropy_axis_sigma_deg: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON): every field, ``None`` for what the record could not give."""
        return asdict(self)



def released_dent(points: Any, tip_center: Any, tip_radius_m: float
                  ) -> tuple[float, float] | str:
    """The dent [m] and its σ that the surface seen after release, ``points`` ``(n, 3)`` (world
    frame, z up), keeps at the press point (module docstring), or why it cannot be had (too few
    points near the press)."""
    pts, center = press_surface(points, tip_center, tip_radius_m)
    r = np.linalg.norm(pts[:, :2] - center[:2], axis=1)
    inner = pts[r <= tip_radius_m, 2]
    ring = pts[(r >= 3.0 * tip_radius_m) & (r <= 5.0 * tip_radius_m), 2]
    if inner.size < 5 or ring.size < 5:
        return (f"the surface after release has {inner.size} points within one tip radius of "
                f"the press and {ring.size} 3–5 radii away; needs 5 of each")

    def median_se(z: NDArray[np.float64]) -> float:
        return float(1.2533 * MAD_TO_SIGMA * np.median(np.abs(z - np.median(z))) / math.sqrt(z.size))

    dent = float(np.median(ring) - np.median(inner))
    return dent, math.hypot(median_se(inner), median_se(ring))


def press_behaviour(record: PressRecord | None, *,
                    released: tuple[float, float] | None = None,
                    modulus: tuple[float, float] | None = None,
                    anisotropy: Anisotropy | str | None = None) -> PressBehaviour:
    """The press's relaxation, loss, residual dent and class (module docstring).

    ``released`` is the camera's dent after release and its σ [m] (:func:`released_dent`), when
    one was seen; ``modulus`` the Young's modulus the loading ramp gave and its σ [Pa], when it
    gave one: it is the instantaneous modulus, and with a hold's fraction gives the relaxed one
    (:func:`relaxed_modulus`); ``anisotropy`` what the dent's shape during the press shows
    (:func:`~deformap.stiffness._anisotropy.dent_anisotropy`), or why it showed nothing (joins
    the evidence). A record with no hold, no unloading and no camera dent is ``"unknown"``.
    """
    got = _press_behaviour(record, released)
    if isinstance(anisotropy, str):
        got = replace(got, evidence=f"{got.evidence}; {anisotropy}")
    elif anisotropy is not None:
        got = replace(got, evidence=f"{got.evidence}; {anisotropy.evidence}",
                      isotropy=anisotropy.isotropy, anisotropy_ratio=anisotropy.ratio,
                      anisotropy_ratio_sigma=anisotropy.ratio_sigma,
                      anisotropy_axis_deg=anisotropy.axis_deg,
                      anisotropy_axis_sigma_deg=anisotropy.axis_sigma_deg)
    if modulus is None:
        return got
    e, e_sigma = (float(v) for v in modulus)
    if not (math.isfinite(e) and e > 0.0 and math.isfinite(e_sigma) and e_sigma >= 0.0):
        raise InvalidArgumentError(
            f"`modulus` must be a positive finite modulus and a σ >= 0 [Pa]; got {modulus!r}")
    relaxed = relaxed_modulus(e, e_sigma, got)
    return replace(got, modulus_instantaneous_pa=e, modulus_instantaneous_sigma_pa=e_sigma,
                   modulus_relaxed_pa=None if relaxed is None else relaxed[0],
                   modulus_relaxed_sigma_pa=None if relaxed is None else relaxed[1])


def relaxed_modulus(modulus_pa: float, sigma_pa: float, behaviour: PressBehaviour
                    ) -> tuple[float, float] | None:
    """The modulus at the hold's end [Pa] and its σ, from the instantaneous one and the hold's
    fraction ``f``: position held (``relaxation_mode`` ``"force"``), the force falls with the
    modulus, ``E∞ = E₀ (1 − f)``; force held (``"travel"``, creep), the travel under a fixed
    force goes as ``E^(−2/3)`` (Hertz), ``E∞ = E₀ (1 − f)^(3/2)``. σ by linear propagation of
    both σ. ``None`` without a fraction, or with one of 1 or more."""
    f, f_sigma = behaviour.relaxation, behaviour.relaxation_sigma
    if f is None or f_sigma is None or f >= 1.0:
        return None
    power = 1.5 if behaviour.relaxation_mode == "travel" else 1.0
    value = modulus_pa * (1.0 - f) ** power
    rel = math.hypot(sigma_pa / modulus_pa, power * f_sigma / (1.0 - f))
    return value, value * rel


def _press_behaviour(record: PressRecord | None, released: tuple[float, float] | None
                     ) -> PressBehaviour:
    if record is not None:
        _check_record(record)
    cam: Measure | None = None
    if released is not None:
        value, sigma = (float(v) for v in released)
        if not (math.isfinite(value) and math.isfinite(sigma) and sigma >= 0.0):
            raise InvalidArgumentError(
                f"`released` must be a finite dent and a σ >= 0 [m]; got {released!r}")
        cam = Measure(value, sigma)
    if record is None:
        if cam is None:
            return PressBehaviour(behaviour="unknown", evidence="no force–travel record")
        return _classify(None, None, None, None, None, cam, notes=["no force–travel record"])
    hold, unloading = record.hold, record.unloading
    if hold is None and unloading is None and cam is None:
        return PressBehaviour(behaviour="unknown", evidence="no hold or unloading recorded")
    force_parts = [np.asarray(record.force_n)]
    travel_parts = [np.asarray(record.travel_m)]
    for phase in (hold, unloading):
        if phase is not None:
            force_parts.append(np.asarray(phase.force_n))
            travel_parts.append(np.asarray(phase.travel_m))
    sigma_f, sigma_t = noise(force_parts), noise(travel_parts)
    notes: list[str] = []
    relax = tau = None
    mode: str | None = None
    if hold is not None:
        relax, tau, mode, note = hold_fraction(hold_with_start(record), sigma_f, sigma_t)
        if note:
            notes.append(note)
    loss = dent = None
    if unloading is not None:
        load_noise = force_noise(force_parts)  # the loss and the dent are its only readers
        got = loop_loss(record, load_noise, sigma_t)
        if isinstance(got, str):
            notes.append(got)
        else:
            loss = got
        creep = None if hold is None else hold_travel(hold_with_start(record), sigma_t)
        res = zero_force_travel(record, load_noise, sigma_t, creep)
        if isinstance(res, str):
            notes.append(res)
        else:
            dent = res
    return _classify(relax, tau, mode, loss, dent, cam, notes=notes,
                     has_hold=hold is not None, has_unloading=unloading is not None,
                     dent_floor=record_dent_floor(record))


def _classify(relax: Measure | None, tau: Measure | None, mode: str | None,
              loss: Measure | None, dent: Measure | None, cam: Measure | None, *,
              notes: list[str], has_hold: bool = False, has_unloading: bool = False,
              dent_floor: float = DENT_FLOOR_M) -> PressBehaviour:
    said: list[str] = []
    if relax is not None:
        said.append(relax.text("creep" if mode == "travel" else "relaxation"))
    if loss is not None:
        said.append(loss.text("loss ratio"))
    if dent is not None:
        said.append(dent.text("dent at zero force", 1e3, " mm"))
    if cam is not None:
        said.append(cam.text("dent after release", 1e3, " mm"))
    relaxes = relax is not None and relax.shows(RELAXATION_FLOOR)
    still = relax is not None and relax.rules_out(RELAXATION_FLOOR)
    lossy = loss is not None and loss.shows(LOSS_FLOOR)
    lossless = loss is not None and loss.rules_out(LOSS_FLOOR)
    dents = [(m, floor) for m, floor in ((dent, dent_floor), (cam, DENT_FLOOR_M)) if m is not None]
    kept = any(m.shows(floor) for m, floor in dents)
    # no dent: none shows one, and one rules it out (a camera too coarse to rule out a tenth of a
    # millimetre does not veto the record's travel at zero force)
    no_dent = not kept and any(m.rules_out(floor) for m, floor in dents)
    behaviour: Behaviour
    why: str
    if relaxes:
        behaviour, why = "viscoelastic", "the hold relaxes"
    elif kept and still:
        behaviour, why = "plastic", "a dent remains and the hold shows no relaxation"
    elif lossy and still:
        behaviour, why = "plastic", "the loop loses energy and the hold shows no relaxation"
    elif lossy and no_dent and not has_hold:
        behaviour, why = "viscoelastic", "the loop loses energy and no dent remains"
    elif kept and not has_hold:
        behaviour, why = "unknown", "a dent remains, but with no hold creep cannot be told from yield"
    elif (still or not has_hold) and no_dent and (lossless or not has_unloading) and \
            (has_unloading or has_hold):
        behaviour, why = "elastic", (f"relaxation, loss and dent all below their floors "
                                     f"({RELAXATION_FLOOR:g}, {LOSS_FLOOR:g}, "
                                     f"{dent_floor * 1e3:.2g} mm) by 2 σ")
    else:
        behaviour, why = "unknown", "the record neither shows nor rules out each behaviour"
        if not said:
            why = "the record gives no relaxation, loss or dent"
    evidence = "; ".join([why, *said, *notes])
    return PressBehaviour(
        behaviour=behaviour, evidence=evidence,
        relaxation=None if relax is None else float(relax.value),
        relaxation_sigma=None if relax is None else float(relax.sigma),
        relaxation_mode=None if relax is None else ("travel" if mode == "travel" else "force"),
        tau_s=None if tau is None else float(tau.value),
        tau_sigma_s=None if tau is None else float(tau.sigma),
        loss_ratio=None if loss is None else float(loss.value),
        loss_ratio_sigma=None if loss is None else float(loss.sigma),
        residual_dent_m=None if dent is None else float(dent.value),
        residual_dent_sigma_m=None if dent is None else float(dent.sigma),
        released_dent_m=None if cam is None else float(cam.value),
        released_dent_sigma_m=None if cam is None else float(cam.sigma))



def _check_record(record: Any) -> None:
    """A record must have a ForceTravel's parts, each finite (a ForceTravel checks the rest)."""
    names = ("travel_m", "force_n", "time_s", "hold", "unloading")
    if not all(hasattr(record, n) for n in names):
        raise InvalidArgumentError(
            f"`record` must be a ForceTravel or None; got {type(record).__name__}")
    parts = [("", record)] + [(f"{n}.", getattr(record, n)) for n in ("hold", "unloading")]
    for prefix, part in parts:
        if part is None:
            continue
        for name in ("time_s", "travel_m", "force_n"):
            values = getattr(part, name, None)
            if values is not None and not np.all(np.isfinite(np.asarray(values, dtype=float))):
                raise InvalidArgumentError(
                    f"`record.{prefix}{name}` holds NaN or infinite values")
