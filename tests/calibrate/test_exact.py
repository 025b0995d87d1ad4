"""Exact-model calibration against virtual robots with known systematic errors."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from odomkit.calibrate.exact import calibrate_exact, jackknife_runs
from odomkit.calibrate.residuals import (
    CarCalibrationModel,
    DiffCalibrationModel,
    TricycleCalibrationModel,
    integrate_with_sensitivity,
)
from odomkit.calibrate.umbmark import apply_corrections, umbmark
from odomkit.calibrate.virtual import (
    SystematicErrors,
    run_virtual_umbmark,
    square_wheel_steps,
    true_robot,
)
from odomkit.errors import InputError, ModelError, OdomkitError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import body_steps, diff_body_steps
from odomkit.log import OdometryLog
from odomkit.noise import WheelNoise
from odomkit.robot import Car, DiffDrive, Tricycle
from odomkit.track import dead_reckon_log

NOMINAL = DiffDrive(wheel_base=0.34, m_per_tick_left=1e-4, m_per_tick_right=1e-4)


def square_logs(errors: SystematicErrors, believed: DiffDrive, side: float, n: int,
                noise: WheelNoise | None = None, rng: np.random.Generator | None = None,
                step: float = 0.05, directions: tuple[str, ...] = ("cw", "ccw")) -> list[OdometryLog]:
    """Logs of a robot that drives the UMBmark square by its own (believed) odometry.

    Ticks come from the virtual robot's controller (odomkit.calibrate.virtual); the ground
    truth integrates what the true wheels (and the wheel noise) make of those ticks.
    """
    truth = true_robot(errors, believed)
    logs = []
    for direction in directions:
        bel_l, bel_r = square_wheel_steps(believed, side, direction, step)
        ticks_l, ticks_r = bel_l / believed.scale_left, bel_r / believed.scale_right
        for _ in range(n):
            true_l, true_r = ticks_l * truth.m_per_tick_left, ticks_r * truth.m_per_tick_right
            if noise is not None:
                assert rng is not None
                true_l = true_l + noise.k_left * np.sqrt(np.abs(true_l)) * rng.standard_normal(true_l.size)
                true_r = true_r + noise.k_right * np.sqrt(np.abs(true_r)) * rng.standard_normal(true_r.size)
            gt = dead_reckon(*diff_body_steps(true_l, true_r, truth.wheel_base))
            ch = {"ticks_left": np.r_[0.0, ticks_l], "ticks_right": np.r_[0.0, ticks_r]}
            logs.append(OdometryLog(0.05 * np.arange(gt.shape[0]), ch, gt, f"virtual-{direction}"))
    return logs


def e_max_virtual(errors: SystematicErrors, believed: DiffDrive, side: float) -> float:
    r = run_virtual_umbmark(errors, believed, side, 1)
    return float(max(np.hypot(*r.errors_cw[0]), np.hypot(*r.errors_ccw[0])))


def test_logs_agree_with_the_virtual_umbmark_engine():
    # Our log builder and odomkit.calibrate.virtual are two implementations of the same
    # experiment: their return errors must agree.
    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    logs = square_logs(errors, NOMINAL, 4.0, 1)
    virt = run_virtual_umbmark(errors, NOMINAL, 4.0, 1, step=0.05)
    for log, expected in zip(logs, (virt.errors_cw[0], virt.errors_ccw[0]), strict=True):
        err = log.ground_truth[-1, :2] - dead_reckon_log(log, NOMINAL).poses[-1, :2]
        np.testing.assert_allclose(err, expected, atol=1e-12)


def test_noise_free_square_recovers_Ed_Eb_exactly_and_beats_umbmark():
    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    cal = calibrate_exact(square_logs(errors, NOMINAL, 4.0, 2), NOMINAL, "endpoints")
    assert cal.scale_fixed  # closed square: the overall scale is unobservable
    assert cal.E_d == pytest.approx(1.002, rel=1e-6)
    assert cal.E_b == pytest.approx(1.01, rel=1e-6)
    assert cal.E_s == pytest.approx(1.0, rel=1e-12)  # held at the input mean
    e_exact = e_max_virtual(errors, cal.robot, 4.0)
    assert e_exact < 1e-4
    # UMBmark's small-angle model leaves a second-order error the exact fit does not.
    virt = run_virtual_umbmark(errors, NOMINAL, 4.0, 1)
    um = apply_corrections(NOMINAL, umbmark(virt.errors_cw, virt.errors_ccw, 4.0, 0.34))
    assert e_max_virtual(errors, um, 4.0) > 10 * e_exact


def test_endpoints_with_scale_error_put_it_into_the_wheel_base():
    # E_s scales both wheels; with the mean scale held at 1 the headings are matched by
    # b = E_b/E_s (turn angle ∝ E_s/E_b, Borenstein–Feng eq. 2.15). The true track is then
    # E_s times the odometry track, so the end residual cannot vanish: it is
    # (E_s − 1)·(odometry end), about 9 mm here, which biases E_d slightly. The exact fit
    # still does better than UMBmark on the same runs.
    errors = SystematicErrors(E_d=0.995, E_b=1.02, E_s=1.01)
    cal = calibrate_exact(square_logs(errors, NOMINAL, 4.0, 1), NOMINAL, "endpoints")
    assert cal.scale_fixed and any("unobservable" in n for n in cal.notes)
    assert cal.E_d == pytest.approx(0.995, rel=1e-4)
    assert cal.E_b == pytest.approx(1.02 / 1.01, rel=1e-4)
    virt = run_virtual_umbmark(errors, NOMINAL, 4.0, 1)
    um = apply_corrections(NOMINAL, umbmark(virt.errors_cw, virt.errors_ccw, 4.0, 0.34))
    assert e_max_virtual(errors, cal.robot, 4.0) < 0.5 * e_max_virtual(errors, um, 4.0)


def test_trajectory_fit_recovers_the_scale_error():
    errors = SystematicErrors(E_d=0.995, E_b=1.02, E_s=1.01)
    cal = calibrate_exact(square_logs(errors, NOMINAL, 4.0, 1), NOMINAL, "trajectory")
    assert not cal.scale_fixed
    assert cal.E_s == pytest.approx(1.01, rel=1e-7)
    assert cal.E_d == pytest.approx(0.995, rel=1e-7)
    assert cal.E_b == pytest.approx(1.02, rel=1e-7)
    truth = true_robot(errors, NOMINAL)
    assert cal.robot.scale_left == pytest.approx(truth.m_per_tick_left, rel=1e-7)
    assert cal.robot.effective_wheel_base == pytest.approx(truth.wheel_base, rel=1e-7)


@pytest.mark.slow
def test_standard_errors_cover_the_truth_at_the_nominal_rate():
    # 5 + 5 noisy runs, residuals whitened by the true noise model (GLS): the estimate is
    # truth + linear-Gaussian error, σ̂ is estimated from 30 − 2 = 28 dof, so
    # |est − truth| ≤ se holds with probability P(|t_28| ≤ 1) = 0.674 per parameter.
    # Over 100 seeded trials the hit count is Binomial(100, 0.674): sd = 0.047 in
    # fraction; we accept ±0.15 (3.2 sd), a false-alarm rate near 1e-3 per parameter.
    from scipy.stats import t as student

    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    noise = WheelNoise(0.002, 0.002)
    truth_right = 2 * 1.002 / 2.002
    rng = np.random.default_rng(20240611)
    trials, hits_b, hits_r = 100, 0, 0
    for _ in range(trials):
        logs = square_logs(errors, NOMINAL, 4.0, 5, noise, rng, step=0.2)
        cal = calibrate_exact(logs, NOMINAL, "endpoints", noise=noise)
        se = dict(zip(cal.names, cal.std_errors, strict=True))
        hits_b += abs(cal.robot.c_wheel_base - 1.01) <= se["c_wheel_base"]
        hits_r += abs(cal.robot.c_right - truth_right) <= se["c_right"]
    p = student.cdf(1, 28) - student.cdf(-1, 28)
    for hits in (hits_b, hits_r):
        assert abs(hits / trials - p) < 0.15, (hits, trials, p)


def test_tricycle_trajectory_recovers_scale_offset_and_length():
    nominal = Tricycle(wheel_to_axle=0.15, m_per_tick=1e-4)
    truth = Tricycle(wheel_to_axle=0.16, m_per_tick=1e-4, steering_offset=0.03, c_scale=1.02)
    t = np.arange(1201) * 0.05
    steer = 0.4 * np.sin(t / 6.0)  # measured angle, positive left
    ticks = np.r_[0.0, np.full(1200, 50.0)]
    ch = {"ticks": ticks, "steer": steer}
    gt = dead_reckon_log(OdometryLog(t, ch, None), truth).poses
    cal = calibrate_exact([OdometryLog(t, ch, gt)], nominal, "trajectory")
    np.testing.assert_allclose(cal.values, [1.02, 0.03, 0.16], rtol=1e-7)


def test_car_trajectory_recovers_scale_offset_and_wheel_base():
    nominal = Car(2.7, 0.8, "rear", m_per_tick=0.01)
    truth = Car(2.8, 0.8, "rear", m_per_tick=0.01, steering_offset=0.005, c_scale=1.03)
    t = np.arange(1201) * 0.05
    ch = {"ticks": np.r_[0.0, np.full(1200, 10.0)], "steer": 0.3 * np.sin(t / 6.0)}
    gt = dead_reckon_log(OdometryLog(t, ch, None), truth).poses
    cal = calibrate_exact([OdometryLog(t, ch, gt)], nominal, "trajectory")
    assert cal.names == ("c_scale", "steering_offset", "wheel_base")
    np.testing.assert_allclose(cal.values, [1.03, 0.005, 2.8], rtol=1e-7)


def test_a_steering_ratio_that_varies_with_the_angle_is_fitted_when_asked():
    """A car whose road wheel turns s + 40 s³ (a variable-ratio rack), driven through turns
    up to 0.13 rad of s: the trajectory fit with the cubic recovers it, the wheel base and
    the offset; without it the fit cannot (its residuals stay), as a real car's did."""
    nominal = Car(2.7, steering_ratio=15.0)
    truth = Car(2.7, steering_offset=0.0005, c_scale=0.98, steering_ratio=15.0, steering_cubic=40.0)
    t = np.arange(4001) * 0.05
    wheel = 15.0 * 0.13 * np.sin(t / 9.0) * np.abs(np.sin(t / 23.0))  # steering-wheel angle [rad]
    ch = {"speed": 6.0 + 2 * np.sin(t / 17.0), "steer": wheel}
    gt = dead_reckon_log(OdometryLog(t, ch, None), truth).poses
    cal = calibrate_exact([OdometryLog(t, ch, gt)], nominal, "trajectory", steering_cubic=True)
    assert cal.names == ("c_scale", "steering_offset", "wheel_base", "steering_cubic")
    np.testing.assert_allclose(cal.values, [0.98, 0.0005, 2.7, 40.0], rtol=1e-6, atol=1e-9)
    assert cal.robot.steering_cubic == pytest.approx(40.0, rel=1e-6)
    linear = calibrate_exact([OdometryLog(t, ch, gt)], nominal, "trajectory")
    assert linear.names == ("c_scale", "steering_offset", "wheel_base")
    assert abs(linear.values[2] - 2.7) > 0.05  # the wheel base absorbs what the cubic is


def test_car_with_a_steering_ratio_is_calibrated_in_road_wheel_radians():
    """A steering-wheel angle (ratio 15): the fitted offset is the road wheel's, as the
    robot file's ``steering_offset`` is, and the rest is recovered as with ratio 1."""
    nominal = Car(2.7, 0.8, "rear", m_per_tick=0.01, steering_ratio=15.0)
    truth = Car(2.8, 0.8, "rear", m_per_tick=0.01, steering_offset=0.005, c_scale=1.03, steering_ratio=15.0)
    t = np.arange(1201) * 0.05
    ch = {"ticks": np.r_[0.0, np.full(1200, 10.0)], "steer": 15.0 * 0.3 * np.sin(t / 6.0)}
    gt = dead_reckon_log(OdometryLog(t, ch, None), truth).poses
    cal = calibrate_exact([OdometryLog(t, ch, gt)], nominal, "trajectory")
    np.testing.assert_allclose(cal.values, [1.03, 0.005, 2.8], rtol=1e-7)
    assert cal.robot.steering_ratio == 15.0


@pytest.mark.parametrize("kind", ["diff", "tricycle", "car-rear", "car-front", "car-cubic"])
def test_sensitivities_match_finite_differences(kind):
    rng = np.random.default_rng(3)
    n = 300
    if kind == "diff":
        robot = DiffDrive(0.4, 1e-3, 1e-3, 0.99, 1.01, 1.02)
        ch = {"ticks_left": np.r_[0, rng.uniform(-5, 20, n)], "ticks_right": np.r_[0, rng.uniform(-5, 20, n)]}
    else:
        robot = (Tricycle(0.3, 1e-3, 0.05, 1.01) if kind == "tricycle"
                 else Car(2.7, 0.8, "rear", 1e-3, 0.05, 1.01, steering_ratio=2.0, steering_cubic=0.7)
                 if kind == "car-cubic"
                 else Car(2.7, 0.8 if kind == "car-rear" else -0.8, kind[4:], 1e-3, 0.05, 1.01))
        ch = {"ticks": np.r_[0, rng.uniform(0, 20, n)], "steer": rng.uniform(-0.6, 0.6, n + 1)}
    log = OdometryLog(np.arange(n + 1.0), ch, np.zeros((n + 1, 3)))
    models = {"diff": DiffCalibrationModel, "tricycle": TricycleCalibrationModel}
    model = (CarCalibrationModel(robot, [log], cubic=True) if kind == "car-cubic"  # type: ignore[arg-type]
             else models.get(kind, CarCalibrationModel)(robot, [log]))  # type: ignore[arg-type]
    pose0 = np.array([0.3, -0.2, 0.7])

    def poses(p):
        return integrate_with_sensitivity(*model.steps(p, 0), pose0)

    p0 = model.p0
    got, jac = poses(p0)
    # The re-integration is the library's dead reckoning with the same robot.
    np.testing.assert_allclose(got, dead_reckon_log(log, model.make_robot(p0), pose0=pose0).poses,
                               atol=1e-12)
    assert len(p0) == (4 if kind == "car-cubic" else 3)
    for j in range(len(p0)):
        h = 1e-6 * max(abs(p0[j]), 1e-2)
        up, dn = p0.copy(), p0.copy()
        up[j] += h
        dn[j] -= h
        fd = (poses(up)[0] - poses(dn)[0]) / (2 * h)
        np.testing.assert_allclose(jac[:, :, j], fd, rtol=1e-5, atol=1e-8)


def test_jackknife_standard_errors_are_finite_and_positive_with_noise():
    rng = np.random.default_rng(5)
    errors = SystematicErrors(E_d=1.002, E_b=1.01, E_s=0.99)
    logs = square_logs(errors, NOMINAL, 2.0, 2, WheelNoise(0.002, 0.002), rng, step=0.1)
    values, se = jackknife_runs(logs, NOMINAL, "trajectory", every=4)
    assert np.all(se > 0) and np.all(np.isfinite(se))
    # Truth within 5 jackknife standard errors (a loose sanity bound, not a coverage test).
    truth = true_robot(errors, NOMINAL)
    assert abs(values[2] * 0.34 - truth.wheel_base) < 5 * se[2] * 0.34


def test_bad_input_is_refused():
    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    cw_only = square_logs(errors, NOMINAL, 4.0, 2, directions=("cw",))
    with pytest.raises(InputError, match="same way"):
        calibrate_exact(cw_only, NOMINAL, "endpoints")
    # One run: its whole trajectory calibrates (user study: the message did not say how).
    with pytest.raises(InputError, match=r"at least two runs, got 1: one run calibrates from its whole "
                                         r"trajectory \(--from trajectory\)"):
        calibrate_exact(cw_only[:1], NOMINAL, "endpoints")
    fitted = calibrate_exact(cw_only[:1], NOMINAL, "trajectory").robot
    true_base = true_robot(errors, NOMINAL).effective_wheel_base
    assert fitted.effective_wheel_base == pytest.approx(true_base, rel=1e-6)
    with pytest.raises(OdomkitError, match="source"):
        calibrate_exact(cw_only, NOMINAL, "middle")  # type: ignore[arg-type]
    no_truth = replace(cw_only[0], ground_truth=None)
    with pytest.raises(InputError, match="ground truth"):
        calibrate_exact([no_truth, cw_only[1]], NOMINAL, "endpoints")
    with pytest.raises(OdomkitError, match="heading_weight"):
        calibrate_exact(square_logs(errors, NOMINAL, 4.0, 1), NOMINAL, heading_weight=-1.0)


def test_body_steps_of_the_model_match_the_library():
    # The calibration's own kinematics must be those of odomkit.kinematics for any robot.
    errors = SystematicErrors(E_d=1.01)
    log = square_logs(errors, NOMINAL, 1.0, 1)[0]
    robot = DiffDrive(0.34, 1e-4, 1.1e-4, 0.98, 1.03, 1.05)
    model = DiffCalibrationModel(robot, [log])
    dd, dth = model.steps(model.p0, 0)[:2]
    ref = body_steps(robot, log)
    np.testing.assert_allclose(dd, ref.dd, rtol=1e-13)
    np.testing.assert_allclose(dth, ref.dtheta, rtol=1e-13)


def test_with_heading_weight_zero_the_residual_variance_counts_only_positions():
    """With the heading left out (weight 0) every third residual is zero; the residual
    variance must be the positions' own: truth positions with white noise of σ = 1 cm per
    axis around an exactly known square give σ̂ = 1 cm within its sampling error
    (relative 1/√(2(n − p)) for n position residuals), not 1 cm·√(2/3) as when the zeros
    were counted."""
    errors = SystematicErrors(E_d=0.995, E_b=1.02, E_s=1.01)
    [log] = square_logs(errors, NOMINAL, 4.0, 1, directions=("cw",))
    rng = np.random.default_rng(5)
    gt = log.ground_truth.copy()
    gt[:, :2] += rng.normal(0.0, 0.01, gt[:, :2].shape)
    noisy = replace(log, ground_truth=gt)
    cal = calibrate_exact([noisy], NOMINAL, "trajectory", heading_weight=0.0)
    n = 2 * (cal.n_residuals // 3)
    assert np.sqrt(cal.residual_variance) == pytest.approx(0.01, rel=4 / np.sqrt(2 * (n - 3)))


def test_a_diverged_tricycle_fit_names_its_parameters_not_left_and_right_wheels():
    """A tricycle whose steering is read 3× too large and flipped runs its fit to a negative
    scale and wheel-to-axle distance. The message said "check the channel assignment
    (left/right)", which a tricycle has none of (user study); it names the parameters."""
    import math

    from odomkit.robot import Tricycle
    from odomkit.track import dead_reckon_log

    tricycle = Tricycle(wheel_to_axle=1.4)
    t = np.arange(0.0, 60.0, 0.05)
    steer = 0.4 * np.sin(2 * math.pi * t / 20.0)
    poses = dead_reckon_log(OdometryLog(t, {"speed": np.full(t.size, 0.5), "steer": steer}), tricycle).poses
    wrong = OdometryLog(t, {"speed": np.full(t.size, 0.5), "steer": -3.0 * steer}, ground_truth=poses)
    with pytest.raises(ModelError, match=r"diverged to non-positive parameters \{'c_scale': -") as raised:
        calibrate_exact([wrong], tricycle, "trajectory")
    assert "left" not in str(raised.value) and "odomkit check" in str(raised.value)
