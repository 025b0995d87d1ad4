"""Angles and the sin(u)/u family: odomkit's one home for these numerics.

Wrapping
    :func:`wrap_angle` maps angles to [−π, π) (θ − 2π·⌊(θ + π)/2π⌋, computed exactly);
    :func:`unwrap_angle` undoes it along an array, making every step its wrapped value.

sin(u)/u
    ``sinc(u) = sin(u)/u`` with ``sinc(0) = 1`` (unnormalised: not numpy's
    ``np.sinc(x) = sin(πx)/(πx)``). The exact-arc step map (:mod:`odomkit.kinematics`)
    scales the chord by ``sinc(Δθ/2)``; its Jacobian needs ``d/dΔθ sinc(Δθ/2)``.
    :func:`sinc`, :func:`sinc_derivative` and :func:`sinc_pair` take u;
    :func:`sinc_half`, :func:`sinc_half_derivative` and :func:`sinc_half_pair` take Δθ.

Series and the one threshold
    Below |u| = :data:`SERIES_BELOW` = 1 every value comes from the Taylor series of
    sin u = Σ a_k u^(2k+1), a_k = (−1)^k/(2k+1)! (Abramowitz–Stegun 4.3.65): sinc(u) =
    Σ a_k u^(2k), cos u = Σ (2k+1)·a_k u^(2k) and sinc′(u) = Σ 2k·a_k u^(2k−1), each table
    rounded once from the exact rationals (:data:`SINC_COEFFS`, :data:`COS_COEFFS`,
    :data:`DSINC_COEFFS`). At and above it the direct formulas are used: sin(u)/u,
    libm's cos, and sinc′(u) = (u·cos u − sin u)/u².

    Why 1: sin(u)/u is accurate to rounding for every u ≠ 0, but the direct derivative
    cancels: u·cos u and sin u agree to within u³/3, so it loses about 3ε/u² relative
    (measured against mpmath: 800ε at |u| ≈ 0.08, 27ε at 0.4, 2.7ε at 1, ≤ 1.5ε beyond
    1.1; ε = 2.2e-16). From 1 on it is within a few ulp. Below 1 the series, cut after
    :data:`SERIES_TERMS` = 10 terms of each (sinc and cos to u¹⁸, sinc′ to u¹⁹), is
    exact to rounding: the first omitted terms at |u| = 1 are u²⁰/21! ≈ 2e-20 for sinc,
    u²⁰/20! ≈ 4e-19 (7.6e-19 relative) for cos and 22·u²¹/23! ≈ 9e-22 (3e-21 relative
    to |sinc′(1)| = 0.30) for sinc′, all under ε/100; the alternating terms fall fast,
    so Horner's rule adds only a few roundings. (With n terms each, sinc′'s relative
    truncation is 3/(2n+3) times sinc's.) Where sinc′ itself vanishes, at |u| ≈ 4.4934,
    no formula in u keeps its relative accuracy; the absolute error stays
    ~ε·(|u cos u| + |sin u|)/u² there.

    Small steps are the common case (|Δθ/2| < 0.015 on 99.99 % of a 100 Hz log), and
    there :data:`SHORT_TERMS` = 5 terms of the same tables suffice: below
    :data:`SHORT_BELOW` = 0.04 the first omitted terms are u¹⁰/11! < 3e-22 (sinc),
    u¹⁰/10! < 3e-21 (cos) and, relative to sinc′ ≈ −u/3, 36·u¹⁰/13! < 1e-22 (sinc′). The
    shorter Horner chain is what makes the kernels fast (measured 27 -> 19 ns a step in
    the covariance recursion). ``tests/test_angles.py`` checks these bounds in exact
    arithmetic and the values against mpmath at 50 digits.

Scalar versions for numba
    :func:`sin_cos_sinc` and :func:`sinc_derivative_scalar` are plain Python on floats,
    with the same tables, threshold and Horner order as the array functions (so the same
    bits where both run without FMA contraction). Their branch-free parts,
    :func:`sin_cos_sinc_series`, :func:`sin_cos_sinc_short` and
    :func:`sinc_derivative_short`, let a kernel's loop vectorise where it knows the
    range of its angles. This
    module never imports numba; the kernels compile these functions with
    :func:`odomkit.jit.njit` (``inline="always"``).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ANCHOR",
    "COS_COEFFS",
    "DSINC_COEFFS",
    "SERIES_BELOW",
    "SERIES_TERMS",
    "SHORT_BELOW",
    "SHORT_TERMS",
    "SINC_COEFFS",
    "TWO_PI",
    "sin_cos_sinc",
    "sin_cos_sinc_series",
    "sin_cos_sinc_short",
    "sinc",
    "sinc_derivative",
    "sinc_derivative_scalar",
    "sinc_derivative_short",
    "sinc_half",
    "sinc_half_derivative",
    "sinc_half_pair",
    "sinc_pair",
    "unwrap_angle",
    "wrap_angle",
]

TWO_PI = 2.0 * math.pi
"""2π as a float (exactly twice ``math.pi``): wrapping is modulo this number."""

SERIES_BELOW = 1.0
"""|u| below which the sin(u)/u family comes from its Taylor series, at and above which
from the direct formulas (the only such switch in odomkit; see the module notes)."""

SERIES_TERMS = 10
"""Terms of each series below :data:`SERIES_BELOW` (sinc and cos to u¹⁸, sinc′ to u¹⁹)."""

SHORT_BELOW = 0.04
"""|u| below which :data:`SHORT_TERMS` terms of the same series are already exact."""

SHORT_TERMS = 5
"""Terms of each series below :data:`SHORT_BELOW` (sinc and cos to u⁸, sinc′ to u⁹)."""

ANCHOR = 128
"""Kernels that carry the heading as a unit vector and turn it by each step's small angle
take a real cos/sin of the heading at least every ANCHOR steps: the turned vector then
drifts by at most ~ANCHOR roundings (~1e-14) from (cos θ, sin θ)."""


# a_k = (−1)^k/(2k+1)!, rounded once from the exact rational.
SINC_COEFFS: tuple[float, ...] = tuple(
    float(Fraction((-1) ** k, math.factorial(2 * k + 1))) for k in range(SERIES_TERMS))
"""Coefficients of u^(2k) in sinc(u), k = 0 … SERIES_TERMS − 1."""
COS_COEFFS: tuple[float, ...] = tuple(
    float(Fraction((-1) ** k * (2 * k + 1), math.factorial(2 * k + 1))) for k in range(SERIES_TERMS))
"""Coefficients of u^(2k) in cos u: (2k+1)·a_k = (−1)^k/(2k)!."""
DSINC_COEFFS: tuple[float, ...] = tuple(
    float(Fraction((-1) ** k * 2 * k, math.factorial(2 * k + 1))) for k in range(1, SERIES_TERMS + 1))
"""Coefficients of u^(2k−1) in sinc′(u): 2k·a_k, k = 1 … SERIES_TERMS."""

# Horner order (highest power first) for the array and scalar evaluations alike.
_SINC_SHORT = SINC_COEFFS[:SHORT_TERMS][::-1]
_COS_SHORT = COS_COEFFS[:SHORT_TERMS][::-1]
_DSINC_SHORT = DSINC_COEFFS[:SHORT_TERMS][::-1]
_SINC_FULL = SINC_COEFFS[::-1]
_COS_FULL = COS_COEFFS[::-1]
_DSINC_FULL = DSINC_COEFFS[::-1]


# --------------------------------------------------------------------------- wrapping


def wrap_angle(theta: ArrayLike) -> NDArray[np.float64]:
    """Wrap angles to [−π, π): θ − 2π·⌊(θ + π)/2π⌋, with 2π = :data:`TWO_PI`.

    Computed without rounding: ``fmod`` is exact, and the one ±2π shift that follows
    is exact too (Sterbenz: both operands lie within a factor 2 of each other). So the
    result lies in [−π, π) for every finite θ, however large, and +π maps to −π.

    Parameters
    ----------
    theta : array_like
        Angles [rad], any shape.

    Returns
    -------
    ndarray (numpy scalar for scalar input)
        The angles wrapped to [−π, π) [rad], same shape.

    Examples
    --------
    >>> float(wrap_angle(-5.0)), float(wrap_angle(np.pi)), float(wrap_angle(3 * np.pi / 2))
    (1.2831853071795862, -3.141592653589793, -1.5707963267948966)
    """
    r = np.fmod(np.asarray(theta, dtype=float), TWO_PI)  # exact; in (−2π, 2π)
    return r - TWO_PI * (r >= math.pi) + TWO_PI * (r < -math.pi)


def unwrap_angle(theta: ArrayLike, axis: int = -1) -> NDArray[np.float64]:
    """Undo :func:`wrap_angle` along ``axis``: every step becomes its wrapped value.

    Each step θ[i+1] − θ[i] is replaced by ``wrap_angle`` of it (so all steps lie in
    [−π, π)), by adding the accumulated multiples of 2π to θ; steps already in
    (−π, π) leave θ untouched. Like :func:`numpy.unwrap`, except that a step of
    exactly +π becomes −π, by the same convention as :func:`wrap_angle`.

    Parameters
    ----------
    theta : array_like
        Angles [rad], at least 1-D.
    axis : int
        Axis along which the angles follow each other.

    Returns
    -------
    ndarray
        Continuous angles [rad], same shape; the first sample along ``axis`` is kept.

    Examples
    --------
    >>> unwrap_angle([3.0, -3.0, -2.0]).round(6).tolist()
    [3.0, 3.283185, 4.283185]
    """
    p = np.asarray(theta, dtype=float)
    step = np.diff(p, axis=axis)
    correction = wrap_angle(step) - step  # exactly 0 where |step| < π
    out = p.copy()
    tail = [slice(None)] * p.ndim
    tail[axis] = slice(1, None)
    out[tuple(tail)] += np.cumsum(correction, axis=axis)
    return out


# --------------------------------------------------------------------- sin(u)/u, arrays


def _horner(v: NDArray[np.float64], coeffs: tuple[float, ...]) -> NDArray[np.float64]:
    """Σ c·v^j with ``coeffs`` highest power first, one multiply and one add per term."""
    acc = np.full_like(v, coeffs[0])
    for c in coeffs[1:]:
        acc *= v
        acc += c
    return acc


def _sinc_parts(u: ArrayLike, want_value: bool, want_derivative: bool
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """sinc(u) and sinc′(u) (each only if wanted; else an empty array), shape of ``u``.

    The short series runs over all entries; entries at or above :data:`SHORT_BELOW`
    (NaN included) are then redone with the full series or the direct formulas, which is
    cheap on odometry steps because they are rare.
    """
    x = np.asarray(u, dtype=float)
    shape = x.shape
    x = x.ravel()
    v = x * x
    empty = np.empty(0)
    f = _horner(v, _SINC_SHORT) if want_value else empty
    df = x * _horner(v, _DSINC_SHORT) if want_derivative else empty
    rest = np.flatnonzero(~(np.abs(x) < SHORT_BELOW))
    if rest.size:
        in_series = np.abs(x[rest]) < SERIES_BELOW
        mid, big = rest[in_series], rest[~in_series]
        if mid.size:
            xm = x[mid]
            vm = xm * xm
            if want_value:
                f[mid] = _horner(vm, _SINC_FULL)
            if want_derivative:
                df[mid] = xm * _horner(vm, _DSINC_FULL)
        if big.size:
            xb = x[big]
            sb = np.sin(xb)
            if want_value:
                f[big] = sb / xb
            if want_derivative:
                df[big] = (xb * np.cos(xb) - sb) / (xb * xb)
    return (f.reshape(shape) if want_value else f), (df.reshape(shape) if want_derivative else df)


def sinc(u: ArrayLike) -> NDArray[np.float64]:
    """sin(u)/u, with sinc(0) = 1 (series below :data:`SERIES_BELOW`).

    Parameters
    ----------
    u : array_like
        Angles [rad], any shape.

    Returns
    -------
    ndarray
        sin(u)/u [1], same shape.

    Examples
    --------
    >>> float(sinc(0.0)), round(float(sinc(np.pi / 2)), 12)
    (1.0, 0.636619772368)
    """
    return _sinc_parts(u, True, False)[0]


def sinc_derivative(u: ArrayLike) -> NDArray[np.float64]:
    """d/du sin(u)/u = (u·cos u − sin u)/u², series below :data:`SERIES_BELOW` (−u/3 near 0).

    Parameters
    ----------
    u : array_like
        Angles [rad], any shape.

    Returns
    -------
    ndarray
        sinc′(u) [1/rad], same shape.
    """
    return _sinc_parts(u, False, True)[1]


def sinc_pair(u: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(:func:`sinc`, :func:`sinc_derivative`) of ``u`` in one pass, same shape as ``u``."""
    return _sinc_parts(u, True, True)


def sinc_half(dtheta: ArrayLike) -> NDArray[np.float64]:
    """sin(Δθ/2)/(Δθ/2), the chord-to-arc factor of a turn Δθ [rad]; 1 at Δθ = 0.

    Examples
    --------
    >>> float(sinc_half(0.0)), round(float(sinc_half(np.pi)), 12)
    (1.0, 0.636619772368)
    """
    return sinc(0.5 * np.asarray(dtheta, dtype=float))


def sinc_half_derivative(dtheta: ArrayLike) -> NDArray[np.float64]:
    """d/dΔθ of :func:`sinc_half` = ½·sinc′(Δθ/2) [1/rad]; −Δθ/12 near Δθ = 0."""
    return 0.5 * sinc_derivative(0.5 * np.asarray(dtheta, dtype=float))


def sinc_half_pair(dtheta: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(:func:`sinc_half`, :func:`sinc_half_derivative`) of Δθ in one pass, vectorised.

    Parameters
    ----------
    dtheta : array_like
        Heading change of each step [rad], any shape.

    Returns
    -------
    f, df : ndarray
        sinc(Δθ/2) [1] and d/dΔθ sinc(Δθ/2) [1/rad], same shape as ``dtheta``.
    """
    f, df = sinc_pair(0.5 * np.asarray(dtheta, dtype=float))
    df *= 0.5
    return f, df


# -------------------------------------------------------------- sin(u)/u, scalar (numba)
# Plain Python on floats, compiled by odomkit.jit.njit inside the kernels. Each function
# writes its Horner loops out (a compiled function can call only compiled functions);
# numba unrolls a loop over a constant tuple, so these run as fast as written-out
# polynomials. Coefficients are multiplied, never divided: a division costs several
# products.


def sin_cos_sinc_series(phi: float) -> tuple[float, float, float]:
    """sin φ, cos φ, sin φ/φ from all :data:`SERIES_TERMS` series terms; only for
    |φ| < :data:`SERIES_BELOW`. Branch-free, so a loop over it vectorises."""
    p2 = phi * phi
    s = _SINC_FULL[0]
    for a in _SINC_FULL[1:]:
        s = s * p2 + a
    c = _COS_FULL[0]
    for a in _COS_FULL[1:]:
        c = c * p2 + a
    return phi * s, c, s


def sin_cos_sinc_short(phi: float) -> tuple[float, float, float]:
    """sin φ, cos φ, sin φ/φ from the :data:`SHORT_TERMS` series terms; only for
    |φ| < :data:`SHORT_BELOW`, where it gives the bits of :func:`sin_cos_sinc`.
    Branch-free, so a loop over it vectorises (the kernels check the range per block)."""
    p2 = phi * phi
    s = _SINC_SHORT[0]
    for a in _SINC_SHORT[1:]:
        s = s * p2 + a
    c = _COS_SHORT[0]
    for a in _COS_SHORT[1:]:
        c = c * p2 + a
    return phi * s, c, s


def sinc_derivative_short(u: float) -> float:
    """d/du sin(u)/u from the :data:`SHORT_TERMS` series terms; only for
    |u| < :data:`SHORT_BELOW`, where it gives the bits of :func:`sinc_derivative_scalar`.
    Branch-free, like :func:`sin_cos_sinc_short`."""
    v = u * u
    d = _DSINC_SHORT[0]
    for a in _DSINC_SHORT[1:]:
        d = d * v + a
    return u * d


def sin_cos_sinc(phi: float) -> tuple[float, float, float]:
    """sin φ, cos φ, sin φ/φ of one float, as the array functions compute them: short
    series below :data:`SHORT_BELOW`, full series below :data:`SERIES_BELOW`, libm above.
    """
    p2 = phi * phi
    if abs(phi) < SHORT_BELOW:
        s = _SINC_SHORT[0]
        for a in _SINC_SHORT[1:]:
            s = s * p2 + a
        c = _COS_SHORT[0]
        for a in _COS_SHORT[1:]:
            c = c * p2 + a
        return phi * s, c, s
    if abs(phi) < SERIES_BELOW:
        s = _SINC_FULL[0]
        for a in _SINC_FULL[1:]:
            s = s * p2 + a
        c = _COS_FULL[0]
        for a in _COS_FULL[1:]:
            c = c * p2 + a
        return phi * s, c, s
    sin_phi = math.sin(phi)  # NaN lands here too, and propagates
    return sin_phi, math.cos(phi), sin_phi / phi


def sinc_derivative_scalar(u: float, sin_u: float, cos_u: float) -> float:
    """d/du sin(u)/u of one float, as :func:`sinc_derivative` computes it; ``sin_u`` and
    ``cos_u`` (from :func:`sin_cos_sinc`) are used only at and above :data:`SERIES_BELOW`."""
    v = u * u
    if abs(u) < SHORT_BELOW:
        d = _DSINC_SHORT[0]
        for a in _DSINC_SHORT[1:]:
            d = d * v + a
        return u * d
    if abs(u) < SERIES_BELOW:
        d = _DSINC_FULL[0]
        for a in _DSINC_FULL[1:]:
            d = d * v + a
        return u * d
    return (u * cos_u - sin_u) / v
