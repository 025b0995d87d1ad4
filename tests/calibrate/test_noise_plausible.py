"""fit-noise says when a fitted noise parameter is physically implausible (BMW user study,
finding 2: sigma_dt 0.498 s on a log sampled every 0.086 s, a 42 % run-to-run speed scale,
a truth stamped 7.7 s off; written as they were, and scored ~50x too big by evaluate).

Each fit here is made implausible by construction, the way real logs make it so: a robot
that was not calibrated (its speed scale, steering offset or gyro offset wrong on every
run), or a truth whose fixes really are stamped seconds off. The facts the warning states
(the sample period, the shortest window, the limit) are checked against the simulation's
own numbers; an honest simulated fit of the same kind gets no such warning.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from odomkit.calibrate.fit_noise import fit_noise
from odomkit.integrate import dead_reckon
from odomkit.kinematics import diff_body_steps
from odomkit.log import OdometryLog
from odomkit.noise import GyroNoise, ParameterUncertainty, SpeedNoise, TricycleNoise, WheelNoise
from odomkit.robot import Car, DiffDrive, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth
from odomkit.window_errors import window_covariance_basis
from odomkit.windows import Window, WindowSpec, split_windows

CAR = Car(2.7)
DIFF = DiffDrive(0.3)


def implausible(fit):
    return [w for w in fit.warnings if " is implausible" in w]


def car_bases(seed, *, scale_error=0.0, steering_offset=0.0, models=None, n_logs=4, n=3000, period=0.1,
              window=10.0):
    """A car at 5-25 m/s sampled every ``period`` s, its true speed 1 % noisy and its true
    steering 2 mrad noisy; the log's speed reads ``scale_error`` short and its steering
    ``steering_offset`` off on every run (a robot not calibrated). Exact truth with heading.
    ``models`` None: white speed, steering and period noise."""
    models = (TricycleNoise(0, 0, 0),) if models is None else models
    rng = np.random.default_rng(seed)
    bases = []
    for _ in range(n_logs):
        t = np.arange(n) * period
        phase = rng.uniform(0, 6, 2)
        speed = 15 + 10 * np.sin(t / 20 + phase[0])
        steer = 0.05 * np.sin(t / 7 + phase[1])
        log = OdometryLog(t, {"speed": speed, "steer": steer - steering_offset})
        true = OdometryLog(t, {"speed": speed * (1 + scale_error) * (1 + rng.normal(0, 0.01, n)),
                               "steer": steer + rng.normal(0, 0.002, n)})
        poses = dead_reckon_log(true, CAR).poses
        windows, _ = split_windows(t, t, WindowSpec(window, "s"))
        bases.append(window_covariance_basis(log, CAR, models, poses, np.ones(n, bool), windows))
    return bases


def diff_bases(seed, *, scale_error=0.0, n_logs=6, n=1200, k=0.002):
    """A differential drive sampled every 0.05 s, white wheel noise k²|d|, per run a draw of
    its wheel base (3 mm) and wheel scales (0.4 %), and both wheels ``scale_error`` too
    small on every run (wheel diameters never calibrated)."""
    rng = np.random.default_rng(seed)
    models = (WheelNoise(k, k), ParameterUncertainty())
    bases = []
    for _ in range(n_logs):
        t = np.arange(n) * 0.05
        phase = rng.uniform(0, 6, 2)
        left = 0.01 + 0.008 * np.sin(t / 2 + phase[0])
        right = 0.01 + 0.008 * np.sin(t / 3 + phase[1])
        eps = rng.normal(0, [0.003, 0.004, 0.004])
        true_l = left * (1 + eps[1] + scale_error) + rng.standard_normal(n) * k * np.sqrt(left)
        true_r = right * (1 + eps[2] + scale_error) + rng.standard_normal(n) * k * np.sqrt(right)
        poses = dead_reckon(*diff_body_steps(true_l[1:], true_r[1:], DIFF.wheel_base + eps[0]))
        windows, _ = split_windows(t, t, WindowSpec(10.0, "s"))
        bases.append(window_covariance_basis(OdometryLog(t, {"dist_left": left, "dist_right": right}), DIFF,
                                             models, poses, np.ones(n, bool), windows))
    return bases, models


def truth_clock_bases(seed, time_sigma, *, n_logs=6, n=1200, window=8.0):
    """A differential drive with white wheel noise whose truth's fixes are each taken at
    t + δ, δ ~ N(0, ``time_sigma``²) (the true track simulated 10 s beyond both ends of the
    log, so that a late or early fix stays on it); each window starts one row after the
    previous one ends, so that no two share a fix. Returns the bases, the models and every
    window's duration [s]."""
    rng = np.random.default_rng(seed)
    models = (WheelNoise(0, 0),)
    pad = 200
    bases, durations = [], []
    for _ in range(n_logs):
        t_all = np.arange(-pad, n + pad) * 0.05
        phase = rng.uniform(0, 6, 2)
        left = 0.01 + 0.008 * np.sin(t_all / 2 + phase[0])
        right = 0.01 + 0.008 * np.sin(t_all / 3 + phase[1])
        true_l = left + rng.standard_normal(t_all.size) * 0.001 * np.sqrt(left)
        true_r = right + rng.standard_normal(t_all.size) * 0.0015 * np.sqrt(right)
        track = dead_reckon(*diff_body_steps(true_l[1:], true_r[1:], DIFF.wheel_base))
        t = t_all[pad:pad + n]
        when = t + rng.normal(0.0, time_sigma, n)
        gt = np.column_stack([np.interp(when, t_all, track[:, 0]), np.interp(when, t_all, track[:, 1]),
                              track[pad:pad + n, 2]])
        log = OdometryLog(t, {"dist_left": left[pad:pad + n], "dist_right": right[pad:pad + n]})
        cut, _ = split_windows(t, t, WindowSpec(window, "s"))
        starts = [w.start + (w.start > 0) for w in cut]
        windows = [Window(a, w.end, float(t[w.end] - t[a]), w.travel)
                   for a, w in zip(starts, cut, strict=True)]
        durations += [w.duration for w in windows]
        bases.append(window_covariance_basis(log, DIFF, models, gt, np.ones(n, bool), windows,
                                             truth=Truth(t, gt[:, :2], gt[:, 2]), truth_columns=True))
    return bases, models, np.array(durations)


def unicycle_bases(seed, yaw_rate_offset, *, n_logs=6, n=1200):
    """A unicycle (speed and yaw rate) at 0.3-0.7 m/s whose gyro reads ``yaw_rate_offset``
    rad/s low on every run (its offset never estimated), 1 cm/s and 0.01 rad/s white noise."""
    rng = np.random.default_rng(seed)
    robot = Unicycle()
    models = (SpeedNoise(1e-4), GyroNoise(1e-5), ParameterUncertainty())
    bases = []
    for _ in range(n_logs):
        t = np.arange(n) * 0.05
        phase = rng.uniform(0, 6, 2)
        speed = 0.5 + 0.2 * np.sin(t / 5 + phase[0])
        yaw_rate = 0.3 * np.sin(t / 4 + phase[1])
        true = OdometryLog(t, {"speed": speed + rng.normal(0, 0.01, n),
                               "yaw_rate": yaw_rate + yaw_rate_offset + rng.normal(0, 0.01, n)})
        windows, _ = split_windows(t, t, WindowSpec(5.0, "s"))
        bases.append(window_covariance_basis(OdometryLog(t, {"speed": speed, "yaw_rate": yaw_rate}), robot,
                                             models, dead_reckon_log(true, robot).poses, np.ones(n, bool),
                                             windows))
    return bases, models, robot


def test_a_period_jitter_over_half_the_sample_period_is_implausible():
    """The car's speed 20 % short on every run, its white noise fitted with the sample
    period's jitter free: sigma_dt takes the error the model lacks (at a given speed a
    period error moves the car as a speed error does), over half the 0.1 s period."""
    fit = fit_noise(car_bases(1, scale_error=0.2), (TricycleNoise(0, 0, 0),), CAR)
    jitter = fit.parameters["sigma_dt"]
    assert jitter > 0.05  # the construction does what it says
    (said,) = [w for w in implausible(fit) if w.startswith("sigma_dt")]
    assert said.startswith(f"sigma_dt = {jitter:.3g} s is implausible")
    assert "(limit 0.05 s: half the logs' mean sample period, 0.1 s)" in said
    assert "--fix sigma_dt" in said and "calibrate" in said


def test_an_honest_period_jitter_is_not_warned_about():
    """The same car calibrated (no scale error): its 1 % white speed noise is a period
    jitter of 1 % of the period (v·σ_T/T = 0.01 v), far inside the limit."""
    fit = fit_noise(car_bases(1), (TricycleNoise(0, 0, 0),), CAR)
    assert 0 < fit.parameters["sigma_dt"] < 0.005
    assert implausible(fit) == []


def test_a_run_to_run_scale_over_10_percent_is_implausible():
    """Wheels 30 % too small on every run, fitted as a bias: the scale's σ comes out above
    10 % (and the wheel base's above 10 % of 0.3 m); an honest robot's stay inside."""
    bases, models = diff_bases(0, scale_error=0.3)
    fit = fit_noise(bases, models, DIFF, kinds=("bias",))
    said = implausible(fit)
    for key in ("sigma_scale_left", "sigma_scale_right"):
        value = fit.parameters[key]
        assert value > 0.1
        (one,) = [w for w in said if w.startswith(f"{key} = ")]
        assert one.startswith(f"{key} = {value:.3g} ({100 * value:.3g} % from run to run) is implausible")
        assert "(limit 10 %)" in one and "calibrate" in one and "--kinds white" in one
    base = fit.parameters["sigma_wheel_base"]
    assert base > 0.03
    (one,) = [w for w in said if w.startswith("sigma_wheel_base")]
    assert one.startswith(f"sigma_wheel_base = {base:.3g} m is implausible (limit 0.03 m: 10 % of the "
                          "robot's wheel base, 0.3 m)")

    honest, models = diff_bases(0)
    assert implausible(fit_noise(honest, models, DIFF, kinds=("bias",))) == []


def test_a_truth_stamped_seconds_off_is_implausible():
    """Fixes 2 s off the log's clock (σ) against 8 s windows: the fit finds the truth's
    time noise, beyond a tenth of the shortest window."""
    bases, models, durations = truth_clock_bases(3, 2.0)
    fit = fit_noise(bases, models, DIFF)
    value, shortest = fit.parameters["truth_time_sigma"], float(durations.min())
    assert value > shortest / 10
    (said,) = implausible(fit)
    assert said.startswith(f"truth_time_sigma = {value:.3g} s is implausible")
    assert f"(limit {shortest / 10:.3g} s: a tenth of the shortest window, {shortest:.3g} s)" in said
    assert "--truth-time-sigma" in said and "calibrate" in said


def test_an_honest_truth_clock_is_not_warned_about():
    bases, models, durations = truth_clock_bases(3, 0.03)
    fit = fit_noise(bases, models, DIFF)
    assert 0 < fit.parameters["truth_time_sigma"] < 0.1
    assert implausible(fit) == []


def test_a_steering_offset_over_a_tenth_of_a_radian_is_implausible():
    """A steering sensor whose zero is 0.15 rad off on every run, fitted as a bias: the
    steering offset's σ beyond 0.1 rad (and the wheel base's and scale's beyond 10 %)."""
    models = (TricycleNoise(0.15, 0.002, 0.0), ParameterUncertainty())
    bases = car_bases(1, steering_offset=0.15, models=models, n_logs=6, n=1500, window=2.0)
    fit = fit_noise(bases, models, CAR, kinds=("bias",))
    value = fit.parameters["sigma_steering_offset"]
    assert value > 0.1
    said = {w.split(" = ")[0]: w for w in implausible(fit)}
    assert said["sigma_steering_offset"].startswith(f"sigma_steering_offset = {value:.3g} rad is implausible")
    # Driving straight with a steering 0.1 rad off: a circle of L / tan(0.1) = 26.9 m.
    assert "(limit 0.1 rad)" in said["sigma_steering_offset"] and "26.9 m" in said["sigma_steering_offset"]
    assert "(limit 0.27 m: 10 % of the robot's wheel base, 2.7 m)" in said["sigma_wheel_base"]
    assert "sigma_scale_left" in said
    honest = car_bases(1, models=models, n_logs=6, n=1500, window=2.0)
    assert implausible(fit_noise(honest, models, CAR, kinds=("bias",))) == []


def test_a_gyro_offset_over_a_tenth_of_a_radian_a_second_is_implausible():
    bases, models, robot = unicycle_bases(1, 0.2)
    fit = fit_noise(bases, models, robot, kinds=("bias",))
    value = fit.parameters["sigma_yaw_rate_offset"]
    assert value > 0.1
    (said,) = [w for w in implausible(fit) if w.startswith("sigma_yaw_rate_offset")]
    assert said.startswith(f"sigma_yaw_rate_offset = {value:.3g} rad/s is implausible")
    assert "(limit 0.1 rad/s)" in said
    honest, models, robot = unicycle_bases(1, 0.0)
    assert implausible(fit_noise(honest, models, robot, kinds=("bias",))) == []


@pytest.mark.parametrize("name", ["sigma_dt", "sigma_scale_left"])
def test_a_value_held_at_the_robot_files_is_not_judged(name):
    """Only fitted values are judged: one the user holds (--fix) is theirs, whatever it is."""
    models = (TricycleNoise(0.1, 0.002, 0.3), ParameterUncertainty(sigma_scale_left=0.5))
    bases = car_bases(1, models=models, n_logs=3, n=1000)
    fit = fit_noise(bases, models, CAR, kinds=("white", "bias"), fixed={name})
    assert not any(re.match(rf"{name} = ", w) for w in implausible(fit))
