"""The step recursion (numba kernel): against a plain loop, the continuous limit on an arc,
published numbers of the classical model, and finite-difference truth for whole logs."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit import jit
from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, diff_body_steps, tricycle_body_steps
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)
from odomkit.noise.wheel import classical_input_cov, wheel_input_cov
from odomkit.propagate import recursion
from odomkit.propagate.inputs import any_step_displacement, any_step_jacobians
from odomkit.propagate.recursion import propagate_recursion, track_covariance
from odomkit.propagate.transition import transition_matrix
from odomkit.robot import CompassOdometry, DiffDrive, GyroOdometry, Tricycle

METHODS = ["exact", "midpoint", "euler", "classical"]


def random_path(rng, m, curvy=0.3):
    dd = rng.uniform(-0.05, 0.2, m)
    dtheta = rng.normal(0.0, curvy, m)
    theta = 0.4 + np.concatenate([[0.0], np.cumsum(dtheta)[:-1]])
    return theta, dd, dtheta


def random_psd(rng, shape, scale):
    """Random PSD matrices of size shape[-1], batch shape shape[:-1]."""
    n = shape[-1]
    a = rng.normal(size=shape[:-1] + (n, n))
    return scale * a @ np.swapaxes(a, -1, -2)


def plain_loop(theta, dd, dtheta, q, p0, method):
    """Reference: Chong–Kleeman eq. (2) with full 3x3 products and the step Jacobians."""
    F, G = any_step_jacobians(theta, dd, dtheta, method)
    out = [p0]
    for k in range(dd.size):
        out.append(F[k] @ out[-1] @ F[k].T + G[k] @ q[k] @ G[k].T)
    return np.array(out)


@pytest.mark.parametrize("method", METHODS)
def test_kernel_equals_plain_loop(method):
    rng = np.random.default_rng(3)
    theta, dd, dtheta = random_path(rng, 300)
    q = random_psd(rng, (300, 2), 1e-4)
    p0 = random_psd(rng, (3,), 1e-3)
    got = propagate_recursion(theta, dd, dtheta, q, p0, method)
    want = plain_loop(theta, dd, dtheta, q, p0, method)
    assert np.allclose(got, want, rtol=1e-12, atol=1e-15 * np.abs(want).max())


def assert_rounding_close(got, want, rel=1e-12):
    """Each matrix agrees to ``rel`` of its largest entry. Entry-wise relative error is
    no measure of rounding here: a cross term that cancels to 1e-4 of the matrix scale
    turns a 1e-16 change of a heading's cos/sin into 1e-12 of that entry."""
    scale = np.abs(want).max(axis=(-2, -1), keepdims=True)
    assert np.all(np.abs(got - want) <= rel * scale)


def test_numpy_fallback_equals_kernel(monkeypatch):
    rng = np.random.default_rng(4)
    theta, dd, dtheta = random_path(rng, 200)
    q = random_psd(rng, (200, 2), 1e-4)
    fast = propagate_recursion(theta, dd, dtheta, q, np.eye(3) * 1e-3)
    monkeypatch.setattr(recursion, "_load_kernel", lambda parallel=False: None)
    slow = propagate_recursion(theta, dd, dtheta, q, np.eye(3) * 1e-3)
    # The kernel turns a carried heading vector where the numpy loop calls cos(θ + Δθ/2):
    # equal to rounding, not bit for bit (before the turned vector, rtol=1e-12, atol=0
    # held entry-wise; now 3e-15 of each matrix's scale, 5e-12 of one cancelled entry).
    assert_rounding_close(fast, slow, 1e-13)


def test_missing_numba_warns_and_still_works(monkeypatch):
    monkeypatch.setitem(sys.modules, "odomkit.propagate._numba", None)  # import fails
    monkeypatch.setattr(jit, "_cache", {})  # forget the loaded kernels (restored after)
    q = np.tile(np.diag([1e-4, 1e-4]), (3, 1, 1))
    with pytest.warns(UserWarning, match="numba is not installed"):
        cov = propagate_recursion(np.zeros(3), np.ones(3), np.zeros(3), q, np.zeros((3, 3)))
    assert cov[-1, 0, 0] == pytest.approx(3e-4)


@pytest.mark.parametrize("method", METHODS)
def test_parallel_kernel_gives_the_same_numbers(method):
    rng = np.random.default_rng(12)
    theta, dd, dtheta = random_path(rng, 5000)
    q = random_psd(rng, (5000, 2), 1e-4)
    serial = propagate_recursion(theta, dd, dtheta, q, np.eye(3), method)
    parallel = propagate_recursion(theta, dd, dtheta, q, np.eye(3), method, parallel=True)
    assert np.array_equal(serial, parallel)


@pytest.mark.parametrize("chunk", [1, 7, 64])
def test_chunk_size_does_not_change_results(chunk):
    rng = np.random.default_rng(5)
    theta, dd, dtheta = random_path(rng, 500)
    q = random_psd(rng, (500, 2), 1e-4)
    ref = propagate_recursion(theta, dd, dtheta, q, np.eye(3) * 1e-2, chunk_size=10**6)
    got = propagate_recursion(theta, dd, dtheta, q, np.eye(3) * 1e-2, chunk_size=chunk)
    assert np.array_equal(ref, got)  # same operations in the same order


@pytest.mark.parametrize("method", METHODS)
def test_zero_noise_keeps_zero_and_maps_initial_covariance_by_phi(method):
    rng = np.random.default_rng(6)
    theta, dd, dtheta = random_path(rng, 100)
    q = np.zeros((100, 2, 2))
    assert not propagate_recursion(theta, dd, dtheta, q, np.zeros((3, 3)), method).any()
    p0 = random_psd(rng, (3,), 1.0)
    cov = propagate_recursion(theta, dd, dtheta, q, p0, method)
    dx, dy = any_step_displacement(theta, dd, dtheta, method)
    poses = np.zeros((101, 3))
    poses[1:, 0], poses[1:, 1] = np.cumsum(dx), np.cumsum(dy)
    phi = transition_matrix(poses, np.arange(101), 0)  # Kelly eq. (11), initial response
    assert np.allclose(cov, phi @ p0 @ np.swapaxes(phi, 1, 2), rtol=1e-10, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 60),
       curvy=st.floats(0.0, 3.0), method=st.sampled_from(METHODS))
def test_covariance_is_symmetric_psd(seed, m, curvy, method):
    rng = np.random.default_rng(seed)
    theta, dd, dtheta = random_path(rng, m, curvy)
    q = random_psd(rng, (m, 2), 1e-3)
    cov = propagate_recursion(theta, dd, dtheta, q, random_psd(rng, (3,), 1e-3), method)
    assert np.array_equal(cov, np.swapaxes(cov, 1, 2))
    eig = np.linalg.eigvalsh(cov)
    assert eig.min() >= -1e-12 * max(eig.max(), 1e-300)


# --- the turned heading vector (fast path) and its fallback ---------------------------

def long_wheel_log(rng, m, base=0.4):
    """A dead-reckoned differential-drive log with smooth turns and a few sharp ones
    (|Δθ/2| > 0.25, where the kernel calls sin/cos of the half angle)."""
    d_l = 0.01 + 0.005 * np.sin(np.arange(m) / 50.0) + rng.normal(0.0, 0.002, m)
    d_r = 0.01 + 0.005 * np.cos(np.arange(m) / 70.0) + rng.normal(0.0, 0.002, m)
    sharp = rng.choice(m, 20, replace=False)
    d_r[sharp] += rng.choice([-0.3, 0.3], 20)
    dd, dth = diff_body_steps(d_l, d_r, base)
    steps = BodySteps(dd, dth, np.full(m, 0.01), {"d_left": d_l, "d_right": d_r},
                      DiffDrive(base))
    return steps, dead_reckon(dd, dth, (0.0, 0.0, 2.0))


def anchors_of(theta, dd, dtheta, q, method):
    """Number of real cos/sin of θ_k the kernel took over one chunk."""
    state = recursion.new_heading_state()
    recursion.recursion_chunk(theta, dd, dtheta, q, np.zeros((3, 3)), method, state=state)
    return int(state[4])


@pytest.mark.parametrize("method", METHODS)
def test_turned_heading_equals_per_step_loop_on_a_dead_reckoned_track(method):
    """10^4 steps of consistent headings take the fast path (a real cos/sin only every
    ANCHOR steps) and still agree with the per-step numpy loop to rounding."""
    rng = np.random.default_rng(20)
    m = 10_000
    steps, poses = long_wheel_log(rng, m)
    theta, dd, dth = poses[:-1, 2], steps.dd, steps.dtheta
    assert np.abs(dth).max() > 0.5  # the sharp turns are there
    q = wheel_input_cov(steps.inputs["d_left"], steps.inputs["d_right"], 0.4,
                        WheelNoise(0.01, 0.02))
    p0 = random_psd(rng, (3,), 1e-4)
    assert anchors_of(theta, dd, dth, q, method) == -(-m // 128)
    got = propagate_recursion(theta, dd, dth, q, p0, method)
    want = np.empty((m + 1, 3, 3))
    want[0] = p0
    recursion._numpy_chunk(theta, dd, dth, q, p0, want[1:], method)
    assert_rounding_close(got, want, 1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_inconsistent_headings_take_the_per_step_fallback(method):
    """Headings that are not θ_0 + ΣΔθ (here jittered by 1e-6 rad, and separately one
    heading moved by 1e-9 rad inside an anchor block) must not be replaced by the turned
    vector: the kernel re-anchors at exactly the steps that disagree."""
    rng = np.random.default_rng(21)
    m = 3000
    steps, poses = long_wheel_log(rng, m)
    dd, dth = steps.dd, steps.dtheta
    q = random_psd(rng, (m, 2), 1e-6)
    jittered = poses[:-1, 2] + rng.normal(0.0, 1e-6, m)
    one_off = poses[:-1, 2].copy()
    one_off[1000] += 1e-9  # 1000 % 128 = 104: between regular anchors
    for theta, anchors in ((jittered, m), (one_off, -(-m // 128) + 2)):
        # one_off: step 1000 disagrees with the carried sum, and so does step 1001 with
        # the sum carried from the moved heading.
        assert anchors_of(theta, dd, dth, q, method) == anchors
        got = propagate_recursion(theta, dd, dth, q, np.zeros((3, 3)), method)
        want = np.zeros((m + 1, 3, 3))
        recursion._numpy_chunk(theta, dd, dth, q, np.zeros((3, 3)), want[1:], method)
        assert_rounding_close(got[1:], want[1:], 1e-12)


def test_nan_heading_propagates_instead_of_being_replaced():
    rng = np.random.default_rng(22)
    theta, dd, dtheta = random_path(rng, 300, 0.05)
    theta[150] = np.nan
    q = random_psd(rng, (300, 2), 1e-4)
    cov = propagate_recursion(theta, dd, dtheta, q, np.eye(3))
    want = np.empty((300, 3, 3))
    recursion._numpy_chunk(theta, dd, dtheta, q, np.eye(3), want, "exact")
    # Position rows go NaN from the bad step on, as in the per-step loop (whose full 3×3
    # products also spread the NaN into var θ, which the kernel never multiplies by a
    # heading term).
    assert np.isfinite(cov[:151]).all() and np.isnan(cov[151:, :2]).all()
    assert np.isnan(want[150:, :2]).all()
    assert_rounding_close(cov[1:151], want[:150])


@pytest.mark.parametrize("parallel", [False, True])
def test_wheel_noise_formed_in_the_kernel_equals_wheel_input_cov(parallel):
    """track_covariance lets the kernel form Q_k from the wheel travels; it must give
    the bits of the recursion fed with inputs.wheel_input_cov, for any chunking and
    with the parallel kernel (chunks not aligned with the anchor blocks)."""
    rng = np.random.default_rng(23)
    m, noise = 5000, WheelNoise(0.01, 0.02)
    steps, poses = long_wheel_log(rng, m)
    q = wheel_input_cov(steps.inputs["d_left"], steps.inputs["d_right"], 0.4, noise)
    p0 = random_psd(rng, (3,), 1e-4)
    want = propagate_recursion(poses[:-1, 2], steps.dd, steps.dtheta, q, p0)
    for chunk in (1000, 77, 10**6):
        got = track_covariance(steps, poses, noise, p0, chunk_size=chunk, parallel=parallel)
        assert np.array_equal(got, want)


def test_long_track_written_in_place_with_streaming_stores_equals_the_chunks():
    """A whole-track output of 2^18+ rows is written by the kernel in place with streaming
    stores, in one chunk or many; every path must give the bits of the chunks that
    iter_track_covariance yields (ordinary stores), and the lanes those of the
    step-by-step path (chunks of 77 steps never hold a whole block of 128)."""
    pytest.importorskip("numba")
    rng = np.random.default_rng(24)
    m, noise = (1 << 18) + 300, WheelNoise(0.01, 0.02)
    steps, poses = long_wheel_log(rng, m)
    p0 = random_psd(rng, (3,), 1e-4)
    want = np.concatenate([c for _, c in recursion.iter_track_covariance(steps, poses, noise, p0)])
    for chunk in (10**6, 4096):
        out = np.full((m + 1, 3, 3), np.nan)
        assert track_covariance(steps, poses, noise, p0, chunk_size=chunk, out=out) is out
        assert np.array_equal(out, want)
    head = 20_000  # the step-by-step path is slow: a prefix is enough
    short = BodySteps(steps.dd[:head], steps.dtheta[:head], steps.dt[:head],
                      {k: v[:head] for k, v in steps.inputs.items()}, steps.robot)
    by_step = track_covariance(short, poses[:head + 1], noise, p0, chunk_size=77)
    assert np.array_equal(by_step, want[:head + 1])


# --- a constant arc: the recursion converges to the continuous integral ---------------

def arc_quadrature(left, right, base, k_left, k_right, nodes=200):
    """P(1) = ∫0^1 Φ(1,s) G(s) Q G(s)^T Φ(1,s)^T ds for wheel travels s·L, s·R.

    Independent of odomkit: the circle is written analytically and the integral is
    done by Gauss–Legendre quadrature (the integrand is smooth, so 200 nodes are exact
    to round-off). G maps wheel-increment rates to pose rates; Q = diag(k²|L|, k²|R|).
    """
    s, w = np.polynomial.legendre.leggauss(nodes)
    s, w = 0.5 * (s + 1.0), 0.5 * w  # nodes and weights on [0, 1]
    dd, dth = 0.5 * (left + right), (right - left) / base
    theta = dth * s
    if dth == 0.0:
        x, y = dd * s, 0.0 * s
        x1, y1 = dd, 0.0
    else:
        r = dd / dth
        x, y = r * np.sin(theta), r * (1.0 - np.cos(theta))
        x1, y1 = r * np.sin(dth), r * (1.0 - np.cos(dth))
    q = np.diag([k_left**2 * abs(left), k_right**2 * abs(right)])
    total = np.zeros((3, 3))
    for wi, th, xi, yi in zip(w, theta, x, y, strict=True):
        g = np.array([[np.cos(th) / 2, np.cos(th) / 2], [np.sin(th) / 2, np.sin(th) / 2],
                      [-1.0 / base, 1.0 / base]])
        phi = np.array([[1.0, 0.0, -(y1 - yi)], [0.0, 1.0, x1 - xi], [0.0, 0.0, 1.0]])
        a = phi @ g
        total += wi * a @ q @ a.T
    return total


def arc_recursion(left, right, base, noise, n):
    d_l, d_r = np.full(n, left / n), np.full(n, right / n)
    dd, dth = diff_body_steps(d_l, d_r, base)
    poses = dead_reckon(dd, dth)
    return propagate_recursion(poses[:-1, 2], dd, dth, wheel_input_cov(d_l, d_r, base, noise),
                               np.zeros((3, 3)))[-1]


@pytest.mark.parametrize("left,right", [(3.0, 4.0), (2.0, 2.0), (-1.0, 1.0), (5.0, 1.0)])
def test_wheel_noise_on_an_arc_converges_to_the_quadrature(left, right):
    base, noise = 0.4, WheelNoise(0.01, 0.02)
    ref = arc_quadrature(left, right, base, noise.k_left, noise.k_right)
    errors = []
    for n in (10, 100, 1000):
        got = arc_recursion(left, right, base, noise, n)
        errors.append(np.abs(got - ref).max() / np.abs(ref).max())
    # Each step puts its input noise at the middle of its arc (the exact-arc G is the
    # midpoint lever), so the sum over steps is a midpoint rule for the integral:
    # second order, a tenfold finer partition cuts the error ~100x (demand 50x).
    assert errors[-1] < 1e-5
    assert errors[1] <= errors[0] / 50 and errors[2] <= errors[1] / 50


def test_per_wheel_model_is_consistent_under_segment_splitting():
    """Chong–Kleeman section 5: variances add along a path, whatever the cut.

    On a straight line x and θ variances are exactly partition-free
    ((k_L² + k_R²)D/4 and (k_L² + k_R²)D/b²); y and the whole arc covariance converge.
    """
    base, noise, dist = 0.4, WheelNoise(0.01, 0.02), 2.0
    var_sum = noise.k_left**2 + noise.k_right**2
    for n in (1, 2, 5, 50):
        cov = arc_recursion(dist, dist, base, noise, n)
        assert cov[0, 0] == pytest.approx(var_sum * dist / 4, rel=1e-12)
        assert cov[2, 2] == pytest.approx(var_sum * dist / base**2, rel=1e-12)
    fine, finer = arc_recursion(3.0, 4.0, base, noise, 500), arc_recursion(3.0, 4.0, base,
                                                                           noise, 1000)
    assert np.abs(fine - finer).max() < 2e-3 * np.abs(finer).max()


# --- the classical model -------------------------------------------------------------

def test_classical_model_reproduces_chong_kleeman_example():
    """Chong–Kleeman section 1: (i) one step of 2D, (ii) two steps of D (printed
    covariance matrices)."""
    d, s_d, s_a = 0.7, 0.05, 0.02
    one = propagate_recursion([0.0], [2 * d], [0.0],
                              classical_input_cov(1, ClassicalNoise(s_d, s_a)),
                              np.zeros((3, 3)), "classical")[-1]
    assert np.allclose(one, [[s_d**2, 0, 0], [0, 4 * d**2 * s_a**2, 2 * d * s_a**2],
                             [0, 2 * d * s_a**2, s_a**2]], rtol=1e-12, atol=1e-18)
    two = propagate_recursion([0.0, 0.0], [d, d], [0.0, 0.0],
                              classical_input_cov(2, ClassicalNoise(s_d, s_a)),
                              np.zeros((3, 3)), "classical")[-1]
    assert np.allclose(two, [[2 * s_d**2, 0, 0], [0, 5 * d**2 * s_a**2, 3 * d * s_a**2],
                             [0, 3 * d * s_a**2, 2 * s_a**2]], rtol=1e-12, atol=1e-18)


def test_classical_model_depends_on_step_size():
    """The same 2 m straight line cut into n steps: θ variance n·σ_α² grows with n, and
    even scaling σ² by 1/n (so θ agrees) leaves y inconsistent — unlike the wheel model."""
    sd, sa, dist = 0.01, 0.01, 2.0
    results = {}
    for n in (1, 2, 10):
        cov = propagate_recursion(np.zeros(n), np.full(n, dist / n), np.zeros(n),
                                  classical_input_cov(n, ClassicalNoise(sd / np.sqrt(n),
                                                                        sa / np.sqrt(n))),
                                  np.zeros((3, 3)), "classical")[-1]
        results[n] = cov
        assert cov[2, 2] == pytest.approx(sa**2, rel=1e-12)
    # one step: y var 4 d² σ² with d = D/2 -> D² σ_α²; the limit is D² σ_α²/3 (integrated)
    assert results[1][1, 1] == pytest.approx(dist**2 * sa**2, rel=1e-12)
    assert results[10][1, 1] < 0.5 * results[1][1, 1]


# --- whole logs: finite differences of dead reckoning give the truth -----------------

def diff_steps(rng, m, base=0.4):
    d_l = rng.uniform(0.0, 0.05, m)
    d_r = d_l + rng.normal(0.0, 0.02, m)
    dd, dth = diff_body_steps(d_l, d_r, base)
    return BodySteps(dd, dth, np.full(m, 0.05), {"d_left": d_l, "d_right": d_r},
                     DiffDrive(base))


@pytest.mark.parametrize("engine", ["recursion", "transition"])
@pytest.mark.parametrize("method", ["exact", "midpoint", "euler"])
def test_wheel_noise_track_equals_finite_difference_truth(numeric_jacobian, engine, method):
    """Linearised covariance of the final pose = J diag(k²|d|) J^T with J the
    finite-difference Jacobian of dead reckoning w.r.t. all 2M wheel travels."""
    rng = np.random.default_rng(7)
    m, base, noise = 40, 0.4, WheelNoise(0.01, 0.015)
    steps = diff_steps(rng, m, base)
    p0 = np.array([1.0, -2.0, 0.3])
    poses = dead_reckon(steps.dd, steps.dtheta, p0, method)
    cov = track_covariance(steps, poses, noise, np.zeros((3, 3)), method, engine)

    def final(x):
        dd, dth = diff_body_steps(x[:m], x[m:], base)
        return dead_reckon(dd, dth, p0, method)[-1]

    x = np.concatenate([steps.inputs["d_left"], steps.inputs["d_right"]])
    jac = numeric_jacobian(final, x, 1e-6)
    var = np.concatenate([noise.k_left**2 * np.abs(x[:m]), noise.k_right**2 * np.abs(x[m:])])
    assert np.allclose(cov[-1], jac @ np.diag(var) @ jac.T, rtol=1e-6, atol=1e-14)


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_tricycle_noise_track_equals_finite_difference_truth(numeric_jacobian, engine):
    """Speed v, steering α and sample period T of every step perturbed one at a time."""
    rng = np.random.default_rng(8)
    m, length = 30, 0.7
    v = rng.uniform(0.2, 1.0, m)
    steer = rng.normal(0.0, 0.4, m)
    dt = rng.uniform(0.04, 0.06, m)
    noise = TricycleNoise(sigma_speed=0.05, sigma_steer=0.02, sigma_dt=0.002)
    dd, dth = tricycle_body_steps(v * dt, steer, length)
    steps = BodySteps(dd, dth, dt, {"travel": v * dt, "steer": steer}, Tricycle(length))
    poses = dead_reckon(dd, dth, (0.0, 0.0, np.pi / 2))
    cov = track_covariance(steps, poses, noise, np.zeros((3, 3)), engine=engine)

    def final(x):
        vv, aa, tt = x[:m], x[m:2 * m], x[2 * m:]
        return dead_reckon(*tricycle_body_steps(vv * tt, aa, length), (0.0, 0.0, np.pi / 2))[-1]

    jac = numeric_jacobian(final, np.concatenate([v, steer, dt]), 1e-7)
    var = np.repeat([noise.sigma_speed**2, noise.sigma_steer**2, noise.sigma_dt**2], m)
    assert np.allclose(cov[-1], jac @ np.diag(var) @ jac.T, rtol=1e-6, atol=1e-14)


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_gyro_odometry_track_equals_finite_difference_truth(numeric_jacobian, engine):
    rng = np.random.default_rng(9)
    m = 50
    dd = rng.uniform(0.0, 0.1, m)
    dt = np.full(m, 0.1)
    rate = rng.normal(0.0, 0.5, m)
    steps = BodySteps(dd, rate * dt, dt, {"yaw_rate": rate}, GyroOdometry())
    noise = (SpeedNoise(alpha_ss=1e-3), GyroNoise(psd_gyro=1e-4))
    poses = dead_reckon(dd, rate * dt)
    cov = track_covariance(steps, poses, noise, np.zeros((3, 3)), engine=engine)

    def final(x):
        return dead_reckon(x[:m], x[m:] * dt)[-1]

    jac = numeric_jacobian(final, np.concatenate([dd, rate]), 1e-7)
    # var Δd = α_ss|Δd|; var of the rate sample = psd/Δt so that var Δθ = psd·Δt
    var = np.concatenate([1e-3 * dd, np.full(m, 1e-4 / 0.1)])
    assert np.allclose(cov[-1], jac @ np.diag(var) @ jac.T, rtol=1e-6, atol=1e-14)


def test_track_covariance_out_argument_and_chunks():
    rng = np.random.default_rng(10)
    steps = diff_steps(rng, 100)
    poses = dead_reckon(steps.dd, steps.dtheta)
    ref = track_covariance(steps, poses, WheelNoise(0.01, 0.01), np.eye(3) * 1e-4)
    out = np.empty((101, 3, 3))
    got = track_covariance(steps, poses, WheelNoise(0.01, 0.01), np.eye(3) * 1e-4, out=out,
                           chunk_size=13)
    assert got is out and np.array_equal(ref, out)


def test_track_covariance_rejects_mismatched_models():
    rng = np.random.default_rng(11)
    steps = diff_steps(rng, 5)
    poses = dead_reckon(steps.dd, steps.dtheta)
    zero = np.zeros((3, 3))
    with pytest.raises(ModelError, match="TricycleNoise applies to a Tricycle"):
        track_covariance(steps, poses, TricycleNoise(0.1, 0.1), zero)
    with pytest.raises(ModelError, match="CompassNoise"):
        track_covariance(steps, poses, CompassNoise(0.1), zero)
    with pytest.raises(ModelError, match="given twice"):
        track_covariance(steps, poses, (WheelNoise(0.1, 0.1), WheelNoise(0.1, 0.1)), zero)
    with pytest.raises(ModelError, match="engine"):
        track_covariance(steps, poses, WheelNoise(0.1, 0.1), zero, engine="magic")
    with pytest.raises(ModelError, match="method"):
        track_covariance(steps, poses, WheelNoise(0.1, 0.1), zero, method="rk4")
    with pytest.raises(ModelError, match="poses"):
        track_covariance(steps, poses[:-1], WheelNoise(0.1, 0.1), zero)
    with pytest.raises(ModelError, match="GyroNoise"):
        compass = BodySteps(steps.dd, steps.dtheta, steps.dt, {}, CompassOdometry())
        track_covariance(compass, poses, GyroNoise(0.1), zero)
