"""Kelly's general solution: the covariance of every sample from prefix sums.

Integrated-heading odometry has the closed-form transition matrix (Kelly eq. 9–11)::

    Φ(k, j) = [[1, 0, −(y_k − y_j)], [0, 1, x_k − x_j], [0, 0, 1]]

In discrete form every step Jacobian is a shear F_k = I + u_k e_θ^T with
u_k = (−Δy_k, Δx_k, 0) and e_θ^T u_k = 0, so the shears commute and their product is
I + Σ u_k e_θ^T = Φ(k, j): the general solution below equals the step recursion exactly,
not just in the limit. With B_j = G_j Q_j G_j^T,

    P_k = Φ(k,0) P_0 Φ(k,0)^T + Σ_{j<k} Φ(k,j+1) B_j Φ(k,j+1)^T          (Kelly eq. 11)

Expanding Φ B Φ^T = B + v (B e_θ)^T + (B e_θ) v^T + v v^T B_θθ, v = (−Y, X, 0),
X = x_k − x_{j+1}, turns the sum over j into prefix sums (``np.cumsum``) of B_j's
entries weighted by 1, x_{j+1}, y_{j+1}, x², y², xy: no loop over samples.

Cancellation: x_k² S0 − 2 x_k S1 + S2 loses about log10(x²/σ-scale) digits when the
coordinates are large. Every chunk is therefore evaluated in coordinates relative to its
first pose (a local origin), and the covariance is carried across chunk boundaries with
Φ itself; memory is O(chunk).

This module also holds the two other Φ-based solutions: the parameter sensitivity
(bias-mode parameter uncertainty) and direct-heading odometry (Kelly eq. 10).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.propagate.inputs import ENGINE_METHODS, step_terms
from odomkit.propagate.lateral import accumulate_lateral

__all__ = [
    "DEFAULT_CHUNK", "bias_sensitivity_chunk", "check_cov3", "check_cov_input", "check_lateral",
    "check_method", "check_steps",
    "direct_heading_chunk",
    "input_terms", "iter_transition", "parameter_sensitivity", "propagate_direct_heading",
    "propagate_transition", "sensitivity_chunk", "sensitivity_terms", "transition_chunk", "transition_matrix"
]

DEFAULT_CHUNK = 1 << 15


def check_method(method: str) -> None:
    """Raise ModelError unless ``method`` is one the engines know."""
    if method not in ENGINE_METHODS:
        raise ModelError(f"unknown method {method!r}; expected one of {', '.join(ENGINE_METHODS)}")


def check_cov3(cov0: ArrayLike, name: str = "cov0") -> NDArray[np.float64]:
    """A finite symmetric PSD (3, 3) matrix (:func:`odomkit.validate.covariance`)."""
    return validate.covariance(cov0, name)


def check_steps(
    dd: ArrayLike, dtheta: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """dd, dtheta as float arrays (M,) of matching length, or ModelError."""
    dd = np.asarray(dd, dtype=float)
    dtheta = np.asarray(dtheta, dtype=float)
    if dd.ndim != 1 or dd.shape != dtheta.shape:
        raise ModelError("dd and dtheta must be 1-D of equal length, "
                         f"got {dd.shape}, {dtheta.shape}")
    return dd, dtheta


def check_cov_input(cov_input: ArrayLike, m: int) -> NDArray[np.float64]:
    """cov_input as a float array (m, 2, 2), or ModelError."""
    q = np.asarray(cov_input, dtype=float)
    if q.shape != (m, 2, 2):
        raise ModelError(f"cov_input must have shape ({m}, 2, 2), got {q.shape}")
    return q


def transition_matrix(poses: ArrayLike, k: ArrayLike, j: ArrayLike) -> NDArray[np.float64]:
    """Φ(k, j) of integrated-heading odometry, Kelly eq. (11), broadcast over k and j.

    Parameters
    ----------
    poses : array_like, shape (N, 3)
        Reference track [m, m, rad].
    k, j : array_like of int
        Row indices (k ≥ j for a forward map, but any pair is valid).

    Returns
    -------
    phi : ndarray, shape broadcast(k, j) + (3, 3)

    Examples
    --------
    >>> transition_matrix([[0, 0, 0], [2, 1, 0.5]], 1, 0).tolist()
    [[1.0, 0.0, -1.0], [0.0, 1.0, 2.0], [0.0, 0.0, 1.0]]
    """
    p = np.asarray(poses, dtype=float)
    k, j = np.broadcast_arrays(np.asarray(k), np.asarray(j))
    phi = np.zeros(k.shape + (3, 3))
    phi[..., 0, 0] = phi[..., 1, 1] = phi[..., 2, 2] = 1.0
    phi[..., 0, 2] = -(p[k, 1] - p[j, 1])
    phi[..., 1, 2] = p[k, 0] - p[j, 0]
    return phi


def input_terms(
    terms: tuple[NDArray[np.float64], ...], cov_input: NDArray[np.float64]
) -> tuple[NDArray[np.float64], ...]:
    """Entries (b00, b01, b11, b02, b12, b22) of B = G Q G^T per step, each (n,).

    ``terms`` is :func:`odomkit.propagate.inputs.step_terms`; G = [[g00, g01],
    [g10, g11], [0, 1]] (Chong–Kleeman eq. 17 in chord form), Q = cov_input (n, 2, 2).
    """
    _, _, g00, g01, g10, g11 = terms
    q00, q11 = cov_input[:, 0, 0], cov_input[:, 1, 1]
    q01 = 0.5 * (cov_input[:, 0, 1] + cov_input[:, 1, 0])
    r00, r01 = g00 * q00 + g01 * q01, g00 * q01 + g01 * q11  # rows of G Q
    r10, r11 = g10 * q00 + g11 * q01, g10 * q01 + g11 * q11
    return (r00 * g00 + r01 * g01, r00 * g10 + r01 * g11, r10 * g10 + r11 * g11,
            r01, r11, q11)


def _shear(P: NDArray[np.float64], X: NDArray[np.float64], Y: NDArray[np.float64]):
    """Φ P Φ^T for Φ = I + v e_θ^T, v = (−Y, X, 0); P (3, 3) or (n, 3, 3), X, Y (n,)."""
    p00, p01, p02 = P[..., 0, 0], P[..., 0, 1], P[..., 0, 2]
    p11, p12, p22 = P[..., 1, 1], P[..., 1, 2], P[..., 2, 2]
    out = np.empty(X.shape + (3, 3))
    out[:, 0, 0] = p00 - 2.0 * Y * p02 + Y * Y * p22
    out[:, 0, 1] = out[:, 1, 0] = p01 + X * p02 - Y * p12 - X * Y * p22
    out[:, 1, 1] = p11 + 2.0 * X * p12 + X * X * p22
    out[:, 0, 2] = out[:, 2, 0] = p02 - Y * p22
    out[:, 1, 2] = out[:, 2, 1] = p12 + X * p22
    out[:, 2, 2] = p22
    return out


def transition_chunk(
    x_local: NDArray[np.float64],
    y_local: NDArray[np.float64],
    B: tuple[NDArray[np.float64], ...],
    cov_start: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Kelly eq. (11) over one chunk of n steps, by prefix sums.

    x_local, y_local : (n + 1,) positions relative to the chunk's first pose (so
    x_local[0] = y_local[0] = 0); B : the entries of the n steps' G Q G^T
    (:func:`input_terms`); cov_start : P at the first pose. Returns P after each
    step, (n, 3, 3).
    """
    X, Y = x_local[1:], y_local[1:]  # x_k for the output rows, and x_{j+1} of step j
    cs = np.cumsum
    b00, b01, b11, b02, b12, b22 = B
    s22 = cs(b22)
    sx22, sy22 = cs(X * b22), cs(Y * b22)
    # Σ_j Φ(k,j+1) B_j Φ(k,j+1)^T entry by entry (Kelly eq. 11 expanded, module doc).
    s02, s12 = cs(b02), cs(b12)
    xth = s02 - (Y * s22 - sy22)
    yth = s12 + (X * s22 - sx22)
    xx = cs(b00) - 2.0 * (Y * s02 - cs(Y * b02)) + (Y * (Y * s22 - 2.0 * sy22)
                                                    + cs(Y * Y * b22))
    yy = cs(b11) + 2.0 * (X * s12 - cs(X * b12)) + (X * (X * s22 - 2.0 * sx22)
                                                    + cs(X * X * b22))
    xy = (cs(b01) + (X * s02 - cs(X * b02)) - (Y * s12 - cs(Y * b12))
          - (X * (Y * s22 - sy22) - Y * sx22 + cs(X * Y * b22)))
    out = _shear(cov_start, X, Y)  # Φ(k, k0) P_k0 Φ(k, k0)^T
    out[:, 0, 0] += xx
    out[:, 1, 1] += yy
    out[:, 2, 2] += s22
    out[:, 0, 1] += xy
    out[:, 0, 2] += xth
    out[:, 1, 2] += yth
    out[:, 1, 0] = out[:, 0, 1]
    out[:, 2, 0] = out[:, 0, 2]
    out[:, 2, 1] = out[:, 1, 2]
    return out


def iter_transition(
    poses: ArrayLike,
    dd: ArrayLike,
    dtheta: ArrayLike,
    cov_input: ArrayLike,
    cov0: ArrayLike,
    method: str = "exact",
    chunk_size: int = DEFAULT_CHUNK,
    var_lateral: ArrayLike | None = None,
) -> Iterator[tuple[int, NDArray[np.float64]]]:
    """Yield ``(row, cov)`` chunks of :func:`propagate_transition`: cov (n, 3, 3) holds
    rows row … row+n−1 (row 0, the initial covariance, comes first, alone)."""
    check_method(method)
    dd_, dth_ = check_steps(dd, dtheta)
    q = check_cov_input(cov_input, dd_.size)
    lateral = check_lateral(var_lateral, dd_.size)
    sums = np.zeros(3)
    poses_ = np.asarray(poses, dtype=float)
    if poses_.shape != (dd_.size + 1, 3):
        raise ModelError(f"poses must have shape ({dd_.size + 1}, 3), got {poses_.shape}")
    P = check_cov3(cov0)
    yield 0, P[None].copy()
    for a in range(0, dd_.size, max(int(chunk_size), 1)):
        b = min(a + max(int(chunk_size), 1), dd_.size)
        terms = step_terms(poses_[a:b, 2], dd_[a:b], dth_[a:b], method)
        # Local origin: subtracting the chunk's first position keeps the moments small.
        xl = poses_[a:b + 1, 0] - poses_[a, 0]
        yl = poses_[a:b + 1, 1] - poses_[a, 1]
        out = transition_chunk(xl, yl, input_terms(terms, q[a:b]), P)
        P = out[-1].copy()
        if lateral is not None:  # carried apart: Φ leaves a position-only term unchanged
            accumulate_lateral(poses_[a:b, 2], dth_[a:b], lateral[a:b], method, sums, out)
        yield a + 1, out


def propagate_transition(
    poses: ArrayLike,
    dd: ArrayLike,
    dtheta: ArrayLike,
    cov_input: ArrayLike,
    cov0: ArrayLike,
    method: str = "exact",
    *,
    out: NDArray[np.float64] | None = None,
    chunk_size: int = DEFAULT_CHUNK,
    var_lateral: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Covariance of every pose by Kelly's general solution (eq. 11), vectorised.

    Parameters
    ----------
    poses : array_like, shape (M + 1, 3)
        The dead-reckoned track (:func:`odomkit.integrate.dead_reckon` with the same
        ``method``) [m, m, rad].
    dd, dtheta : array_like, shape (M,)
        Body motion of each step [m], [rad].
    cov_input : array_like, shape (M, 2, 2)
        Covariance of each step's (Δd, Δθ) (see :mod:`odomkit.propagate.inputs`).
    cov0 : array_like, shape (3, 3)
        Covariance of the first pose.
    method : {"exact", "midpoint", "euler", "classical"}
        Step map whose G_k is used.
    out : ndarray, shape (M + 1, 3, 3), optional
        Written in place and returned (saves the allocation for long logs).
    chunk_size : int
        Steps per chunk (memory about 30·8·chunk_size bytes).
    var_lateral : array_like, shape (M,), optional
        Variance of each step's sideways slip [m²]; its running sum is added to the x–y
        block of every row (:mod:`odomkit.propagate.lateral`).

    Returns
    -------
    cov : ndarray, shape (M + 1, 3, 3)
        Equal to :func:`odomkit.propagate.recursion.propagate_recursion` up to round-off.

    Examples
    --------
    One straight step of 1 m with var Δθ = 0.01: y picks up 1²·0.01/4 (midpoint lever).

    >>> from odomkit.integrate import dead_reckon
    >>> p = dead_reckon([1.0], [0.0])
    >>> c = propagate_transition(p, [1.0], [0.0], [[[0.0, 0.0], [0.0, 0.01]]], np.zeros((3, 3)))
    >>> round(float(c[1, 1, 1]), 6), round(float(c[1, 1, 2]), 6)
    (0.0025, 0.005)
    """
    dd = np.asarray(dd, dtype=float)
    if out is None:
        out = np.empty((dd.size + 1, 3, 3))
    elif out.shape != (dd.size + 1, 3, 3):
        raise ModelError(f"out must have shape ({dd.size + 1}, 3, 3), got {out.shape}")
    for row, chunk in iter_transition(poses, dd, dtheta, cov_input, cov0, method, chunk_size,
                                      var_lateral):
        out[row:row + chunk.shape[0]] = chunk
    return out


def sensitivity_chunk(
    u: NDArray[np.float64], C: NDArray[np.float64], S_start: NDArray[np.float64]
) -> NDArray[np.float64]:
    """S after each of n steps: S_{k+1} = F_k S_k + C_k with F_k = I + u_k e_θ^T.

    u : (n, 2) = (−Δy_k, Δx_k); C : (n, 3, p) = G_k K_k; S_start : (3, p).
    The θ row is a plain prefix sum; the x, y rows add u_k times the θ row *before* the
    step, again a prefix sum, so no large coordinates ever enter (no cancellation).
    """
    theta_after = S_start[2] + np.cumsum(C[:, 2, :], axis=0)
    theta_before = np.concatenate([S_start[2][None], theta_after[:-1]])
    S = np.empty_like(C)
    S[:, 2, :] = theta_after
    for r in (0, 1):
        S[:, r, :] = S_start[r] + np.cumsum(C[:, r, :] + u[:, r, None] * theta_before, axis=0)
    return S


def bias_sensitivity_chunk(
    terms: tuple[NDArray[np.float64], ...], K: NDArray[np.float64], S_start: NDArray[np.float64],
    direct: bool = False,
) -> NDArray[np.float64]:
    """Sensitivity S = ∂pose/∂β after each of n steps of constant (bias) parameters β,
    (n, 3, p), from S_start (3, p): the one bias path of every engine.

    ``terms`` are the steps' :func:`odomkit.propagate.inputs.step_terms`, K (n, 2, p)
    their ∂(Δd, Δθ)/∂β. Integrated heading: S_{k+1} = F_k S_k + G_k K_k
    (:func:`sensitivity_chunk`). Direct heading (``direct``; Kelly section 3.1, the
    heading is measured and Φ = I for it): the heading row is not integrated but stays
    ∂θ_k/∂β of the heading sensor, the same at every row, which the caller puts in
    S_start[2] at row 0 (:meth:`odomkit.noise.NoiseModel.bias_heading`: 1 for a heading
    offset, θ_k = θ_meas,k + δ); each step's position then moves by ∂Δp/∂θ = (−Δy, Δx)
    times it, plus ∂Δp/∂Δd times K's Δd row (a distance scale).

    Examples
    --------
    >>> from odomkit.propagate.inputs import step_terms
    >>> terms = step_terms(np.zeros(10), np.full(10, 0.1), np.zeros(10), "exact")
    >>> S = bias_sensitivity_chunk(terms, np.zeros((10, 2, 1)), np.array([[0.0], [0.0], [1.0]]), True)
    >>> S[-1, :, 0].round(12).tolist()   # a heading offset swings a 1 m line sideways by 1 m/rad
    [0.0, 1.0, 1.0]
    """
    u, C = sensitivity_terms(terms, K)
    if direct:
        C[:, 2, :] = 0.0  # a measured heading accumulates nothing
    return sensitivity_chunk(u, C, S_start)


def parameter_sensitivity(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, jac_params: ArrayLike,
    method: str = "exact",
) -> NDArray[np.float64]:
    """Sensitivity S_k = ∂pose_k/∂β of every pose to constant parameters β, (M+1, 3, p).

    A parameter error δβ (wheel base, wheel scale) is the same at every step, so the pose
    error it causes is S_k δβ with S_k = Σ_{j<k} Φ(k, j+1) G_j K_j (Kelly eq. 11 applied
    to a constant input), K_j = ∂(Δd_j, Δθ_j)/∂β (:mod:`odomkit.propagate.inputs`). With
    Cov(β) = diag(σ²) the pose covariance it adds is S_k diag(σ²) S_k^T, which grows with
    distance² (bias mode of ParameterUncertainty).

    Parameters
    ----------
    theta, dd, dtheta : array_like, shape (M,)
        Start heading [rad], length [m] and heading change [rad] of each step.
    jac_params : array_like, shape (M, 2, p)

    Examples
    --------
    A 1 m straight line in 10 steps with a 1 % distance scale error ends 1 cm long:

    >>> from odomkit.noise.parameters import scale_parameter_jacobian
    >>> dd = np.full(10, 0.1)
    >>> S = parameter_sensitivity(np.zeros(10), dd, np.zeros(10), scale_parameter_jacobian(dd))
    >>> round(float(S[-1, 0, 0] * 0.01), 12)
    0.01
    """
    check_method(method)
    dd_, dth_ = check_steps(dd, dtheta)
    th_ = np.asarray(theta, dtype=float)
    K = np.asarray(jac_params, dtype=float)
    u, C = sensitivity_terms(step_terms(th_, dd_, dth_, method), K)
    S = np.zeros((dd_.size + 1, 3, K.shape[-1]))
    S[1:] = sensitivity_chunk(u, C, S[0])
    return S


def sensitivity_terms(
    terms: tuple[NDArray[np.float64], ...], K: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """u = (−Δy, Δx) (n, 2) and C = G K (n, 3, p) for :func:`sensitivity_chunk`."""
    dx, dy, g00, g01, g10, g11 = terms
    C = np.empty((dx.size, 3, K.shape[-1]))
    C[:, 0, :] = g00[:, None] * K[:, 0, :] + g01[:, None] * K[:, 1, :]
    C[:, 1, :] = g10[:, None] * K[:, 0, :] + g11[:, None] * K[:, 1, :]
    C[:, 2, :] = K[:, 1, :]
    return np.stack([-dy, dx], axis=1), C


def direct_heading_chunk(
    theta: NDArray[np.float64], dd: NDArray[np.float64], dtheta: NDArray[np.float64],
    var_dd: NDArray[np.float64], var_heading: NDArray[np.float64],
    cov_xy: NDArray[np.float64], cross: NDArray[np.float64], method: str,
) -> NDArray[np.float64]:
    """Direct-heading covariance after each of n steps; var_heading has n + 1 entries
    (rows k0 … k0+n); cov_xy (2, 2) and cross (2,) = Cov(pos, heading error) at row k0."""
    dx, dy, g00, g01, g10, g11 = step_terms(theta, dd, dtheta, method)
    a = np.stack([g00, g10], axis=1)     # ∂Δp/∂Δd
    c = np.stack([g01, g11], axis=1)     # ∂Δp/∂h_{k+1} = ∂Δp/∂Δθ   (Δθ = h_{k+1} − h_k)
    b = np.stack([-dy, dx], axis=1) - c  # ∂Δp/∂h_k   = ∂Δp/∂θ − ∂Δp/∂Δθ
    h0, h1 = var_heading[:-1], var_heading[1:]
    # Cov(p_k, δh_k): the previous step's c times var h_k (a fresh compass sample
    # correlates only with the step that ended at it).
    r = np.concatenate([cross[None], c[:-1] * h0[1:, None]])
    inc = (np.einsum("ni,nj->nij", a, a) * var_dd[:, None, None]
           + np.einsum("ni,nj->nij", b, b) * h0[:, None, None]
           + np.einsum("ni,nj->nij", c, c) * h1[:, None, None]
           + np.einsum("ni,nj->nij", b, r) + np.einsum("ni,nj->nij", r, b))
    out = np.empty((dd.size, 3, 3))
    out[:, :2, :2] = cov_xy + np.cumsum(inc, axis=0)
    out[:, :2, 2] = out[:, 2, :2] = c * h1[:, None]
    out[:, 2, 2] = h1
    return out


def propagate_direct_heading(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, var_dd: ArrayLike,
    var_heading: ArrayLike, cov_xy0: ArrayLike, method: str = "exact",
    *, chunk_size: int = DEFAULT_CHUNK, var_lateral: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Covariance of direct-heading (compass) odometry, Kelly section 3.1, eq. (10).

    The heading of every row is a *measurement* with its own error (variance
    ``var_heading``), not the sum of earlier increments: heading errors do not
    accumulate, so P_θθ at row k is var_heading[k], and Φ = I for position (Kelly: the
    system is memoryless). The step from row k to k+1 uses h_k and h_{k+1} (its Δθ is
    h_{k+1} − h_k), so each compass sample enters two steps; the resulting correlation
    is kept exactly (the position–heading cross-covariance carries it), which makes a
    straight line at speed V grow as ``var_y = |V|·psd·s`` (Kelly eq. 13).

    Parameters
    ----------
    theta : array_like, shape (M,)
        Measured heading at the start of each step [rad].
    dd, dtheta : array_like, shape (M,)
        Distance [m] and measured heading change [rad] of each step.
    var_dd : array_like, shape (M,)
        Variance of each Δd [m²] (Kelly: α_ss·|Δd|).
    var_heading : array_like, shape (M + 1,)
        Variance of each heading sample [rad²]
        (:func:`odomkit.noise.kelly.direct_heading_variances`).
    cov_xy0 : array_like, shape (2, 2)
        Initial position covariance [m²]; the initial heading is the compass's, with
        variance var_heading[0] and no correlation to the position.
    method : {"exact", "midpoint", "euler"}
    var_lateral : array_like, shape (M,), optional
        Variance of each step's sideways slip [m²], added as its running sum to the
        position block (:mod:`odomkit.propagate.lateral`).

    Returns
    -------
    cov : ndarray, shape (M + 1, 3, 3)

    Examples
    --------
    >>> c = propagate_direct_heading(np.zeros(100), np.full(100, 0.01), np.zeros(100),
    ...                              np.zeros(100), np.full(101, 1e-4), np.zeros((2, 2)))
    >>> # 0.01² · 1e-4 per interior sample; the two end samples enter one step each (¼ + ¼)
    >>> round(float(c[-1, 1, 1]), 12), float(c[-1, 2, 2])   # 0.01² · 1e-4 · 99.5
    (9.95e-07, 0.0001)
    """
    check_method(method)
    dd_, dth_ = check_steps(dd, dtheta)
    th_ = np.asarray(theta, dtype=float)
    var_dd_ = np.asarray(var_dd, dtype=float)
    var_h = np.asarray(var_heading, dtype=float)
    if var_h.shape != (dd_.size + 1,) or var_dd_.shape != dd_.shape:
        raise ModelError("var_heading must have M + 1 entries and var_dd M entries")
    out = np.empty((dd_.size + 1, 3, 3))
    out[0] = 0.0
    out[0, :2, :2] = np.asarray(cov_xy0, dtype=float).reshape(2, 2)
    out[0, 2, 2] = var_h[0]
    lateral = check_lateral(var_lateral, dd_.size)
    n = max(int(chunk_size), 1)
    P, sums = out[0], np.zeros(3)
    for a in range(0, dd_.size, n):
        b = min(a + n, dd_.size)
        out[a + 1:b + 1] = direct_heading_chunk(
            th_[a:b], dd_[a:b], dth_[a:b], var_dd_[a:b], var_h[a:b + 1],
            P[:2, :2], P[:2, 2], method)
        P = out[b]
        if lateral is not None:
            P = P.copy()  # the slip's running sum is carried apart
            accumulate_lateral(th_[a:b], dth_[a:b], lateral[a:b], method, sums, out[a + 1:b + 1])
    return out


def check_lateral(var_lateral: ArrayLike | None, m: int) -> NDArray[np.float64] | None:
    """``var_lateral`` (the sideways-slip variance of each step [m²]) as a float array
    (m,); None if None; ModelError for another shape."""
    if var_lateral is None:
        return None
    var = np.asarray(var_lateral, dtype=float)
    if var.shape != (m,):
        raise ModelError(f"var_lateral must have shape ({m},), got {var.shape}")
    return var
