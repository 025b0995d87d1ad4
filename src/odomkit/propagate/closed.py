"""Closed-form covariance of one constant-curvature segment (Chong–Kleeman; the
classical model they criticise).

One derivation serves every integrated-heading model (Chong–Kleeman per-wheel noise here,
Kelly's gyro odometry in :mod:`odomkit.propagate.closed_kelly`). Parametrise the segment
by the fraction τ ∈ [0, 1] travelled. In the segment's local frame (start at the origin,
heading 0) the heading is φ = τ·a with ``a = Δθ``, and the arc length is τ·D. A
perturbation ``ds`` of the travelled length and ``dθ`` of the heading at τ moves the end
pose by (linearised; Kelly eq. 11 "input transition matrix", Chong–Kleeman eq. 21–24 in
the limit k -> ∞)::

    A(τ) = [[cos φ, −(y₁ − y(τ))],
            [sin φ,   x₁ − x(τ) ],
            [0,       1         ]]

with ``x₁ − x(τ) = D·(sin a − sin φ)/a`` and ``y₁ − y(τ) = D·(cos φ − cos a)/a``. If the
noise density Q per unit τ is constant along the segment (true for both papers' noise
models at constant wheel speeds), the added covariance is ``∫₀¹ A Q Aᵀ dτ``, a sum of 14
scalar integrals of a alone, times Q and powers of D; see :func:`arc_integrals`.

Those integrals are evaluated by two branches (see :data:`SERIES_BELOW`): trigonometric
closed forms for |a| >= 1, a Taylor series in a (exact polynomial integration, entire
functions, so it converges for any a) below. The closed forms divide differences of O(1)
terms by up to a², losing ~1/a⁴ ulps as a -> 0; the series loses accuracy only through
alternation, ~e^|a| ulps. At |a| = 1 both are within ~10 ulps (tested: the branches
agree to 4e-15 relative for 0.9 <= |a| <= 1.1, and both match quadrature to 1e-12).
Straight lines (a = 0), spins (D = 0), zero-length and reversing segments (signed D and
a, |L|, |R| in the noise) are therefore the same formulas, never a special case.

The result equals Chong–Kleeman eq. (25) wherever that is defined (tested), and its
limits are their eq. (26)–(28). Misprints in Chong–Kleeman found on the way (each
checked numerically in tests/propagate/test_closed.py):

* eq. (26), Cov₂₂: last term printed ``D²/(3B²)·sin²θ_k``; it is ``cos²θ_k`` (rotating
  eq. 27, which is right, by θ_k), the known trap.
* eq. (28): the text substitutes ``L -> (B/2)(θ_k − θ₀)``, ``R -> (B/2)(θ₀ − θ_k)``, which
  by eq. (14) turns the wrong way; the printed results hold for L = −(B/2)Δθ,
  R = +(B/2)Δθ.
* eq. (17): the four position entries print ``r_k cos θ_k`` / ``r_k sin θ_k`` where
  eq. (22) (right, by finite differences) has ``r/B``; and ∂y/∂R prints ``−BL_k`` for
  ``+BL_k``.
* eq. (21): the product over i = m…n involves θ_{m−1}, not θ_m (eq. 23 uses θ₀ for
  i = 1…k, consistently with θ_{m−1}); eq. (23)–(24) omit the factor ∇_u f between the
  product and diag(k²|L_i|, k²|R_i|) (3×3 times 2×2 as printed).
* eq. (4): "k_L² and k_R² are constants with unit m^½": k has unit m^½, k² is in m.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError
from odomkit.kinematics import step_displacement
from odomkit.noise import ClassicalNoise, WheelNoise

__all__ = [
    "INTEGRALS", "SERIES_BELOW", "arc_added_cov_local", "arc_integrals", "chain_cov", "classical_step",
    "pose_transition", "rotate_cov", "wheel_arc_cov", "wheel_arc_noise"
]

SERIES_BELOW = 1.0
"""|Δθ| [rad] below which the Taylor series of the arc integrals is used."""

_SERIES_ORDER = 30  # terms ~ |a|^n/n!: 1/30! ~ 4e-33, far below rounding for |a| < 1

# Order of the integrals returned by arc_integrals (the names used in the derivation).
INTEGRALS = (
    "c", "s", "cc", "cs", "ss", "cp", "sp", "cq", "sq", "pp", "pq", "qq", "p", "q",
)


def _factor_series(name: str, n: int) -> NDArray[np.float64]:
    """Bivariate Taylor coefficients F[i, j] of a^i·τ^j of one integrand factor."""
    f = np.zeros((n + 1, n + 2))
    for k in range(n + 2):
        sign = (-1.0) ** (k // 2)
        if name == "1" and k == 0:
            f[0, 0] = 1.0
        if k % 2 == 0 and k <= n:  # even powers
            if name == "c":
                f[k, k] = sign / math.factorial(k)
            if name == "q":  # (sin a − sin τa)/a: coefficient of a^k is from a^(k+1)
                f[k, 0] += sign / math.factorial(k + 1)
                f[k, k + 1] -= sign / math.factorial(k + 1)
        if k % 2 == 1 and k <= n:  # odd powers
            if name == "s":
                f[k, k] = sign / math.factorial(k)
            if name == "p":  # −(cos τa − cos a)/a: from a^(k+1), sign of a^(k+1) term
                sign_next = (-1.0) ** ((k + 1) // 2)
                f[k, k + 1] -= sign_next / math.factorial(k + 1)
                f[k, 0] += sign_next / math.factorial(k + 1)
    return f


@lru_cache(maxsize=1)
def _series_table() -> NDArray[np.float64]:
    """Taylor coefficients (in a) of the 14 arc integrals, shape (14, order + 1)."""
    n = _SERIES_ORDER
    factors = {name: _factor_series(name, n) for name in ("1", "c", "s", "p", "q")}
    weights = 1.0 / np.arange(1, 2 * n + 4)  # ∫₀¹ τ^j dτ = 1/(j + 1)
    table = np.zeros((len(INTEGRALS), n + 1))
    for row, name in enumerate(INTEGRALS):
        f = factors[name[0]]
        g = factors[name[1]] if len(name) == 2 else factors["1"]
        for order in range(n + 1):
            poly = np.zeros(2 * n + 3)
            for i in range(order + 1):
                prod = np.convolve(f[i], g[order - i])
                poly[: prod.size] += prod
            # fsum: exact rational coefficients (1/3 at a = 0) come out correctly rounded
            table[row, order] = math.fsum(poly * weights[: poly.size])
    return table


def arc_integrals(a: ArrayLike) -> NDArray[np.float64]:
    """The 14 integrals over τ ∈ [0, 1] that make up the covariance of an arc.

    With φ = τ·a, c = cos φ, s = sin φ, p = −(cos φ − cos a)/a, q = (sin a − sin φ)/a
    (so that y₁ − y = −D·p and x₁ − x = D·q), the rows are, in the order of
    :data:`INTEGRALS`: ∫c, ∫s, ∫c², ∫cs, ∫s², ∫cp, ∫sp, ∫cq, ∫sq, ∫p², ∫pq, ∫q², ∫p, ∫q.

    Parameters
    ----------
    a : array_like, shape (...)
        Heading change Δθ of the segment [rad].

    Returns
    -------
    ndarray, shape (14, ...)

    Examples
    --------
    On a straight line ∫q² = ∫(1 − τ)² dτ = 1/3 and ∫cq = 1/2:

    >>> vals = dict(zip(INTEGRALS, arc_integrals(0.0)))
    >>> float(vals["qq"]), float(vals["cq"])
    (0.3333333333333333, 0.5)
    """
    a = np.asarray(a, dtype=float)
    small = np.abs(a) < SERIES_BELOW
    series = np.polynomial.polynomial.polyval(np.where(small, a, 0.0), _series_table().T)
    x = np.where(small, 1.0, a)  # any value: those entries are replaced by the series
    C, S = np.cos(x), np.sin(x)
    i_c = S / x
    i_s = (1.0 - C) / x
    i_cc = 0.5 + S * C / (2.0 * x)
    i_ss = 0.5 - S * C / (2.0 * x)
    i_cs = S * S / (2.0 * x)
    direct = np.stack([
        i_c,
        i_s,
        i_cc,
        i_cs,
        i_ss,
        -(i_cc - C * i_c) / x,  # ∫c·p
        -(i_cs - C * i_s) / x,  # ∫s·p
        (S * i_c - i_cs) / x,  # ∫c·q
        (S * i_s - i_ss) / x,  # ∫s·q
        (i_cc - 2.0 * C * i_c + C * C) / x**2,  # ∫p²
        -(S * i_c - i_cs - C * S + C * i_s) / x**2,  # ∫p·q
        (S * S - 2.0 * S * i_s + i_ss) / x**2,  # ∫q²
        -(i_c - C) / x,  # ∫p
        (S - i_s) / x,  # ∫q
    ])
    return np.where(small, series, direct)


def arc_added_cov_local(
    length: ArrayLike, dtheta: ArrayLike, q_ss: ArrayLike, q_st: ArrayLike, q_tt: ArrayLike
) -> NDArray[np.float64]:
    """``∫₀¹ A Q Aᵀ dτ`` for one arc, in the frame of its start pose.

    Parameters
    ----------
    length : array_like, shape (...)
        Signed arc length D of the reference point [m].
    dtheta : array_like, shape (...)
        Heading change a [rad].
    q_ss, q_st, q_tt : array_like, shape (...)
        Noise of (ds, dθ) accumulated over the whole segment, i.e. the density per unit
        τ: var(ds) [m²], cov(ds, dθ) [m·rad], var(dθ) [rad²].

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Covariance added to the end pose, in the start frame, order x, y, θ.

    Examples
    --------
    Straight line, heading noise only: σ_y² = q_tt·D²/3 (Kelly eq. 13's s²t/3 term).

    >>> cov = arc_added_cov_local(2.0, 0.0, 0.0, 0.0, 3.0)
    >>> float(cov[1, 1]), float(cov[1, 2]), float(cov[2, 2])
    (4.0, 3.0, 3.0)
    """
    d, a, qss, qst, qtt = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                                for v in (length, dtheta, q_ss, q_st, q_tt)))
    i = dict(zip(INTEGRALS, arc_integrals(a), strict=True))
    cov = np.empty(d.shape + (3, 3))
    # A = [[c, D·p], [s, D·q], [0, 1]] (p, q as in arc_integrals), so each entry is
    # q_ss·∫(col 1 products) + q_st·D·∫(cross products) + q_tt·D²·∫(col 2 products).
    cov[..., 0, 0] = qss * i["cc"] + 2.0 * qst * d * i["cp"] + qtt * d * d * i["pp"]
    cov[..., 1, 1] = qss * i["ss"] + 2.0 * qst * d * i["sq"] + qtt * d * d * i["qq"]
    cov[..., 0, 1] = qss * i["cs"] + qst * d * (i["cq"] + i["sp"]) + qtt * d * d * i["pq"]
    cov[..., 0, 2] = qst * i["c"] + qtt * d * i["p"]
    cov[..., 1, 2] = qst * i["s"] + qtt * d * i["q"]
    cov[..., 2, 2] = qtt
    cov[..., 1, 0] = cov[..., 0, 1]
    cov[..., 2, 0] = cov[..., 0, 2]
    cov[..., 2, 1] = cov[..., 1, 2]
    return cov


def rotate_cov(cov: ArrayLike, theta: ArrayLike) -> NDArray[np.float64]:
    """Express a pose covariance given in a frame rotated by ``theta`` in the world frame.

    ``T·cov·Tᵀ`` with T = diag(Rot(θ), 1); shapes (..., 3, 3) and (...).
    """
    cov = np.asarray(cov, dtype=float)
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    rot = np.zeros(np.shape(theta) + (3, 3))
    rot[..., 0, 0], rot[..., 0, 1] = c, -s
    rot[..., 1, 0], rot[..., 1, 1] = s, c
    rot[..., 2, 2] = 1.0
    return rot @ cov @ np.swapaxes(rot, -1, -2)


def pose_transition(dx: ArrayLike, dy: ArrayLike) -> NDArray[np.float64]:
    """Transition matrix of a segment with world displacement (dx, dy), shape (..., 3, 3).

    An initial heading error δθ swings the whole segment about its start:
    ``[[1, 0, −Δy], [0, 1, Δx], [0, 0, 1]]`` (Chong–Kleeman eq. 21/23 with
    r(cos θ₀ − cos θ_k) = −Δy; Kelly's Φ(t, τ) in section 3.2).
    """
    dx = np.asarray(dx, dtype=float)
    dy = np.asarray(dy, dtype=float)
    phi = np.zeros(np.broadcast_shapes(dx.shape, dy.shape) + (3, 3))
    phi[..., 0, 0] = phi[..., 1, 1] = phi[..., 2, 2] = 1.0
    phi[..., 0, 2] = -dy
    phi[..., 1, 2] = dx
    return phi


def wheel_arc_noise(
    left: ArrayLike, right: ArrayLike, wheel_base: float, noise: WheelNoise
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Whole-segment covariance of (ds, dθ) from per-wheel noise.

    Chong–Kleeman eq. (4)/(18): var(L) = k_L²|L|, var(R) = k_R²|R|, independent; with
    ds = (dR + dL)/2 and dθ = (dR − dL)/B (Chong–Kleeman eq. 14–15). Returns
    (q_ss [m²], q_st [m·rad], q_tt [rad²]).
    """
    var_left = noise.k_left**2 * np.abs(np.asarray(left, dtype=float))
    var_right = noise.k_right**2 * np.abs(np.asarray(right, dtype=float))
    return (
        0.25 * (var_left + var_right),
        (var_right - var_left) / (2.0 * wheel_base),
        (var_left + var_right) / wheel_base**2,
    )


def _check_wheel_base(wheel_base: float | None) -> float:
    if wheel_base is None or not (math.isfinite(wheel_base) and wheel_base > 0):
        raise ModelError(f"wheel_base must be a positive number of metres, got {wheel_base!r}")
    return float(wheel_base)


def wheel_arc_cov(
    left: float,
    right: float,
    wheel_base: float,
    noise: WheelNoise,
    theta0: float = 0.0,
    cov0: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Covariance at the end of one arc under per-wheel noise (Chong–Kleeman eq. 23, 25).

    ``Φ·cov0·Φᵀ + T·(∫₀¹ A Q Aᵀ dτ)·Tᵀ``: the incoming covariance carried through the
    segment's transition matrix plus the covariance the wheels add, rotated from the
    segment's start frame to the world. Consistent: splitting the arc into pieces and
    chaining this function gives the same result (to rounding).

    Parameters
    ----------
    left, right : float
        Signed travel of the left and right wheel [m] (negative = backwards).
    wheel_base : float
        B [m].
    noise : WheelNoise
        k_L, k_R [m^½].
    theta0 : float
        Heading at the start of the segment [rad].
    cov0 : array_like, shape (3, 3), optional
        Covariance of the start pose (default zero).

    Returns
    -------
    ndarray, shape (3, 3)

    Examples
    --------
    A straight metre with k = 1 mm/√m on both wheels: σ_x² = k²·D/2 (eq. 27).

    >>> cov = wheel_arc_cov(1.0, 1.0, 0.4, WheelNoise(0.001, 0.001))
    >>> round(float(cov[0, 0]) / 0.5e-6, 12)
    1.0
    """
    b = _check_wheel_base(wheel_base)
    d, a = 0.5 * (left + right), (right - left) / b  # Chong–Kleeman eq. (14)–(15)
    added = arc_added_cov_local(d, a, *wheel_arc_noise(left, right, b, noise))
    return chain_cov(d, a, theta0, cov0, added)


def chain_cov(
    length: float,
    dtheta: float,
    theta0: float,
    cov0: ArrayLike | None,
    added_local: NDArray[np.float64],
) -> NDArray[np.float64]:
    """End-of-segment covariance ``Φ·cov0·Φᵀ + T·added_local·Tᵀ`` (Chong–Kleeman eq. 23).

    ``length`` [m] and ``dtheta`` [rad] define the arc, ``theta0`` [rad] its start
    heading; ``added_local`` (3, 3) is :func:`arc_added_cov_local`'s result. Returns a
    symmetrised (3, 3) matrix.
    """
    d, a = length, dtheta
    cov = rotate_cov(added_local, theta0)
    if cov0 is not None:
        dx, dy = step_displacement(theta0, d, a, "exact")
        phi = pose_transition(dx, dy)
        cov = cov + phi @ np.asarray(cov0, dtype=float) @ phi.T
    return 0.5 * (cov + np.swapaxes(cov, -1, -2))


def classical_step(
    pose: ArrayLike, cov: ArrayLike, distance: float, angle: float, noise: ClassicalNoise
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One step of the classical model: rotate by α, then translate by D.

    Chong–Kleeman eq. (1)–(3): ``x' = x + D cos(θ + α)``, ``y' = y + D sin(θ + α)``,
    ``θ' = θ + α`` and ``P' = F P Fᵀ + G diag(σ_D², σ_α²) Gᵀ``. The noise is per *step*,
    whatever its length, which is why the model is inconsistent (their 2D vs D + D
    example).

    Parameters
    ----------
    pose : array_like, shape (3,)
    cov : array_like, shape (3, 3)
    distance, angle : float
        D_k [m] and α_k [rad].
    noise : ClassicalNoise

    Returns
    -------
    pose, cov : ndarray, shapes (3,) and (3, 3)

    Examples
    --------
    Chong–Kleeman's case (i): 2D = 2 in one step, σ_D = σ_α = 1 gives var(y) = 4D² = 4.

    >>> _, cov = classical_step((0, 0, 0), np.zeros((3, 3)), 2.0, 0.0, ClassicalNoise(1, 1))
    >>> cov.tolist()
    [[1.0, 0.0, 0.0], [0.0, 4.0, 2.0], [0.0, 2.0, 1.0]]
    """
    x, y, theta = np.asarray(pose, dtype=float)
    heading = theta + angle
    c, s = math.cos(heading), math.sin(heading)
    f_state = np.array([[1.0, 0.0, -distance * s], [0.0, 1.0, distance * c], [0.0, 0.0, 1.0]])
    f_input = np.array([[c, -distance * s], [s, distance * c], [0.0, 1.0]])  # eq. (3)
    cov_input = np.diag([noise.sigma_distance**2, noise.sigma_angle**2])
    new_cov = f_state @ np.asarray(cov, dtype=float) @ f_state.T + f_input @ cov_input @ f_input.T
    new_pose = np.array([x + distance * c, y + distance * s, heading])
    return new_pose, 0.5 * (new_cov + new_cov.T)
