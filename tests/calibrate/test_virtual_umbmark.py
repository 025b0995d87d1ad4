"""The virtual UMBmark robot and UMBmark calibration on it.

Truth here comes from (a) an independent integration of the true wheel travels with
odomkit.integrate (midpoint rule, 1 mm steps) built from the physics in the test, (b) the
closed-form geometry of Borenstein–Feng eq. (4.1)-(4.16) before their small-angle
approximation, (c) scaling laws (first- vs second-order residuals) and (d) the
first-order propagation of the cluster noise through the calibration.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.calibrate.umbmark import umbmark
from odomkit.calibrate.virtual import (
    SystematicErrors,
    iterate_umbmark,
    run_virtual_umbmark,
    square_wheel_steps,
    true_robot,
    virtual_umbmark_logs,
)
from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.noise import WheelNoise
from odomkit.robot import DiffDrive

L, B = 4.0, 0.34


def reference_end_pose(err: SystematicErrors, robot: DiffDrive, direction: str,
                       step: float = 1e-3) -> np.ndarray:
    """Independent integration: true wheel travel of each segment from the physics,
    integrated with the midpoint rule in ``step`` metre pieces."""
    sign = 1.0 if direction == "ccw" else -1.0
    d_left_nom, d_right_nom = 2 * err.E_s / (err.E_d + 1), 2 * err.E_s * err.E_d / (err.E_d + 1)
    # Ticks the controller commands / what the believed robot reads per metre of each wheel.
    k_left = d_left_nom * robot.m_per_tick_left / robot.scale_left
    k_right = d_right_nom * robot.m_per_tick_right / robot.scale_right
    arc = robot.effective_wheel_base * math.pi / 4  # believed wheel travel of a 90° turn
    dl, dr = [], []
    for _ in range(4):
        n = round(L / step)
        dl += [k_left * L / n] * n
        dr += [k_right * L / n] * n
        m = max(1, round(arc / step))
        dl += [-sign * k_left * arc / m] * m
        dr += [sign * k_right * arc / m] * m
    dl, dr = np.array(dl), np.array(dr)
    b_true = err.E_b * robot.wheel_base
    return dead_reckon((dl + dr) / 2, (dr - dl) / b_true, method="midpoint")[-1]


@pytest.mark.parametrize("err", [SystematicErrors(1.002, 1.01),
                                 SystematicErrors(0.995, 0.98, 1.01)])
@pytest.mark.parametrize("robot", [DiffDrive(B), DiffDrive(B, c_left=0.999, c_right=1.002,
                                                           c_wheel_base=1.005)])
def test_noise_free_runs_match_independent_integration(err, robot) -> None:
    runs = run_virtual_umbmark(err, robot, L, 2)
    for direction, true_end, odom_end in [("cw", runs.true_end_cw, runs.odom_end_cw),
                                          ("ccw", runs.true_end_ccw, runs.odom_end_ccw)]:
        ref = reference_end_pose(err, robot, direction)
        # Midpoint error per step ~ d·dθ²/24: far below 1e-7 m here.
        np.testing.assert_allclose(true_end, np.tile(ref, (2, 1)), rtol=0, atol=1e-7)
        # The odometry believes it drove a perfect square and made four full turns.
        sign = 1.0 if direction == "ccw" else -1.0
        np.testing.assert_allclose(odom_end, [[0, 0, sign * 2 * math.pi]] * 2, atol=1e-12)
    np.testing.assert_allclose(runs.errors_cw, runs.true_end_cw[:, :2] - runs.odom_end_cw[:, :2])


def test_pure_type_a_matches_borenstein_feng_geometry() -> None:
    # Eq. (4.1)-(4.8) before the small-angle approximation, α = (π/2)(1 − 1/E_b).
    a = math.pi / 2 * (1 - 1 / 1.02)
    runs = run_virtual_umbmark(SystematicErrors(E_b=1.02), DiffDrive(B), L, 1, step=0.37)
    ccw = [L * (1 + math.sin(a) - math.cos(2 * a) - math.sin(3 * a)),
           L * (math.cos(a) + math.sin(2 * a) - math.cos(3 * a))]
    cw = [ccw[0], -ccw[1]]
    np.testing.assert_allclose(runs.errors_ccw, [ccw], atol=1e-12)
    np.testing.assert_allclose(runs.errors_cw, [cw], atol=1e-12)


def test_stop_is_not_quantised() -> None:
    # A step that does not divide the leg or the turn: the odometry still stops exactly.
    dl, dr = square_wheel_steps(DiffDrive(B), 4.0, "cw", step=0.3)
    assert (dl + dr).sum() / 2 == pytest.approx(4 * 4.0, abs=1e-12)
    assert (dr - dl).sum() / B == pytest.approx(-2 * math.pi, abs=1e-12)
    a = run_virtual_umbmark(SystematicErrors(1.002, 1.01), DiffDrive(B), L, 1, step=0.3)
    b = run_virtual_umbmark(SystematicErrors(1.002, 1.01), DiffDrive(B), L, 1, step=0.0071)
    np.testing.assert_allclose(a.errors_cw, b.errors_cw, atol=1e-12)
    np.testing.assert_allclose(a.errors_ccw, b.errors_ccw, atol=1e-12)


def test_umbmark_cuts_e_max_tenfold_noise_free() -> None:
    it = iterate_umbmark(SystematicErrors(E_d=1.002, E_b=1.01), DiffDrive(B), L, 1, iterations=2)
    before, after, after2 = it.e_max_syst
    assert before > 0.3  # Borenstein–Feng's LabMate had 317 mm on the same square
    assert after < before / 10
    assert after2 < after / 10  # a second pass removes the second-order rest
    first = it.results[0]
    # Estimates agree with the truth to second order (relative errors ~ 1e-2 of the error).
    assert first.E_d == pytest.approx(1.002, abs=0.002 * 0.02)
    assert first.E_b == pytest.approx(1.01, abs=0.01 * 0.05)
    assert it.robots[-1].c_right / it.robots[-1].c_left == pytest.approx(1.002, abs=1e-7)
    assert it.robots[-1].c_wheel_base == pytest.approx(1.01, abs=1e-7)


def test_pure_wheel_base_error_gives_beta_zero() -> None:
    # CW and CCW are mirror images: β_x and β_y vanish, so E_d = 1 and R is infinite.
    r = iterate_umbmark(SystematicErrors(E_b=1.01), DiffDrive(B), L, 1, iterations=0).results[0]
    assert abs(r.beta) < 1e-15
    assert r.E_d == pytest.approx(1.0, abs=1e-15)
    assert abs(r.radius) > 1e12


def test_scale_error_is_read_as_a_turn_error() -> None:
    # Eq. (2.15): a 1 % larger average diameter turns 1 % more, so UMBmark reports
    # E_b ≈ 1/1.01 (the effective wheel base must grow to compensate), and the square
    # closes again; UMBmark cannot see E_s in the legs.
    it = iterate_umbmark(SystematicErrors(E_s=1.01), DiffDrive(B), L, 1, iterations=1)
    assert it.results[0].E_b == pytest.approx(1 / 1.01, rel=1e-3)
    assert it.e_max_syst[1] < it.e_max_syst[0] / 50


@pytest.mark.parametrize("eps", [0.005, 0.01, 0.02])
def test_c_b_discrepancy(eps: float) -> None:
    """Borenstein–Feng's E_b leaves a residual wheel-base error O(ε²); Chong–Kleeman's
    c_b = π/(π − α) leaves ≈ ε/2 (half the Type A error)."""
    err = SystematicErrors(E_b=1 + eps)
    bf = iterate_umbmark(err, DiffDrive(B), L, 1, iterations=1)
    ck = iterate_umbmark(err, DiffDrive(B), L, 1, iterations=1, variant="chong-kleeman")
    resid_bf = bf.robots[1].c_wheel_base / (1 + eps) - 1
    resid_ck = ck.robots[1].c_wheel_base / (1 + eps) - 1
    assert abs(resid_bf) < eps**2  # second order (measured: ≈ 0.7 ε²)
    assert resid_ck / eps == pytest.approx(-0.5, abs=0.02)  # first order, half left
    assert bf.e_max_syst[1] < bf.e_max_syst[0] * 20 * eps  # residual/initial ~ ε
    assert ck.e_max_syst[1] / ck.e_max_syst[0] == pytest.approx(0.5, abs=0.03)


def test_c_b_residual_scales_quadratically() -> None:
    resid = []
    for eps in (0.004, 0.008, 0.016):
        it = iterate_umbmark(SystematicErrors(E_b=1 + eps), DiffDrive(B), L, 1, iterations=1)
        resid.append(it.robots[1].c_wheel_base / (1 + eps) - 1)
    # Doubling ε quadruples a second-order residual.
    assert resid[1] / resid[0] == pytest.approx(4, rel=0.1)
    assert resid[2] / resid[1] == pytest.approx(4, rel=0.1)


def test_seed_reproducible_and_noise_independent_of_step() -> None:
    noise = WheelNoise(0.001, 0.001)
    a = run_virtual_umbmark(SystematicErrors(), DiffDrive(B), L, 3, noise, rng=7)
    b = run_virtual_umbmark(SystematicErrors(), DiffDrive(B), L, 3, noise,
                            rng=np.random.default_rng(7))
    np.testing.assert_array_equal(a.errors_cw, b.errors_cw)
    assert not np.allclose(a.errors_cw[0], a.errors_cw[1])


@pytest.mark.slow
def test_noise_spread_does_not_depend_on_step() -> None:
    """Chong–Kleeman's k²|d| model is consistent: the spread of the return errors is the
    same for 1 cm and 8 cm steps. With N = 1500 runs the sample variance of one coordinate
    has relative std √(2/N) = 3.7 %; the ratio of two has ≈ 5.2 %; 4σ tolerance = 21 %."""
    noise = WheelNoise(0.001, 0.0015)
    n = 1500
    fine = run_virtual_umbmark(SystematicErrors(), DiffDrive(B), L, n, noise, rng=1, step=0.01)
    coarse = run_virtual_umbmark(SystematicErrors(), DiffDrive(B), L, n, noise, rng=2, step=0.08)
    for e1, e2 in [(fine.errors_cw, coarse.errors_cw), (fine.errors_ccw, coarse.errors_ccw)]:
        ratio = e1.var(axis=0, ddof=1) / e2.var(axis=0, ddof=1)
        np.testing.assert_allclose(ratio, 1.0, atol=0.21)


@pytest.mark.slow
def test_residual_after_noisy_calibration_matches_noise_level() -> None:
    """After one compensation from n = 5 noisy runs per direction, the c.g.s deviate from
    the noise-free compensated ones by −P·e₁ + e₂ (first order): e₁, e₂ the c.g. noise of
    the calibration and the check runs, P = M·A the projection of the four c.g.
    coordinates onto the (α, β) model (M from eq. 4.17-4.18 and their y analogues, A the
    averaged estimators 4.20/4.24). So Cov = P·C·Pᵀ + C with C = blockdiag(Σ_cw, Σ_ccw)/n.
    We compare the mean squared deviation of each cluster over R = 150 replicated
    calibrations with that prediction; the tolerance is 4 standard errors of the mean
    (measured from the replicates) plus 10 % for the linearisation and for Σ estimated
    from 1000 runs."""
    err = SystematicErrors(E_d=1.002, E_b=1.01)
    robot = DiffDrive(B)
    noise = WheelNoise(0.0005, 0.0005)
    n, replicates, step = 5, 150, 0.02
    rng = np.random.default_rng(12345)

    many = run_virtual_umbmark(err, robot, L, 1000, noise, rng, step=step)
    C = np.zeros((4, 4))
    C[:2, :2] = np.cov(many.errors_cw.T) / n
    C[2:, 2:] = np.cov(many.errors_ccw.T) / n
    M = np.array([[-2 * L, -2 * L], [-2 * L, -2 * L], [-2 * L, 2 * L], [2 * L, -2 * L]])
    A = np.array([[1, 1, 1, -1], [1, 1, -1, 1]]) / (-8 * L)
    P = M @ A
    cov_pred = P @ C @ P.T + C
    pred = [np.trace(cov_pred[:2, :2]), np.trace(cov_pred[2:, 2:])]

    nf = iterate_umbmark(err, robot, L, 1, iterations=1, step=step).results[1]
    sq = np.zeros((replicates, 2))
    advised_after = 0
    for i in range(replicates):
        it = iterate_umbmark(err, robot, L, n, iterations=1, noise=noise, rng=rng, step=step)
        after = it.results[1]
        sq[i, 0] = np.sum((np.array(after.cg_cw) - nf.cg_cw) ** 2)
        sq[i, 1] = np.sum((np.array(after.cg_ccw) - nf.cg_ccw) ** 2)
        advised_after += bool(after.second_compensation_advised)
        assert it.e_max_syst[1] < it.e_max_syst[0] / 5
    mean, se = sq.mean(axis=0), sq.std(axis=0, ddof=1) / math.sqrt(replicates)
    for k in range(2):
        assert abs(mean[k] - pred[k]) < 4 * se[k] + 0.10 * pred[k], (mean, se, pred)
    # The residual is at the noise level, so the 3·SEM rule should rarely ask for more.
    assert advised_after < 0.25 * replicates


def test_true_robot_and_validation() -> None:
    t = true_robot(SystematicErrors(E_d=1.01, E_b=1.02, E_s=0.99), DiffDrive(0.5, 0.002, 0.003))
    assert t.wheel_base == pytest.approx(0.51)
    assert t.m_per_tick_right / 0.003 / (t.m_per_tick_left / 0.002) == pytest.approx(1.01)
    assert (t.m_per_tick_right / 0.003 + t.m_per_tick_left / 0.002) / 2 == pytest.approx(0.99)
    with pytest.raises(ModelError):
        SystematicErrors(E_d=0.0)
    with pytest.raises(ModelError):
        run_virtual_umbmark(SystematicErrors(), DiffDrive(B), -1.0, 1)
    with pytest.raises(ModelError):
        run_virtual_umbmark(SystematicErrors(), DiffDrive(B), L, 0)
    with pytest.raises(ModelError):
        square_wheel_steps(DiffDrive(B), L, "left")


def test_x_y_disagreement_is_second_order_without_noise() -> None:
    # The x and y estimators (4.20a/b, 4.24a/b) differ only through the neglected
    # second-order terms: doubling both errors quadruples their disagreement.
    dis = []
    for scale in (1.0, 2.0):
        err = SystematicErrors(1 + 0.0005 * scale, 1 + 0.0025 * scale)
        runs = run_virtual_umbmark(err, DiffDrive(B), L, 1)
        r = umbmark(runs.errors_cw, runs.errors_ccw, L, B)
        dis.append((r.alpha_disagreement, r.beta_disagreement))
    assert dis[1][0] / dis[0][0] == pytest.approx(4, rel=0.1)
    assert dis[1][1] / dis[0][1] == pytest.approx(4, rel=0.1)


def test_logs_reproduce_the_runs() -> None:
    err, robot = SystematicErrors(1.003, 0.99), DiffDrive(B, 0.001, 0.001, 1.001, 0.999, 1.002)
    noise = WheelNoise(0.001, 0.001)
    runs = run_virtual_umbmark(err, robot, L, 2, noise, rng=5, step=0.05)
    logs = virtual_umbmark_logs(err, robot, L, 2, noise, rng=5, step=0.05)
    assert [log.meta["direction"] for log in logs] == ["cw", "cw", "ccw", "ccw"]
    true_end = np.vstack([runs.true_end_cw, runs.true_end_ccw])
    for log, end in zip(logs, true_end, strict=True):
        np.testing.assert_allclose(log.ground_truth[-1], end, atol=1e-12)
        np.testing.assert_array_equal(log.ground_truth[0], [0, 0, 0])
        # The believed robot's odometry of the logged ticks closes the square.
        dl = robot.scale_left * log.channels["ticks_left"][1:]
        dr = robot.scale_right * log.channels["ticks_right"][1:]
        odo = dead_reckon((dl + dr) / 2, (dr - dl) / robot.effective_wheel_base)[-1]
        sign = 1.0 if log.meta["direction"] == "ccw" else -1.0
        np.testing.assert_allclose(odo, [0, 0, sign * 2 * math.pi], atol=1e-12)
        assert np.all(np.diff(log.t) > 0)


def test_logs_agree_with_return_errors_from_runs() -> None:
    """Integration with the log-based UMBmark (odomkit.calibrate.realdata)."""
    realdata = pytest.importorskip("odomkit.calibrate.realdata")
    err, robot = SystematicErrors(1.002, 1.01), DiffDrive(B, 0.001, 0.001)
    runs = run_virtual_umbmark(err, robot, L, 2, WheelNoise(0.001, 0.001), rng=3)
    logs = virtual_umbmark_logs(err, robot, L, 2, WheelNoise(0.001, 0.001), rng=3)
    cw, ccw = realdata.return_errors_from_runs(logs, robot)
    np.testing.assert_allclose(cw, runs.errors_cw, atol=1e-9)
    np.testing.assert_allclose(ccw, runs.errors_ccw, atol=1e-9)
