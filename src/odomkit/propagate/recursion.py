"""The step recursion P_{k+1} = F_k P_k F_k^T + G_k Q_k G_k^T (Chong–Kleeman eq. 2).

F_k and G_k are the exact-arc Jacobians of :func:`odomkit.kinematics.step_jacobians`
(Chong–Kleeman eq. 16–17 in chord form; ``midpoint``, ``euler`` and the classical
rotate-then-translate map are also available). The recurrence runs in a numba kernel
(:mod:`odomkit.propagate._numba`) over bounded chunks; without numba a numpy loop runs
instead, with a warning (about 100× slower).

The kernel is fastest (about 9 ns a step, SIMD lanes) when the headings are those of the
steps, θ_{k+1} = θ_k + Δθ_k, as on a track from :func:`odomkit.integrate.dead_reckon`: it
then turns a heading vector instead of calling cos/sin at every step. Any other headings
are detected step by step and get a real cos/sin (about 30 ns a step); the results are
the same to rounding either way. Per-wheel noise alone (:class:`odomkit.noise.WheelNoise`)
has its input covariance formed inside the kernel. A position-only noise (lateral slip)
adds its running sum to the rows apart from the kernel (:mod:`odomkit.propagate.lateral`
shows that this is exact). :func:`track_covariance` has the kernel
write straight into the output, with streaming stores when it is large
(``benchmarks/propagation.py`` compares it with copying the same bytes).

:func:`track_covariance` is the entry point of ``odomkit track``: a log's body steps and a
noise model (or a tuple of them) in, the covariance of every pose out.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import jit
from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps
from odomkit.noise.wheel import WheelInputs
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.propagate.inputs import any_step_jacobians, step_terms
from odomkit.propagate.lateral import accumulate_lateral
from odomkit.propagate.plan import NoiseArg, NoisePlan, plan_noise
from odomkit.propagate.transition import (
    bias_sensitivity_chunk,
    check_cov3,
    check_cov_input,
    check_lateral,
    check_method,
    check_steps,
    direct_heading_chunk,
    input_terms,
    transition_chunk,
)

__all__ = [
    "DEFAULT_CHUNK", "iter_track_covariance", "new_heading_state", "propagate_recursion", "recursion_chunk",
    "track_covariance"
]

#: Steps per chunk: small enough for bounded memory, large enough that the Python work
#: per chunk (~10 µs) stays below 1 % of the kernel's (~10 ns a step).
DEFAULT_CHUNK = 1 << 15
# From this many rows on a whole-track output is written with streaming stores (it will
# not stay in the cache anyway; odomkit._stores): 2^18 rows are 19 MB.
_STREAM_ROWS = 1 << 18
_METHOD_CODES = {"exact": 0, "midpoint": 1, "euler": 2, "classical": 3}


def _load_kernel(parallel: bool = False) -> Callable[..., None] | None:
    """The numba kernel, or None (with a one-time warning, :func:`odomkit.jit.load`) when
    numba is missing: then a numpy loop runs, about 100x slower."""
    module = jit.load("propagate._numba", stacklevel=4)
    if module is None:
        return None
    return module.recursion_kernel_parallel if parallel else module.recursion_kernel


def new_heading_state() -> NDArray[np.float64]:
    """Heading state carried by the kernel from one chunk to the next (see _numba.py):
    ``[cos, sin, heading sum, valid, anchor count]``, initially invalid. The anchor count
    (real cos/sin of a heading taken) shows whether the fast path ran:

    Examples
    --------
    >>> state = new_heading_state()
    >>> q = np.zeros((1000, 2, 2))
    >>> _ = recursion_chunk(np.zeros(1000), np.ones(1000), np.zeros(1000), q, np.eye(3),
    ...                     state=state)
    >>> int(state[4])   # every 128 steps on consistent headings
    8
    """
    return np.zeros(5)


def _numpy_chunk(theta, dd, dtheta, cov_input, cov_start, out, method: str) -> None:
    """Fallback of the kernel: the same recursion with 3×3 numpy products per step."""
    F, G = any_step_jacobians(theta, dd, dtheta, method)
    P = cov_start.copy()
    for k in range(dd.size):
        P = F[k] @ P @ F[k].T + G[k] @ cov_input[k] @ G[k].T
        # Symmetrise: round-off in the products makes P_ij and P_ji drift apart, and
        # an asymmetric P breaks Cholesky/eigh downstream (filterpy does the same).
        P = 0.5 * (P + P.T)
        out[k] = P


_EMPTY1 = np.empty(0)
_EMPTY3 = np.empty((0, 2, 2))


def recursion_chunk(theta, dd, dtheta, cov_input, cov_start, method: str = "exact",
                    parallel: bool = False, *, start: int = 0,
                    state: NDArray[np.float64] | None = None,
                    wheel: WheelInputs | None = None, row: int = 0,
                    out: NDArray[np.float64] | None = None, stream: bool = False):
    """P after each of n steps, (n, 3, 3), starting from ``cov_start`` (3, 3).

    ``cov_input`` (n, 2, 2) may be None when ``wheel`` is given: the kernel then forms
    the per-wheel Q_k itself from ``wheel``'s rows ``row`` … ``row + n − 1``. ``start``
    is the global index of the first step and ``state`` (:func:`new_heading_state`) the
    heading carried from the previous chunk, updated in place: with both, results do
    not depend on the chunking. ``out`` (n, 3, 3), C-contiguous, receives the result
    (e.g. a slice of the whole track's array, so that nothing is copied); ``stream``
    writes it with streaming stores, for outputs larger than the cache.
    """
    if out is None:
        out = np.empty((dd.size, 3, 3))
    kernel = _load_kernel(parallel)
    if kernel is None:
        if cov_input is None:
            assert wheel is not None
            cov_input = wheel.cov_input(row, row + dd.size)
        _numpy_chunk(theta, dd, dtheta, cov_input, cov_start, out, method)
        return out
    if state is None:
        state = new_heading_state()
    cov_start = np.asarray(cov_start, dtype=float)
    # The kernel accepts strided views (e.g. poses[:, 2]): no contiguous copies.
    args = (np.asarray(theta, dtype=float), np.asarray(dd, dtype=float),
            np.asarray(dtheta, dtype=float))
    if wheel is not None and cov_input is None:
        b = row + dd.size
        kernel(*args, _EMPTY3, wheel.d_left[row:b], wheel.d_right[row:b], wheel.coefficients,
               1, _METHOD_CODES[method], start, state, cov_start, out, stream)
    else:
        kernel(*args, np.asarray(cov_input, dtype=float), _EMPTY1, _EMPTY1, _EMPTY1, 0,
               _METHOD_CODES[method], start, state, cov_start, out, stream)
    return out


def propagate_recursion(
    theta: ArrayLike,
    dd: ArrayLike,
    dtheta: ArrayLike,
    cov_input: ArrayLike,
    cov0: ArrayLike,
    method: str = "exact",
    *,
    out: NDArray[np.float64] | None = None,
    chunk_size: int = DEFAULT_CHUNK,
    parallel: bool = False,
    var_lateral: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Covariance of every pose by the step recursion, Chong–Kleeman eq. (2).

    Parameters
    ----------
    theta : array_like, shape (M,)
        Heading at the start of each step [rad].
    dd, dtheta : array_like, shape (M,)
        Body motion of each step [m], [rad].
    cov_input : array_like, shape (M, 2, 2)
        Covariance of each step's (Δd, Δθ) [m², m·rad; m·rad, rad²].
    cov0 : array_like, shape (3, 3)
        Covariance of the first pose.
    method : {"exact", "midpoint", "euler", "classical"}
        Step map whose Jacobians F_k, G_k are used.
    out : ndarray, shape (M + 1, 3, 3), optional
        Written in place and returned.
    chunk_size : int
        Steps per call of the kernel; results do not depend on it (bit for bit).
    parallel : bool
        Form the per-step terms on numba's threads (NUMBA_NUM_THREADS), in blocks of 128
        steps, then run the recurrence on one. Same bits as the serial kernel; faster on
        idle cores (0.15 s against 0.2 s for 10^7 steps on 2 cores), many times slower
        when other processes keep the cores busy (each chunk then waits for a
        scheduler slice), hence not the default.
    var_lateral : array_like, shape (M,), optional
        Variance of each step's sideways slip [m²] (:class:`odomkit.noise.LateralSlipNoise`):
        its running sum is added to the x–y block of every row
        (:mod:`odomkit.propagate.lateral`).

    Returns
    -------
    cov : ndarray, shape (M + 1, 3, 3)

    Examples
    --------
    Two straight 1 m steps with var Δθ = 0.01 each (midpoint lever ½ m, then 1.5 m):

    >>> q = np.array([[[0.0, 0.0], [0.0, 0.01]]] * 2)
    >>> c = propagate_recursion(np.zeros(2), np.ones(2), np.zeros(2), q, np.zeros((3, 3)))
    >>> round(float(c[2, 1, 1]), 6)   # 0.01·(0.5² + 1.5²)
    0.025
    """
    check_method(method)
    dd_, dth_ = check_steps(dd, dtheta)
    q = check_cov_input(cov_input, dd_.size)
    th_ = np.asarray(theta, dtype=float)
    if th_.shape != dd_.shape:
        raise ModelError(f"theta must have shape {dd_.shape}, got {th_.shape}")
    if out is None:
        out = np.empty((dd_.size + 1, 3, 3))
    elif out.shape != (dd_.size + 1, 3, 3):
        raise ModelError(f"out must have shape ({dd_.size + 1}, 3, 3), got {out.shape}")
    out[0] = check_cov3(cov0)
    lateral = check_lateral(var_lateral, dd_.size)
    n = max(int(chunk_size), 1)
    state = new_heading_state()
    direct, stream = _writes_in_place(out)
    P, sums = out[0], np.zeros(3)
    for a in range(0, dd_.size, n):
        b = min(a + n, dd_.size)
        chunk = recursion_chunk(th_[a:b], dd_[a:b], dth_[a:b], q[a:b], P, method, parallel,
                                start=a, state=state, out=out[a + 1:b + 1] if direct else None,
                                stream=stream)
        if not direct:
            out[a + 1:b + 1] = chunk
        P = out[b]
        if lateral is not None:
            P = P.copy()  # the recursion goes on without the slip; its sum is carried apart
            accumulate_lateral(th_[a:b], dth_[a:b], lateral[a:b], method, sums, out[a + 1:b + 1])
    return out


def _writes_in_place(out: NDArray[np.float64]) -> tuple[bool, bool]:
    """Whether the kernel can write straight into slices of ``out`` (float64, C order),
    and whether with streaming stores (an output too large for the cache)."""
    direct = out.dtype == np.float64 and out.flags.c_contiguous and out.flags.writeable
    return direct, direct and out.shape[0] >= _STREAM_ROWS


def _white_chunk(plan: NoisePlan, engine: str, theta, dd, dtheta, a: int, b: int, P,
                 parallel: bool = False, state: NDArray[np.float64] | None = None,
                 out: NDArray[np.float64] | None = None, stream: bool = False):
    """White-noise covariance after steps a … b−1 (n, 3, 3), from P at row a; the
    recursion engine writes it into ``out`` when given (the others return a new array)."""
    if plan.direct:
        assert plan.var_heading is not None
        return direct_heading_chunk(theta, dd, dtheta, plan.var_dd(a, b),
                                    plan.var_heading[a:b + 1], P[:2, :2], P[:2, 2],
                                    plan.method)
    if engine == "recursion":
        # Per-wheel noise alone: the kernel forms Q_k itself (no (n, 2, 2) array).
        q = None if plan.wheel is not None else plan.cov_input(a, b)
        return recursion_chunk(theta, dd, dtheta, q, P, plan.method, parallel, start=a,
                               state=state, wheel=plan.wheel, row=a, out=out, stream=stream)
    q = plan.cov_input(a, b)
    # Local origin at the chunk's first pose, built from the same step map as the
    # recursion so both engines linearise about the same track.
    terms = step_terms(theta, dd, dtheta, plan.method)
    xl = np.concatenate([[0.0], np.cumsum(terms[0])])
    yl = np.concatenate([[0.0], np.cumsum(terms[1])])
    return transition_chunk(xl, yl, input_terms(terms, q), P)


def _bias_chunk(plan: NoisePlan, theta, dd, dtheta, a: int, b: int, S):
    """Parameter sensitivity after steps a … b−1 (n, 3, p), from S at row a
    (:func:`odomkit.propagate.transition.bias_sensitivity_chunk`; direct heading: S's θ
    row is the heading sensor's constant ∂θ/∂β, set at row 0 by :func:`_chunks`)."""
    return bias_sensitivity_chunk(step_terms(theta, dd, dtheta, plan.method),
                                  plan.param_jacobian(a, b), S, plan.direct)


def iter_track_covariance(
    steps: BodySteps,
    poses: ArrayLike,
    noise: NoiseArg,
    cov0: ArrayLike,
    method: str = "exact",
    engine: str = "recursion",
    chunk_size: int = DEFAULT_CHUNK,
    parallel: bool = False,
) -> Iterator[tuple[int, NDArray[np.float64]]]:
    """Yield ``(row, cov)`` chunks of :func:`track_covariance`; cov (n, 3, 3) holds rows
    row … row+n−1. Memory stays O(chunk_size) beyond the inputs, for logs whose full
    (N, 3, 3) output (72 bytes a row: 720 MB for 10^7 rows) should never exist at once."""
    return _chunks(steps, poses, noise, cov0, method, engine, chunk_size, parallel, None)


def _chunks(steps: BodySteps, poses: ArrayLike, noise: NoiseArg, cov0: ArrayLike, method: str,
            engine: str, chunk_size: int, parallel: bool, out: NDArray[np.float64] | None
            ) -> Iterator[tuple[int, NDArray[np.float64]]]:
    """:func:`iter_track_covariance`; with ``out`` (M+1, 3, 3), float64 and C-contiguous,
    each chunk is formed in its rows of ``out`` (and yielded as that view)."""
    check_method(method)
    if engine not in ("recursion", "transition"):
        raise ModelError(f"unknown engine {engine!r}; expected 'recursion' or 'transition'")
    plan = plan_noise(steps, noise, method)
    dd, dtheta = check_steps(steps.dd, steps.dtheta)
    poses = np.asarray(poses, dtype=float)
    if poses.shape != (dd.size + 1, 3):
        raise ModelError(f"poses must have shape ({dd.size + 1}, 3), got {poses.shape}")
    P = check_cov3(cov0)
    if plan.var_heading is not None:
        P = np.zeros((3, 3))
        P[:2, :2] = check_cov3(cov0)[:2, :2]
        P[2, 2] = plan.var_heading[0]
    var_params = plan.var_params
    S = None if var_params is None else np.zeros((3, var_params.size))
    if S is not None and var_params is not None and plan.bias_heading is not None and plan.bias_heading.any():
        # A heading-sensor offset moves the measured start heading too (θ_0 = θ_meas,0 + δ).
        S[2] = plan.bias_heading
        yield 0, (P + (S * var_params) @ S.T)[None]
    else:
        yield 0, P[None].copy()
    n = max(int(chunk_size), 1)
    state = new_heading_state()
    stream = out is not None and out.shape[0] >= _STREAM_ROWS
    sums = np.zeros(3)
    for a in range(0, dd.size, n):
        b = min(a + n, dd.size)
        theta = poses[a:b, 2]
        rows = None if out is None else out[a + 1:b + 1]
        white = _white_chunk(plan, engine, theta, dd[a:b], dtheta[a:b], a, b, P, parallel,
                             state, rows, stream)
        if rows is not None and white is not rows:  # engines that return a new array
            rows[...] = white
            white = rows
        P = white[-1].copy()
        var_lateral = plan.var_lateral(a, b)
        if var_lateral is not None:
            # Position-only noise passes every engine's step unchanged, so its running
            # sum adds to the rows and is carried apart (odomkit.propagate.lateral).
            accumulate_lateral(theta, dtheta[a:b], var_lateral, plan.method, sums, white)
        if S is not None and var_params is not None:
            sens = _bias_chunk(plan, theta, dd[a:b], dtheta[a:b], a, b, S)
            S = sens[-1]
            # The bias and the white noise are independent, so their covariances add:
            # S_k diag(σ²) S_k^T is the exact (linearised) effect of a constant error.
            white += np.einsum("nip,p,njp->nij", sens, var_params, sens)
        yield a + 1, white


def track_covariance(
    steps: BodySteps,
    poses: ArrayLike,
    noise: NoiseArg,
    cov0: ArrayLike,
    method: str = "exact",
    engine: str = "recursion",
    *,
    out: NDArray[np.float64] | None = None,
    chunk_size: int = DEFAULT_CHUNK,
    parallel: bool = False,
    progress: Progress = NO_PROGRESS,
) -> NDArray[np.float64]:
    """Covariance of every pose of a dead-reckoned log.

    Parameters
    ----------
    steps : odomkit.kinematics.BodySteps
        M steps: ``dd``, ``dtheta``, ``dt``, ``inputs`` (``d_left``/``d_right``,
        ``travel``/``steer``, ``heading``) and ``robot``.
    poses : array_like, shape (M + 1, 3)
        The track dead-reckoned from ``steps`` (headings at the start of each step are
        ``poses[:-1, 2]``; for a compass robot the measured heading).
    noise : noise model or tuple of noise models
        Any of :mod:`odomkit.noise`; each model's ``check_robot`` says which robots it
        applies to.
    cov0 : array_like, shape (3, 3)
        Covariance of the first pose (for a compass robot only its position block is
        used: the heading variance is the compass's).
    method : {"exact", "midpoint", "euler"}
        Step map of the track. ClassicalNoise always uses its own rotate-then-translate
        map (Chong–Kleeman eq. 1).
    engine : {"recursion", "transition"}
        Numba step recursion or Kelly's prefix-sum solution; they agree to round-off.
        Direct-heading odometry has its own (prefix-sum) solution and ignores this.
    out : ndarray, shape (M + 1, 3, 3), optional
        Written in place and returned; use :func:`iter_track_covariance` to avoid the
        full output altogether.
    chunk_size : int
        Steps per chunk; results do not depend on it.
    parallel : bool
        Recursion engine only: see :func:`propagate_recursion`.
    progress : Progress
        One stage, ``"covariance"`` of M steps, advanced chunk by chunk
        (:mod:`odomkit.progress`); never changes a number.

    Returns
    -------
    cov : ndarray, shape (M + 1, 3, 3)

    Examples
    --------
    >>> from odomkit.kinematics import BodySteps, diff_body_steps
    >>> from odomkit.integrate import dead_reckon
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.robot import DiffDrive
    >>> dl = dr = np.full(100, 0.01)
    >>> dd, dth = diff_body_steps(dl, dr, 0.4)
    >>> steps = BodySteps(dd, dth, np.full(100, 0.1), {"d_left": dl, "d_right": dr},
    ...                   DiffDrive(0.4))
    >>> cov = track_covariance(steps, dead_reckon(dd, dth), WheelNoise(0.01, 0.01),
    ...                        np.zeros((3, 3)))
    >>> round(float(cov[-1, 0, 0]), 12)   # straight 1 m: (k_L² + k_R²)·D/4
    5e-05
    """
    m = int(np.asarray(steps.dd).size)
    if out is None:
        out = np.empty((m + 1, 3, 3))
    elif out.shape != (m + 1, 3, 3):
        raise ModelError(f"out must have shape ({m + 1}, 3, 3), got {out.shape}")
    # The kernel writes straight into ``out`` when it can (no chunk is copied).
    direct, _ = _writes_in_place(out)
    with stage(progress, m, "covariance"):
        for row, chunk in _chunks(steps, poses, noise, cov0, method, engine, chunk_size, parallel,
                                  out if direct else None):
            if not direct or row == 0:
                out[row:row + chunk.shape[0]] = chunk
            if row:  # row 0 is the start pose; every later chunk is that many steps
                progress.advance(chunk.shape[0])
    return out
