"""The rotation ``R`` of the polar decomposition ``A = R S`` of batches of 3×3 matrices (Müller et
al. 2005), by SVD, or by Higham's (1986) scaled Newton iteration from a closed-form start.

References
----------
Higham, N. J. (1986). Computing the polar decomposition — with applications. SIAM J. Sci.
Stat. Comput. 7(4), 1160–1174.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["fast_polar_rotation", "polar_components", "polar_rotation"]

Array = NDArray[np.float64]


def polar_rotation(a: Array) -> Array:
    """Rotation factor ``R`` of the polar decomposition ``A = R S`` of ``(..., 3, 3)`` matrices:
    ``R = U diag(1, 1, det(U Vᵀ)) Vᵀ`` from the SVD, a proper rotation also for rank-2 ``A`` or
    ``det A < 0`` (Kabsch)."""
    u, _, vt = np.linalg.svd(a)
    det = np.linalg.det(u @ vt)
    u[..., :, 2] *= np.where(det < 0.0, -1.0, 1.0)[..., None]
    return u @ vt


def fast_polar_rotation(a: Array, *, tol: float = 1e-14, max_iter: int = 30) -> Array:
    """``polar_rotation(a)`` by Higham's ``X ← (γ X + X⁻ᵀ / γ) / 2``, ``γ = |det X|^(−1/3)``; a small
    or negative relative determinant, or no convergence, gets the SVD answer."""
    shape = a.shape
    m = np.ascontiguousarray(a.reshape(-1, 9).T)
    return np.asarray(polar_components(m, tol=tol, max_iter=max_iter).T.reshape(shape))


def polar_components(m: Array, *, tol: float = 1e-14, max_iter: int = 30) -> Array:
    """:func:`fast_polar_rotation` of ``(9, n)`` component-major (row-major 3×3) matrices."""
    norm = np.sqrt(np.sum(m * m, axis=0))
    x = m / np.maximum(norm, np.finfo(float).tiny)
    cof0, det0 = _cofactors(x)
    safe = det0 > 1e-9  # scaled Newton copes with any positive det; flat ones go to SVD
    all_safe = bool(np.all(safe))
    # from the closed-form estimate R h(U) (h ≈ 1, SPD) Newton lands on R in a step or two
    if all_safe:
        cur = _polar_start(x, cof0, det0)
    else:
        cur = _polar_start(np.ascontiguousarray(x[:, safe]), np.ascontiguousarray(cof0[:, safe]),
                           det0[safe])
    step = np.inf
    for _ in range(max_iter):
        cof, det = _cofactors(cur)
        # X ← (X / c + c X⁻ᵀ) / 2 with c = ∛det (Higham 1986, §3), halving folded into factors
        gamma = np.cbrt(det)
        new = cur * (0.5 / gamma)
        cof *= 0.5 * gamma / det
        new += cof
        diff = np.subtract(cur, new, out=cur)  # ``cur`` is a start or an iterate, never ``x``
        np.abs(diff, out=diff)
        step = float(diff.max()) if diff.size else 0.0
        cur = new
        if step < tol**0.5:  # quadratic convergence: the next step would be below tol
            break
    if all_safe and step < tol**0.5:
        return cur
    cof, det = _cofactors(cur)
    gamma = np.cbrt(det)
    ok = np.max(np.abs(0.5 * (cur / gamma + cof / (det / gamma)) - cur), axis=0) < tol**0.5
    out = np.empty_like(x)
    out[:, safe] = cur
    redo = ~safe
    redo[np.flatnonzero(safe)[~ok]] = True
    out[:, redo] = polar_rotation(x[:, redo].T.reshape(-1, 3, 3)).reshape(-1, 9).T
    return out


def _polar_start(x: Array, cof: Array, det: Array) -> Array:
    """``R h(U)``, ``h(U) ≈ I`` SPD, for ``(9, n)`` row-major ``x = R U``, unit norm, ``det > 0``
    (``cof`` overwritten): ``R = [(I_U² − II_U) x + I_U cof(x) − x xᵀx] / (I_U II_U − det x)``
    with the invariants of ``U = √(xᵀx)``."""
    a, b, c, d, e, f, g, h, i = x
    # invariants of C = xᵀx from sums of squares: tr C = ‖x‖² = 1, II_C = ‖cof x‖², det C = det²
    ii = np.sum(cof * cof, axis=0)
    # largest eigenvalue of C (trigonometric solution of its characteristic cubic)
    p = np.sqrt(np.maximum(1.0 / 9.0 - ii / 3.0, 0.0))
    half = np.maximum(2.0 * p**3, np.finfo(float).tiny)
    r = np.clip((2.0 / 27.0 - ii / 3.0 + det * det) / half, -1.0, 1.0)
    lam1 = 1.0 / 3.0 + 2.0 * p * np.cos(np.arccos(r) / 3.0)
    # the singular values σ₁ = √λ₁ and σ₂ σ₃ = det / σ₁, σ₂ + σ₃ = √(λ₂ + λ₃ + 2 σ₂ σ₃)
    s1 = np.sqrt(lam1)
    s23 = det / s1
    s2_s3 = np.sqrt(np.maximum((ii - det * det / lam1) / lam1, 0.0) + 2.0 * s23)
    i_u = s1 + s2_s3
    ii_u = s1 * s2_s3 + s23
    denom = i_u * ii_u - det
    # x C, C = xᵀx symmetric
    c11, c22, c33 = a * a + d * d + g * g, b * b + e * e + h * h, c * c + f * f + i * i
    c12, c13, c23 = a * b + d * e + g * h, a * c + d * f + g * i, b * c + e * f + h * i
    out = x * ((i_u * i_u - ii_u) / denom)
    cof *= i_u / denom
    out += cof
    inv = 1.0 / denom
    for row, (u, v, w) in enumerate(((a, b, c), (d, e, f), (g, h, i))):
        out[3 * row] -= (u * c11 + v * c12 + w * c13) * inv
        out[3 * row + 1] -= (u * c12 + v * c22 + w * c23) * inv
        out[3 * row + 2] -= (u * c13 + v * c23 + w * c33) * inv
    return out


def _cofactors(m: Array) -> tuple[Array, Array]:
    """Cofactors ``(9, n)`` and determinants ``(n,)`` of ``(9, n)`` row-major 3×3 matrices."""
    a, b, c, d, e, f, g, h, i = m
    cof = np.empty_like(m)
    for row, (p, q, r, t) in enumerate(((e, i, f, h), (f, g, d, i), (d, h, e, g),
                                        (c, h, b, i), (a, i, c, g), (b, g, a, h),
                                        (b, f, c, e), (c, d, a, f), (a, e, b, d))):
        np.multiply(p, q, out=cof[row])
        cof[row] -= r * t
    det = a * cof[0] + b * cof[1] + c * cof[2]
    return cof, det
