"""Differential-drive noise (:mod:`odomkit.noise.wheel`): per-wheel white noise mapped to
(Δd, Δθ) by the wheel Jacobian (Chong–Kleeman eq. 4), its compiled-engine form, and the
classical per-step model with its own step map (Chong–Kleeman eq. 1–3)."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, diff_body_steps, tricycle_body_steps
from odomkit.noise import ClassicalNoise, NoiseSet, WheelNoise
from odomkit.noise.wheel import WheelInputs, classical_input_cov, wheel_input_cov
from odomkit.propagate.recursion import track_covariance
from odomkit.robot import DiffDrive, Tricycle

M = 40


def diff_log(seed: int, robot: DiffDrive) -> BodySteps:
    """M random steps (some backwards) of ``robot``, its travels through b_eff."""
    rng = np.random.default_rng(seed)
    dl, dr = rng.uniform(-0.02, 0.05, M), rng.uniform(-0.02, 0.05, M)
    dd, dth = diff_body_steps(dl, dr, robot.effective_wheel_base)
    return BodySteps(dd, dth, np.full(M, 0.1), {"d_left": dl, "d_right": dr}, robot)


def test_wheel_input_cov_maps_wheel_variances(numeric_jacobian):
    """Cov(Δd, Δθ) = J diag(k²|d|) J^T with J by finite differences; the off-diagonal
    (σR² − σL²)/(2b) is what the Sun–Gao exercise drops, and θθ adds the variances."""
    dl, dr, base, noise = np.array([0.1, -0.2]), np.array([0.3, 0.05]), 0.5, WheelNoise(0.01, 0.03)
    for i in range(2):
        jac = numeric_jacobian(lambda w: np.array(diff_body_steps(w[0], w[1], base)),
                               [dl[i], dr[i]])
        want = jac @ np.diag([1e-4 * abs(dl[i]), 9e-4 * abs(dr[i])]) @ jac.T
        assert np.allclose(wheel_input_cov(dl, dr, base, noise)[i], want, rtol=1e-8)
    q = wheel_input_cov([1.0], [1.0], base, noise)[0]
    assert q[0, 1] == pytest.approx((9e-4 - 1e-4) / (2 * base))
    assert q[1, 1] == pytest.approx((9e-4 + 1e-4) / base**2)


def test_wheel_noise_maps_through_the_effective_wheel_base(numeric_jacobian):
    """A wheel-base correction c_b (Borenstein–Feng eq. 4.32) changes the Jacobian: the
    model must use b_eff = c_b·b, not the nominal b."""
    robot = DiffDrive(0.4, c_wheel_base=1.25)  # b_eff = 0.5
    steps = diff_log(21, robot)
    dl, dr = steps.inputs["d_left"], steps.inputs["d_right"]
    q = WheelNoise(0.01, 0.03).input_cov(steps, 5, 25)
    assert q.shape == (20, 2, 2)
    for k in (5, 13, 24):
        jac = numeric_jacobian(lambda w: np.array(diff_body_steps(w[0], w[1], 0.5)), [dl[k], dr[k]])
        want = jac @ np.diag([1e-4 * abs(dl[k]), 9e-4 * abs(dr[k])]) @ jac.T
        assert np.allclose(q[k - 5], want, rtol=1e-8, atol=1e-20)


def test_compiled_inputs_give_wheel_input_cov_chunk_by_chunk():
    """What the numba recursion consumes (:class:`WheelInputs`) forms the same Q_k, to the
    bit, as :func:`wheel_input_cov` on any chunk; its constants are those of
    J = [[½, ½], [−1/b, 1/b]] (Borenstein–Feng eq. 2.2–2.4) worked out by hand."""
    robot = DiffDrive(0.4, c_wheel_base=1.25)
    steps = diff_log(22, robot)
    dl, dr = steps.inputs["d_left"], steps.inputs["d_right"]
    noise = WheelNoise(0.01, 0.03)
    wheel = noise.compiled_inputs(steps)
    assert isinstance(wheel, WheelInputs)
    assert np.array_equal(wheel.d_left, dl) and np.array_equal(wheel.d_right, dr)
    b = 0.5
    # (k_L², k_R², J00², J01·J11, J11²)
    assert np.allclose(wheel.coefficients, [1e-4, 9e-4, 0.25, 1 / (2 * b), 1 / b**2], rtol=1e-15)
    bounds = [0, 7, 8, 25, M]
    parts = []
    for a, e in zip(bounds[:-1], bounds[1:], strict=True):
        got = wheel.cov_input(a, e)
        assert got.shape == (e - a, 2, 2)
        assert np.array_equal(got, wheel_input_cov(dl[a:e], dr[a:e], b, noise))
        assert np.array_equal(got, noise.input_cov(steps, a, e))
        parts.append(got)
    assert np.array_equal(np.concatenate(parts), wheel_input_cov(dl, dr, b, noise))


def test_wheel_noise_factor_has_one_column_per_wheel():
    """A Monte Carlo draws each wheel's error from its own normal: column i of J diag(σ)
    is wheel i's σ = k·√|d| times its Jacobian column (½, ∓1/b)."""
    steps = diff_log(23, DiffDrive(0.5))
    dl, dr = steps.inputs["d_left"], steps.inputs["d_right"]
    factor = WheelNoise(0.01, 0.03).input_factor(steps, 0, M)
    sigma_l, sigma_r = 0.01 * np.sqrt(np.abs(dl)), 0.03 * np.sqrt(np.abs(dr))
    assert np.allclose(factor[:, :, 0], np.stack([0.5 * sigma_l, -sigma_l / 0.5], axis=-1), rtol=1e-14)
    assert np.allclose(factor[:, :, 1], np.stack([0.5 * sigma_r, sigma_r / 0.5], axis=-1), rtol=1e-14)


def test_wheel_noise_needs_wheel_travels():
    travel, steer = np.full(3, 0.1), np.zeros(3)
    steps = BodySteps(*tricycle_body_steps(travel, steer, 0.7), np.full(3, 0.1),
                      {"travel": travel, "steer": steer}, Tricycle(0.7))
    with pytest.raises(ModelError, match="WheelNoise needs the per-step input 'd_left'.*Tricycle"):
        WheelNoise(0.1, 0.1).input_cov(steps, 0, 3)


# --- the classical model --------------------------------------------------------------

def test_classical_input_cov_is_one_diagonal_for_every_step_of_any_robot():
    """Chong–Kleeman eq. (3): Cov(D_k, α_k) = diag(σ_D², σ_α²), whatever the step."""
    noise = ClassicalNoise(0.1, 0.02)
    want = np.diag([0.1**2, 0.02**2])
    q = classical_input_cov(5, noise)
    assert q.shape == (5, 2, 2) and np.allclose(q, want, rtol=1e-15, atol=0)
    travel, steer = np.array([0.1, 0.0, 0.3, 0.2]), np.array([0.2, -0.1, 0.0, 0.5])
    steps = BodySteps(*tricycle_body_steps(travel, steer, 0.7), np.full(4, 0.1),
                      {"travel": travel, "steer": steer}, Tricycle(0.7))
    assert np.allclose(noise.input_cov(steps, 1, 4), want, rtol=1e-15, atol=0)
    assert NoiseSet.of(noise).step_map("midpoint") == "classical"


def test_classical_noise_ignores_the_robot_and_uses_its_own_step_map(straight_diff):
    steps = straight_diff(4, dist=2.0)
    poses = dead_reckon(steps.dd, steps.dtheta)
    cov = track_covariance(steps, poses, ClassicalNoise(0.01, 0.02), np.zeros((3, 3)))[-1]
    # 4 steps of D = 0.5 with the rotation first: y lever arms 2.0, 1.5, 1.0, 0.5
    assert cov[1, 1] == pytest.approx(0.02**2 * (4 + 2.25 + 1 + 0.25))
    assert cov[0, 0] == pytest.approx(4 * 0.01**2)
