"""Exact calibration of body-velocity (Unicycle) and gyro (GyroOdometry) robots
(:class:`~odomkit.calibrate.residuals.UnicycleCalibrationModel`,
:class:`~odomkit.calibrate.residuals.GyroCalibrationModel`): the parameter Jacobians
against finite differences and the steps against the library's own kinematics; noise-free
logs give back the true parameters from the truth at every row and from position fixes on
their own clock; with noisy inputs and truth the reported standard errors cover the truth."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.calibrate.exact import calibrate_exact
from odomkit.calibrate.positions import calibrate_positions
from odomkit.calibrate.residuals import (
    CALIBRATED_ROBOTS,
    GyroCalibrationModel,
    UnicycleCalibrationModel,
    calibration_model,
)
from odomkit.errors import ModelError
from odomkit.kinematics import body_steps
from odomkit.log import OdometryLog
from odomkit.robot import CompassOdometry, GyroOdometry, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth

TRUE_UNICYCLE = Unicycle(c_scale=1.03, yaw_rate_bias=0.01, yaw_rate_scale=0.97)
M_PER_TICK = 1e-3
TRUE_GYRO = GyroOdometry(m_per_tick=1.02 * M_PER_TICK, gyro_bias=-0.015, gyro_scale=1.04)
NOMINAL_GYRO = GyroOdometry(m_per_tick=M_PER_TICK)


def channels(seed: int, travel: str, n: int = 2000, dt: float = 0.1
             ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Times and noise-free channels of smooth random driving: a speed of 0.7–1.3 m/s and
    yaw rates of up to ±0.5 rad/s both ways (which separates a yaw-rate bias from a scale);
    the travel as ``speed`` [m/s], ``dist`` [m] or ``ticks`` (of M_PER_TICK)."""
    rng = np.random.default_rng(seed)
    t = dt * np.arange(n) + 0.05 * rng.random(n).cumsum()  # uneven steps
    knots = rng.uniform(-0.5, 0.5, n // 40 + 2)
    yaw_rate = np.interp(t, np.linspace(t[0], t[-1], knots.size), knots)
    speed = 1.0 + 0.3 * np.sin(t / 7.0 + seed)
    ch = {"yaw_rate": yaw_rate}
    dist = np.r_[0.0, speed[:-1] * np.diff(t)]
    if travel == "speed":
        ch["speed"] = speed
    elif travel == "dist":
        ch["dist"] = dist
    else:
        ch["ticks"] = dist / M_PER_TICK
    return t, ch


def with_truth(t: np.ndarray, measured: dict[str, np.ndarray], true_robot: Unicycle | GyroOdometry,
               true_channels: dict[str, np.ndarray] | None = None, source: str = "run") -> OdometryLog:
    """A log of the ``measured`` channels whose ground truth is what ``true_robot`` makes of
    the noise-free ``true_channels`` (default: the measured ones)."""
    ideal = OdometryLog(t, true_channels or measured)
    gt = dead_reckon_log(ideal, true_robot, pose0=(4.0, -3.0, 0.6)).poses
    return OdometryLog(t, measured, gt, source)


def fixes(log: OdometryLog, rate: float = 5.0, offset: float = 0.037, sigma: float = 0.0,
          rng: np.random.Generator | None = None) -> Truth:
    """Position-only truth at ``rate`` Hz on its own clock (``offset`` s off the log's
    rows), linearly interpolated between the rows of the log's ground truth (as
    calibrate_positions interpolates the odometry), with N(0, sigma²) noise per axis."""
    gt = log.ground_truth
    assert gt is not None
    tau = np.arange(log.t[0] + offset, log.t[-1], 1.0 / rate)
    xy = np.column_stack([np.interp(tau, log.t, gt[:, 0]), np.interp(tau, log.t, gt[:, 1])])
    if sigma > 0:
        assert rng is not None
        xy = xy + rng.normal(0.0, sigma, xy.shape)
    return Truth(tau, xy, None, sigma, f"fixes-{log.source}")


CASES = [
    (Unicycle(1.01, -0.02, 0.95), "speed"),
    (Unicycle(0.98, 0.03, 1.02), "dist"),
    (GyroOdometry(1.1e-3, 0.02, 0.99), "ticks"),
    (GyroOdometry(1.1e-3, 0.02, 0.99), "speed"),
]


@pytest.mark.parametrize(("robot", "travel"), CASES)
def test_step_jacobian_matches_central_differences(robot, travel):
    t, ch = channels(3, travel, n=300)
    model = calibration_model(robot, [OdometryLog(t, ch)])
    p = model.p0 * np.array([1.01, 1.0, 0.99]) + np.array([0.0, 0.004, 0.0])
    _, _, ddd, ddt = model.steps(p, 0)
    for k in range(3):
        h = 1e-6 * max(1.0, abs(p[k])) if k == 1 else 1e-6 * p[k]
        plus, minus = p.copy(), p.copy()
        plus[k] += h
        minus[k] -= h
        dd_p, dt_p = model.steps(plus, 0)[:2]
        dd_m, dt_m = model.steps(minus, 0)[:2]
        fd_dd, fd_dt = (dd_p - dd_m) / (2 * h), (dt_p - dt_m) / (2 * h)
        np.testing.assert_allclose(ddd[:, k], fd_dd, rtol=1e-6, atol=1e-9 * np.abs(fd_dd).max(initial=1.0))
        np.testing.assert_allclose(ddt[:, k], fd_dt, rtol=1e-6, atol=1e-9 * np.abs(fd_dt).max(initial=1.0))
    if isinstance(robot, GyroOdometry) and travel != "ticks":
        assert np.all(ddd[:, 0] == 0) and model.unobservable.keys() == {"m_per_tick"}
    else:
        assert np.all(np.abs(ddd[:, 0]) > 0) and not model.unobservable


@pytest.mark.parametrize(("robot", "travel"), CASES)
def test_steps_are_the_library_kinematics_of_the_robot_they_make(robot, travel):
    t, ch = channels(4, travel, n=300)
    log = OdometryLog(t, ch)
    model = calibration_model(robot, [log])
    p = model.p0 * np.array([1.02, 1.0, 0.97]) + np.array([0.0, -0.01, 0.0])
    dd, dtheta = model.steps(p, 0)[:2]
    ref = body_steps(model.make_robot(p), log)
    np.testing.assert_allclose(dd, ref.dd, rtol=1e-14, atol=0.0)
    np.testing.assert_allclose(dtheta, ref.dtheta, rtol=1e-12, atol=1e-16)
    assert model.names == (("c_scale", "yaw_rate_bias", "yaw_rate_scale") if isinstance(robot, Unicycle)
                           else ("m_per_tick", "gyro_bias", "gyro_scale"))
    # index 0 and 2 are the positive scales (positions.py bounds them to half..twice)
    assert model.positive == (True, False, True)


def test_dispatch_and_the_supported_robots():
    t, ch = channels(5, "speed", n=50)
    log = OdometryLog(t, ch)
    assert isinstance(calibration_model(Unicycle(), [log]), UnicycleCalibrationModel)
    assert isinstance(calibration_model(NOMINAL_GYRO, [log]), GyroCalibrationModel)
    assert Unicycle in CALIBRATED_ROBOTS and GyroOdometry in CALIBRATED_ROBOTS
    assert not isinstance(CompassOdometry(), CALIBRATED_ROBOTS)
    with pytest.raises(ModelError, match="CompassOdometry"):
        calibration_model(CompassOdometry(), [log])  # type: ignore[arg-type]


def test_unicycle_trajectory_fit_recovers_the_truth_from_nominal():
    logs = [with_truth(*channels(s, travel), TRUE_UNICYCLE, source=f"run{s}")
            for s, travel in ((1, "speed"), (2, "dist"))]
    cal = calibrate_exact(logs, Unicycle(), "trajectory")
    assert cal.names == ("c_scale", "yaw_rate_bias", "yaw_rate_scale")
    np.testing.assert_allclose(cal.values, [1.03, 0.01, 0.97], rtol=0, atol=1e-6)
    assert cal.robot == Unicycle(*cal.values) and not cal.scale_fixed and not cal.notes


def test_gyro_trajectory_fit_with_ticks_recovers_all_three():
    logs = [with_truth(*channels(s, "ticks"), TRUE_GYRO, source=f"run{s}") for s in (1, 2)]
    cal = calibrate_exact(logs, NOMINAL_GYRO, "trajectory")
    truth = [TRUE_GYRO.m_per_tick, TRUE_GYRO.gyro_bias, TRUE_GYRO.gyro_scale]
    np.testing.assert_allclose(cal.values, truth, rtol=1e-6, atol=1e-6)
    assert not cal.scale_fixed and not cal.notes


@pytest.mark.parametrize("fix_scale", [None, True])
def test_gyro_without_ticks_holds_m_per_tick_and_says_so(fix_scale):
    """m_per_tick converts ticks only: with speed logs it changes nothing, so it is held
    (zero variance, a note) and the gyro's bias and scale are still recovered."""
    logs = [with_truth(*channels(s, "speed"), TRUE_GYRO, source=f"run{s}") for s in (1, 2)]
    cal = calibrate_exact(logs, NOMINAL_GYRO, "trajectory", fix_scale=fix_scale)
    assert cal.values[0] == M_PER_TICK and cal.std_errors[0] == 0.0 and cal.scale_fixed
    np.testing.assert_allclose(cal.values[1:], [TRUE_GYRO.gyro_bias, TRUE_GYRO.gyro_scale], rtol=0, atol=1e-6)
    assert any(note.startswith("m_per_tick held") and "ticks" in note for note in cal.notes)


@pytest.mark.parametrize(("nominal", "true_robot", "travel"), [
    (Unicycle(), TRUE_UNICYCLE, "speed"),
    (NOMINAL_GYRO, TRUE_GYRO, "ticks"),
    (NOMINAL_GYRO, TRUE_GYRO, "dist"),
])
def test_positions_fit_recovers_the_truth_from_5hz_fixes_off_the_rows(nominal, true_robot, travel):
    logs = [with_truth(*channels(s, travel), true_robot, source=f"run{s}") for s in (1, 2)]
    truths = [fixes(log) for log in logs]
    assert not np.any(np.isin(truths[0].t, logs[0].t))
    cal = calibrate_positions(logs, truths, nominal)
    truth = np.array([getattr(true_robot, name) for name in cal.names])
    if travel == "dist":  # m_per_tick does not act on dist: it stays, unmoved and unreported
        truth[0] = nominal.m_per_tick
        assert cal.std_errors[0] == 0.0
    np.testing.assert_allclose(cal.values, truth, rtol=1e-6, atol=1e-6)
    assert cal.source == "positions"


def noisy_run(seed: int, true_robot: Unicycle | GyroOdometry, travel: str, sigma: float
              ) -> tuple[OdometryLog, Truth]:
    """One run (2000 steps of about 0.125 s, about 250 m) whose channels carry white noise
    (speed 1e-3 m/s, ticks 0.1 % of a step, yaw rate 2e-5 rad/s per sample) and its 5 Hz
    truth with σ = ``sigma`` per axis.

    calibrate_positions' standard errors model the fixes' noise only; the input noise makes
    the odometry a random walk, correlated from fix to fix, which they leave out. It is kept
    small enough not to matter: along the track a walk of variance q per metre (here
    (1.25e-4 m)²/0.125 m ≈ 1.2e-7 m) moves the fitted speed scale by about √(1.2 q / L)
    ≈ 2.4e-5 (the least-squares slope through the origin of a Brownian path over length L),
    against σ/√(Σ s_i²) ≈ 0.3/√(1250·250²/3) ≈ 7e-5 from the fixes: about 10 % more variance;
    the heading wanders by 2e-5·0.125·√2000 ≈ 1e-4 rad, about 0.015 m sideways at the end,
    against 0.3 m per fix. (Ten times this input noise makes the z-scores' spread 1.2–1.8.)"""
    rng = np.random.default_rng(seed)
    t, ch = channels(seed, travel)
    measured = dict(ch)
    measured["yaw_rate"] = ch["yaw_rate"] + rng.normal(0.0, 2e-5, t.size)
    key = "speed" if travel == "speed" else "ticks"
    noise = (rng.normal(0.0, 1e-3, t.size) if key == "speed"
             else 1e-3 * ch[key] * rng.standard_normal(t.size))
    measured[key] = ch[key] + noise
    log = with_truth(t, measured, true_robot, ch, f"noisy{seed}")
    return log, fixes(log, sigma=sigma, rng=rng)


@pytest.mark.parametrize(("nominal", "true_robot", "travel"), [
    (Unicycle(), TRUE_UNICYCLE, "speed"),
    (NOMINAL_GYRO, TRUE_GYRO, "ticks"),
])
def test_positions_fit_standard_errors_cover_the_truth_under_noise(nominal, true_robot, travel):
    """Over 20 seeds each parameter lies within 2 reported standard errors of the truth in
    at least 17 (honest errors: P(|z| < 2) = 0.954, so fewer than 17 of 20 has probability
    about 1.4 %; standard errors too small by 2x give about 14 of 20), and the z-scores'
    spread is about 1 (0.6..1.5 for 20 samples)."""
    truth = np.array([getattr(true_robot, name) for name in calibration_model(nominal, []).names])
    z = []
    for seed in range(20):
        log, fix = noisy_run(200 + seed, true_robot, travel, sigma=0.3)
        cal = calibrate_positions([log], [fix], nominal)
        assert np.all(cal.std_errors > 0)
        z.append((cal.values - truth) / cal.std_errors)
    z_arr = np.array(z)
    within = np.sum(np.abs(z_arr) < 2, axis=0)
    assert np.all(within >= 17), (within, z_arr)
    spread = np.sqrt(np.mean(z_arr**2, axis=0))
    assert np.all((spread > 0.6) & (spread < 1.5)), spread


def _arcs(t: np.ndarray, speed: np.ndarray, yaw_rate: np.ndarray, robot: Unicycle,
          pose0=(4.0, -3.0, 0.6)) -> np.ndarray:
    """Poses (N, 3) of a base doing what its rows say, held from each row to the next, on
    exact arcs, written here apart from the library: speed·c_scale, and the yaw rate
    yaw_rate_scale·(ω − yaw_rate_bias) only where it moves (zero speed and yaw rate: it
    stands, and no bias turns it)."""
    poses = np.empty((len(t), 3))
    poses[0] = pose0
    for k in range(len(t) - 1):
        dt = t[k + 1] - t[k]
        moving = speed[k] != 0 or yaw_rate[k] != 0
        v = robot.c_scale * speed[k]
        w = robot.yaw_rate_scale * (yaw_rate[k] - robot.yaw_rate_bias) if moving else 0.0
        x, y, th = poses[k]
        if abs(w * dt) > 1e-9:
            x += v / w * (np.sin(th + w * dt) - np.sin(th))
            y -= v / w * (np.cos(th + w * dt) - np.cos(th))
        else:
            x += v * dt * np.cos(th + w * dt / 2)
            y += v * dt * np.sin(th + w * dt / 2)
        poses[k + 1] = (x, y, th + w * dt)
    return poses


def with_stops(seed: int, n: int = 2000) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """:func:`channels` ("speed") with the base told to stand (speed and yaw rate 0) for
    a third of its rows, in stretches of 5 s: cmd_vel robots such as MRCLAM's stand often."""
    t, ch = channels(seed, "speed", n=n)
    standing = (np.arange(n) // 50) % 3 == 1
    return t, {name: np.where(standing, 0.0, ch[name]) for name in ("speed", "yaw_rate")}


def test_a_standing_unicycle_is_not_turned_by_its_yaw_rate_bias():
    """A base told to stand stands: its yaw-rate bias acts only while it moves. The track
    of a log with stops equals exact arcs integrated here; a log standing for 200 s stays
    where it is; calibration from nominal values gets the true bias and scales back; and
    the calibration's Jacobian on such a log matches central differences."""
    t, ch = with_stops(6)
    log = OdometryLog(t, ch)
    track = dead_reckon_log(log, TRUE_UNICYCLE, pose0=(4.0, -3.0, 0.6))
    np.testing.assert_allclose(track.poses, _arcs(t, ch["speed"], ch["yaw_rate"], TRUE_UNICYCLE),
                               rtol=0, atol=1e-9)
    still = OdometryLog(np.arange(0.0, 200.0, 0.1), {"speed": np.zeros(2000), "yaw_rate": np.zeros(2000)})
    assert np.array_equal(dead_reckon_log(still, TRUE_UNICYCLE).poses[-1], np.zeros(3))

    truth = _arcs(t, ch["speed"], ch["yaw_rate"], TRUE_UNICYCLE)
    cal = calibrate_exact([OdometryLog(t, ch, truth, "stops")], Unicycle(), "trajectory")
    np.testing.assert_allclose(cal.values, [1.03, 0.01, 0.97], rtol=0, atol=1e-6)

    model = calibration_model(Unicycle(), [log])
    p = np.array([1.01, 0.004, 0.99])
    _, _, _, ddt = model.steps(p, 0)
    h = 1e-6
    plus, minus = p.copy(), p.copy()
    plus[1] += h
    minus[1] -= h
    fd = (model.steps(plus, 0)[1] - model.steps(minus, 0)[1]) / (2 * h)
    np.testing.assert_allclose(ddt[:, 1], fd, rtol=1e-6, atol=1e-12)
    assert np.all(ddt[(np.arange(len(t) - 1) // 50) % 3 == 1, 1] == 0)
