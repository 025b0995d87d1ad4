"""Dead reckoning against exact answers and convergence orders."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon, dead_reckon_direct_heading, dead_reckon_wheels, path_length
from odomkit.kinematics import diff_body_steps

METHODS = ("exact", "midpoint", "euler")


def arc_end(pose0, length, dtheta):
    """Closed-form end pose of a constant-curvature arc (independent of the code)."""
    x0, y0, t0 = pose0
    if dtheta == 0:
        return np.array([x0 + length * np.cos(t0), y0 + length * np.sin(t0), t0])
    r = length / dtheta
    return np.array([x0 + r * (np.sin(t0 + dtheta) - np.sin(t0)),
                     y0 - r * (np.cos(t0 + dtheta) - np.cos(t0)), t0 + dtheta])


@pytest.mark.parametrize("method", METHODS)
def test_straight_run_is_exact_for_every_method(method):
    pose = dead_reckon(np.full(500, 0.01), np.zeros(500), (1.0, 2.0, 0.3), method)
    assert np.allclose(pose[-1], [1 + 5 * np.cos(0.3), 2 + 5 * np.sin(0.3), 0.3], atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_spin_on_the_spot_does_not_move(method):
    d_left, d_right = np.full(100, -0.001), np.full(100, 0.001)
    dd, dth = diff_body_steps(d_left, d_right, 0.2)
    pose = dead_reckon(dd, dth, (0.5, -0.5, 0.0), method)
    assert np.allclose(pose[:, :2], [0.5, -0.5], atol=0)
    assert pose[-1, 2] == pytest.approx(100 * 0.002 / 0.2)


def test_exact_matches_closed_form_arc_with_uneven_steps():
    rng = np.random.default_rng(1)
    fractions = rng.random(777)
    fractions /= fractions.sum()
    length, dtheta = 3.7, -5.0
    pose = dead_reckon(length * fractions, dtheta * fractions, (0.1, 0.2, 0.4), "exact")
    assert np.allclose(pose[-1], arc_end((0.1, 0.2, 0.4), length, dtheta), rtol=0, atol=1e-13)


def test_circle_closes_and_theta_stays_continuous():
    n = 1000
    pose = dead_reckon(np.full(n, 2 * np.pi / n), np.full(n, 2 * np.pi / n), (0, 0, 0), "exact")
    # Prefix sums of n terms of size ~1 accumulate about n·ε of rounding.
    assert np.allclose(pose[-1, :2], 0.0, atol=n * 1e-15)
    assert pose[-1, 2] == pytest.approx(2 * np.pi)  # continuous, not wrapped to 0
    assert np.all(np.diff(pose[:, 2]) > 0)


@pytest.mark.parametrize("method", METHODS)
def test_reversing_retraces_the_path(method):
    rng = np.random.default_rng(2)
    dd = rng.normal(0.01, 0.003, 300)
    dth = rng.normal(0, 0.02, 300)
    forward = dead_reckon(dd, dth, (0, 0, 0), method)
    # Drive the same steps backwards in reverse order: exact and midpoint are
    # time-symmetric and come home to rounding; euler's local error is first order,
    # |Δd|·|Δθ| per step, so its miss is bounded by the sum of those terms.
    back = dead_reckon(-dd[::-1], -dth[::-1], forward[-1], method)
    tol = 1e-12 if method != "euler" else float(np.sum(np.abs(dd * dth)))
    assert np.hypot(back[-1, 0], back[-1, 1]) < tol
    assert abs(back[-1, 2]) < 1e-12
    if method == "euler":
        assert np.hypot(back[-1, 0], back[-1, 1]) > 1e-6  # and it really is inexact
    assert path_length(np.concatenate((dd, -dd))) == pytest.approx(2 * np.abs(dd).sum())


def _sinusoidal_heading_error(method: str, n: int, a: float = 1.2, T: float = 2.0) -> float:
    """Unit speed with heading θ(t) = a·sin(t): increments are the exact heading changes
    an encoder would measure; the reference end point comes from scipy quadrature."""
    t = np.linspace(0.0, T, n + 1)
    theta = a * np.sin(t)
    pose = dead_reckon(np.diff(t), np.diff(theta), (0, 0, 0), method)
    x_ref = quad(lambda s: np.cos(a * np.sin(s)), 0, T, epsabs=1e-13, epsrel=1e-13)[0]
    y_ref = quad(lambda s: np.sin(a * np.sin(s)), 0, T, epsabs=1e-13, epsrel=1e-13)[0]
    return float(np.hypot(pose[-1, 0] - x_ref, pose[-1, 1] - y_ref))


@pytest.mark.parametrize(("method", "order"), [("euler", 1), ("midpoint", 2), ("exact", 2)])
def test_convergence_order(method, order):
    errors = [_sinusoidal_heading_error(method, n) for n in (200, 400, 800, 1600)]
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # Observed orders of an O(h^p) method approach p; 0.1 allows the higher-order terms.
    assert np.all(np.abs(observed - order) < 0.1), observed


def test_direct_heading_unwraps_compass_jumps():
    heading = np.array([3.1, -3.1, 3.1])  # crosses ±π twice: a wiggle, not two turns
    pose = dead_reckon_direct_heading(np.array([1.0, 1.0]), heading, (0, 0), "midpoint")
    assert abs(pose[-1, 2] - 3.1) < 1e-12
    assert pose[-1, 0] == pytest.approx(2 * np.cos(np.pi), abs=0.1)


def test_bad_arguments_are_model_errors():
    with pytest.raises(ModelError, match="method"):
        dead_reckon([1.0], [0.0], (0, 0, 0), "rk4")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="initial pose"):
        dead_reckon([1.0], [0.0], (0, 0))
    with pytest.raises(ModelError, match="equal length"):
        dead_reckon([1.0, 2.0], [0.0], (0, 0, 0))


@pytest.mark.parametrize("method", METHODS)
def test_numba_kernel_agrees_with_numpy(method):
    pytest.importorskip("numba")
    rng = np.random.default_rng(3)
    n = 5000
    dd = rng.normal(0.01, 0.02, n)  # with reversals
    # mostly small turns (polynomial branch) and some large ones (libm branch)
    dth = np.where(rng.random(n) < 0.05, rng.normal(0, 1.5, n), rng.normal(0, 0.05, n))
    dth[::97] = 0.0
    a = dead_reckon(dd, dth, (1.0, -2.0, 0.5), method, engine="numpy")
    b = dead_reckon(dd, dth, (1.0, -2.0, 0.5), method, engine="numba")
    # Different summation order and the rotated heading vector: a few ulps per step.
    assert np.allclose(a, b, rtol=0, atol=n * 1e-15)
    assert np.array_equal(a[:, 2], b[:, 2])  # the heading is the same prefix sum


def test_nan_step_is_rejected_with_its_index():
    dd = np.array([0.1, np.nan, 0.1])
    with pytest.raises(ModelError, match=r"dd\[1\] is nan"):
        dead_reckon(dd, np.zeros(3))


# --- the compiled pass (numba): its stages, tiers, streaming stores and checks ----------

def regime_steps(rng, per_chunk=1024):
    """Steps whose turns need each tier of the kernel in turn, chunk by chunk: small
    (|Δθ/2| < 0.04: short series), medium (< 1: full series), huge (libm); the last chunk
    is partial."""
    small = rng.normal(0.0, 0.01, per_chunk)
    medium = rng.uniform(-0.6, 0.6, per_chunk)
    huge = rng.normal(0.0, 0.05, per_chunk)
    huge[::50] = rng.choice([-3.0, 2.5], huge[::50].size)
    dth = np.concatenate([small, medium, huge, small[:300]])
    dd = rng.normal(0.01, 0.02, dth.size)
    return dd, dth


@pytest.mark.parametrize("method", METHODS)
def test_every_kernel_tier_agrees_with_numpy(method):
    pytest.importorskip("numba")
    dd, dth = regime_steps(np.random.default_rng(4))
    a = dead_reckon(dd, dth, (0.3, -0.2, 1.0), method, engine="numpy")
    b = dead_reckon(dd, dth, (0.3, -0.2, 1.0), method, engine="numba")
    assert np.allclose(a, b, rtol=0, atol=dd.size * 1e-15)
    assert np.array_equal(a[:, 2], b[:, 2])


@pytest.mark.parametrize("engine", ["numpy", "numba"])
def test_wheels_equal_body_steps_then_dead_reckon(engine):
    """The fused pass forms (Δd, Δθ) as kinematics.diff_body_steps does: the same
    headings bit for bit, positions to rounding; ticks with a scale give the same as
    metres."""
    if engine == "numba":
        pytest.importorskip("numba")
    rng = np.random.default_rng(5)
    ticks_l = rng.integers(-5, 60, 3000).astype(float)
    ticks_r = rng.integers(-5, 60, 3000).astype(float)
    scale_l, scale_r, base = 2.1e-4, 1.9e-4, 0.37
    dd, dth = diff_body_steps(ticks_l * scale_l, ticks_r * scale_r, base)
    want = dead_reckon(dd, dth, (1.0, 2.0, -0.5), "exact", engine="numpy")
    got = dead_reckon_wheels(ticks_l, ticks_r, base, (1.0, 2.0, -0.5), "exact", engine,
                             scale_left=scale_l, scale_right=scale_r)
    assert np.array_equal(got[:, 2], want[:, 2])
    assert np.allclose(got, want, rtol=0, atol=3000 * 1e-15)
    metres = dead_reckon_wheels(ticks_l * scale_l, ticks_r * scale_r, base, (1.0, 2.0, -0.5),
                                "exact", engine)
    assert np.array_equal(metres[:, 2], want[:, 2])


def test_long_log_with_streaming_stores_closes_the_circle():
    """Above STREAM_FROM the poses are written with non-temporal stores: a constant-
    curvature log must still land on the circle's closed form, into ``out`` in place."""
    pytest.importorskip("numba")
    from odomkit._integrate_numba import STREAM_FROM

    n = STREAM_FROM + 777
    left, right = np.full(n, 1e-3), np.full(n, 1.2e-3)
    out = np.full((n + 1, 3), np.nan)
    got = dead_reckon_wheels(left, right, 0.5, (0.0, 0.0, 0.0), "exact", "numba", out=out)
    assert got is out
    travel, turn = n * 1.1e-3, n * 0.2e-3 / 0.5
    # n·ε of rounding in the sums, times the size of the coordinates (~r = 5.5 m)
    assert np.allclose(out[-1], arc_end((0.0, 0.0, 0.0), travel, turn), rtol=0, atol=n * 1e-14)
    k = np.arange(0, n + 1, 9973)
    radius = travel / turn
    assert np.allclose(np.hypot(out[k, 0], out[k, 1] - radius), radius, rtol=0, atol=n * 1e-14)


def test_kernel_path_names_the_non_finite_input():
    """The kernel path checks the inputs only when the last pose is not finite; it must
    still name the first bad element, and a finite log that overflows is no error."""
    pytest.importorskip("numba")
    dd, dth = np.full(30_000, 0.01), np.zeros(30_000)
    dd[12_345] = np.nan
    with pytest.raises(ModelError, match=r"dd\[12345\] is nan"):
        dead_reckon(dd, dth, engine="numba")
    right = np.full(30_000, 0.01)
    right[29_999] = -np.inf
    with pytest.raises(ModelError, match=r"d_right\[29999\] is -inf"):
        dead_reckon_wheels(np.full(30_000, 0.01), right, 0.4, engine="numba")
    huge = dead_reckon(np.full(30_000, 1e305), np.zeros(30_000), engine="numba")
    assert np.isinf(huge[-1, 0])


def test_out_must_match():
    with pytest.raises(ModelError, match="out must be"):
        dead_reckon(np.ones(5), np.zeros(5), out=np.empty((5, 3)))
    with pytest.raises(ModelError, match="out must be"):
        dead_reckon_wheels(np.ones(5), np.ones(5), 0.4, out=np.empty((6, 3), dtype=np.float32))
    with pytest.raises(ModelError, match="wheel_base"):
        dead_reckon_wheels(np.ones(5), np.ones(5), 0.0)
