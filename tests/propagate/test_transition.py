"""Kelly's general solution (prefix sums) against the recursion, Φ against products of
step Jacobians, large coordinates, direct heading (Kelly eq. 10, 13) and the sensitivity."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon, dead_reckon_direct_heading
from odomkit.kinematics import BodySteps
from odomkit.noise import CompassNoise, ParameterUncertainty, SpeedNoise
from odomkit.noise.kelly import direct_heading_variances
from odomkit.propagate.inputs import any_step_jacobians
from odomkit.propagate.recursion import propagate_recursion, track_covariance
from odomkit.propagate.transition import (
    propagate_direct_heading,
    propagate_transition,
    transition_matrix,
)
from odomkit.robot import CompassOdometry


def random_psd(rng, n, scale, batch=()):
    a = rng.normal(size=batch + (n, n))
    return scale * a @ np.swapaxes(a, -1, -2)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 400), curvy=st.floats(0.0, 2.0),
       chunk=st.integers(1, 500), method=st.sampled_from(["exact", "midpoint", "euler"]))
def test_transition_equals_recursion(seed, m, curvy, chunk, method):
    rng = np.random.default_rng(seed)
    dd = rng.uniform(-0.1, 0.3, m)
    dth = rng.normal(0.0, curvy, m)
    poses = dead_reckon(dd, dth, (rng.normal(), rng.normal(), rng.normal()), method)
    q = random_psd(rng, 2, 1e-4, (m,))
    p0 = random_psd(rng, 3, 1e-3)
    rec = propagate_recursion(poses[:-1, 2], dd, dth, q, p0, method)
    tra = propagate_transition(poses, dd, dth, q, p0, method, chunk_size=chunk)
    scale = np.abs(rec).max(axis=(1, 2))[:, None, None]
    assert np.all(np.abs(tra - rec) <= 1e-9 * scale)


def test_transition_matrix_is_the_product_of_step_jacobians():
    rng = np.random.default_rng(1)
    dd, dth = rng.uniform(0, 0.3, 60), rng.normal(0, 0.5, 60)
    poses = dead_reckon(dd, dth)
    F, _ = any_step_jacobians(poses[:-1, 2], dd, dth, "exact")
    for j, k in [(0, 60), (5, 17), (30, 31), (12, 12)]:
        prod = np.eye(3)
        for i in range(j, k):
            prod = F[i] @ prod
        assert np.allclose(transition_matrix(poses, k, j), prod, rtol=0, atol=1e-12)


def test_large_coordinates_do_not_lose_digits():
    """Covariance does not depend on where the path is. Without a local origin the
    moments x_k² S0 − 2x_k S1 + S2 at x ~ 1e6 m would cancel ~10 of 16 digits."""
    rng = np.random.default_rng(2)
    m = 20000
    dd, dth = rng.uniform(0.0, 0.02, m), rng.normal(0.0, 0.05, m)
    q = random_psd(rng, 2, 1e-6, (m,))
    near = dead_reckon(dd, dth, (0.0, 0.0, 0.2))
    far = dead_reckon(dd, dth, (3e6, -5e6, 0.2))
    ref = propagate_transition(near, dd, dth, q, np.zeros((3, 3)), chunk_size=m)
    got = propagate_transition(far, dd, dth, q, np.zeros((3, 3)), chunk_size=4096)
    scale = np.abs(ref).max(axis=(1, 2))[1:, None, None]
    assert np.all(np.abs(got - ref)[1:] <= 1e-8 * scale)


def test_out_argument_and_shape_errors():
    poses = dead_reckon(np.ones(3), np.zeros(3))
    q = np.tile(np.eye(2) * 1e-4, (3, 1, 1))
    out = np.empty((4, 3, 3))
    assert propagate_transition(poses, np.ones(3), np.zeros(3), q, np.zeros((3, 3)),
                                out=out) is out
    with pytest.raises(ModelError, match="cov_input"):
        propagate_transition(poses, np.ones(3), np.zeros(3), q[:2], np.zeros((3, 3)))
    with pytest.raises(ModelError, match="poses"):
        propagate_transition(poses[:2], np.ones(3), np.zeros(3), q, np.zeros((3, 3)))
    with pytest.raises(ModelError, match="cov0"):
        propagate_transition(poses, np.ones(3), np.zeros(3), q, np.zeros((2, 2)))


# --- direct heading ------------------------------------------------------------------

@pytest.mark.parametrize("method", ["exact", "midpoint", "euler"])
def test_direct_heading_equals_finite_difference_truth(numeric_jacobian, method):
    """Every Δd and every heading sample perturbed: cov = J diag(var) J^T of the final
    pose of dead_reckon_direct_heading (heading measured, not integrated)."""
    rng = np.random.default_rng(3)
    m = 40
    dd = rng.uniform(0.0, 0.1, m)
    heading = np.cumsum(rng.normal(0.0, 0.3, m + 1))
    var_dd = 1e-3 * dd
    var_h = rng.uniform(1e-5, 1e-4, m + 1)
    cov = propagate_direct_heading(heading[:-1], dd, np.diff(heading), var_dd, var_h,
                                   np.zeros((2, 2)), method, chunk_size=7)

    def final(x):
        return dead_reckon_direct_heading(x[:m], x[m:], (0.0, 0.0), method)[-1]

    jac = numeric_jacobian(final, np.concatenate([dd, heading]), 1e-7)
    want = jac @ np.diag(np.concatenate([var_dd, var_h])) @ jac.T
    assert np.allclose(cov[-1], want, rtol=1e-6, atol=1e-15)
    assert np.allclose(cov[:, 2, 2], var_h)  # heading errors do not accumulate


def test_direct_heading_straight_line_matches_kelly_eq_13():
    """Kelly eq. (13): P = P0 + α_ss·diag(s, 0) + |V|·σ_θθ·diag(0, s) at constant speed.

    Discretely the first and last compass samples enter one step each instead of two, so
    var_y is |V|σ_θθ s·(1 − 1/(2M)): a relative tolerance of 1/M covers it."""
    m, v, dt, alpha, psd = 1000, 0.8, 0.05, 2e-3, 3e-4
    dd = np.full(m, v * dt)
    steps = BodySteps(dd, np.zeros(m), np.full(m, dt), {"heading": np.zeros(m + 1)},
                      CompassOdometry())
    cov = track_covariance(steps, dead_reckon(dd, np.zeros(m)),
                           (SpeedNoise(alpha), CompassNoise(psd)), np.diag([1e-4, 2e-4, 0.0]))
    s = v * dt * m
    assert cov[-1, 0, 0] == pytest.approx(1e-4 + alpha * s, rel=1e-12)
    assert cov[-1, 1, 1] == pytest.approx(2e-4 + v * psd * s, rel=1.0 / m)
    assert cov[-1, 0, 1] == pytest.approx(0.0, abs=1e-18)
    assert cov[-1, 2, 2] == pytest.approx(psd / dt)


def test_direct_heading_bias_scale_is_the_sensitivity():
    """A constant distance-scale error ε on a compass robot moves the end point by
    ε·(x_M − x_0, y_M − y_0): covariance σ² times the outer product of the displacement."""
    rng = np.random.default_rng(4)
    m = 300
    dd = rng.uniform(0.0, 0.05, m)
    heading = np.cumsum(rng.normal(0.0, 0.1, m + 1))
    steps = BodySteps(dd, np.diff(heading), np.full(m, 0.1), {"heading": heading},
                      CompassOdometry())
    poses = dead_reckon_direct_heading(dd, heading)
    cov = track_covariance(steps, poses, ParameterUncertainty(sigma_scale_left=0.01),
                           np.zeros((3, 3)))
    disp = poses[-1, :2] - poses[0, :2]
    assert np.allclose(cov[-1, :2, :2], 1e-4 * np.outer(disp, disp), rtol=1e-10, atol=1e-16)


def test_direct_heading_variances_need_positive_dt():
    assert np.allclose(direct_heading_variances([0.1, 0.2], CompassNoise(1e-3)),
                       [1e-2, 1e-3 / 0.15, 5e-3])
    with pytest.raises(ModelError, match="dt > 0"):
        direct_heading_variances([0.1, 0.0], CompassNoise(1e-3))
