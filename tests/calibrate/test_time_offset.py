"""The truth's clock offset δ fitted by :func:`odomkit.calibrate.positions.calibrate_positions`
(``fit_time_offset=True``): a fix stamped t is the pose at log time t − δ.

* noise-free recovery: a car log whose true path is odomkit's own kinematics (so the fit's
  model is exact), fixes at 5 Hz off the log's rows on a clock δ late (and early): δ and
  the car's speed scale, steering offset and wheel base come back to round-off;
* the δ column of the fit's Jacobian against finite differences of its residuals (they are
  piecewise linear in δ, so the differences are taken where no fix crosses a log row);
* without the flag nothing changes, and with δ = 0 the flag moves no parameter by more
  than a small part of its standard error;
* real data: the built-in OptiOdom runs against their own OptiTrack positions, once as
  recorded and once with the truth's stamps moved 0.3 s later: the two fitted offsets
  differ by the injected 0.3 s (whatever the recording's own offset is, it cancels).
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.calibrate.positions import MAX_TIME_OFFSET, _Problem, _runs_with_truth, calibrate_positions
from odomkit.calibrate.residuals import calibration_model
from odomkit.errors import InputError, ModelError
from odomkit.log import OdometryLog
from odomkit.robot import Car
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth

TRUE_CAR = Car(2.75, 0.0, "rear", steering_offset=0.01, c_scale=1.02)
NOMINAL_CAR = Car(2.7, 0.0, "rear")
TRUE_VALUES = np.array([TRUE_CAR.c_scale, TRUE_CAR.steering_offset, TRUE_CAR.wheel_base])
DT, FIX_PHASE, FIX_PERIOD = 0.1, 0.037, 0.2  # log rows every 0.1 s; fixes at 0.037 + 0.2 k s


def drive(seed: int, delta: float, n: int = 1500, sigma: float = 0.0, fix_period: float = FIX_PERIOD
          ) -> tuple[OdometryLog, Truth]:
    """A car log of ``n`` rows (every DT s) driving smooth random turns at a speed that
    varies (1.5–10.5 m/s: without accelerations δ would be one with the start position along
    the track), and 5 Hz position fixes of its true path (``TRUE_CAR`` through odomkit's
    own dead reckoning, linear between rows as the calibration interpolates) on a clock
    ``delta`` s late: the fix stamped s is the true position at log time s − delta, plus
    N(0, sigma²) per axis."""
    rng = np.random.default_rng(seed)
    t = DT * np.arange(n)
    knots = rng.uniform(-0.25, 0.25, n // 50 + 2)
    steer = np.interp(t, np.arange(knots.size) * 50 * DT, knots)
    speed = 6.0 + 3.0 * np.sin(t / 9.0) + 1.5 * np.sin(t / 3.1 + 1.0)
    log = OdometryLog(t, {"speed": speed, "steer": steer}, source=f"run{seed}")
    poses = dead_reckon_log(log, TRUE_CAR, pose0=(10.0, -5.0, 0.3)).poses
    stamps = np.arange(FIX_PHASE, t[-1], fix_period)
    xy = np.column_stack([np.interp(stamps - delta, t, poses[:, i]) for i in (0, 1)])
    if sigma > 0:
        xy = xy + rng.normal(0.0, sigma, xy.shape)
    return log, Truth(stamps, xy, None, sigma, f"fixes{seed}")


@pytest.mark.parametrize("delta", [0.25, -0.15])
def test_a_noise_free_clock_offset_and_the_car_come_back_exactly(delta):
    """The model is exact here (the fixes are the calibration's own interpolation of the
    true car's dead reckoning), so δ and the parameters come back to round-off; tolerances
    of 1e-6 s and 1e-6 relative leave a margin of ~1e9 over what it reaches (~1e-15)."""
    logs, truths = zip(*(drive(seed, delta) for seed in (1, 2)), strict=True)
    cal = calibrate_positions(logs, truths, NOMINAL_CAR, fit_time_offset=True)
    assert cal.names == ("c_scale", "steering_offset", "wheel_base")
    assert cal.time_offset == pytest.approx(delta, abs=1e-6)
    np.testing.assert_allclose(cal.values, TRUE_VALUES, rtol=1e-6)
    assert cal.time_offset_std_error is not None and cal.time_offset_std_error < 1e-6
    said = cal.to_dict()["truth_time_offset"]
    assert said == {"value": cal.time_offset, "std_error": cal.time_offset_std_error,
                    "std_error_between_runs": cal.time_offset_std_error_between_runs}  # the 2 runs' spread
    # Without δ the same data cannot be matched: the fit is off, the residual far from zero
    # (a check that the offset is large enough to matter here).
    blind = calibrate_positions(logs, truths, NOMINAL_CAR)
    assert np.sqrt(blind.residual_variance) > 0.1


def test_an_offset_beyond_the_fitted_range_is_refused_at_its_edge():
    """A truth 2.5 s late is outside ±MAX_TIME_OFFSET: the fit runs to the bound and says
    so (naming the clock offset) rather than returning the bound as an estimate."""
    assert MAX_TIME_OFFSET == 2.0
    log, truth = drive(1, 2.5, n=3000)
    with pytest.raises(ModelError, match=r"edge of the plausible range for .*truth time offset \(.*clock "
                       r"offset \+2 s reached, the range ±2 s\)"):
        calibrate_positions([log], [truth], NOMINAL_CAR, fit_time_offset=True)


def slalom(seed: int, delta: float, seconds: float = 3.3, fix_period: float = 0.01
           ) -> tuple[OdometryLog, Truth]:
    """A car accelerating through a slalom for ``seconds`` (rows every 0.02 s), and fixes of
    its true path (``TRUE_CAR``) every ``fix_period`` s on a clock ``delta`` s late."""
    t = 0.02 * np.arange(int(round(seconds / 0.02)) + 1)
    speed, steer = 2.0 + 1.5 * t + 0.3 * seed, 0.3 * np.sin(2 * np.pi * t / 1.6 + seed)
    log = OdometryLog(t, {"speed": speed, "steer": steer}, source=f"slalom{seed}")
    poses = dead_reckon_log(log, TRUE_CAR, pose0=(1.0, 2.0, 0.3)).poses
    stamps = np.arange(0.007, t[-1], fix_period)
    xy = np.column_stack([np.interp(stamps - delta, t, poses[:, i]) for i in (0, 1)])
    return log, Truth(stamps, xy, None, 0.0, f"slalom fixes{seed}")


def test_a_run_of_a_few_seconds_fits_its_clock_within_a_quarter_of_its_length():
    """A 3.3 s run (an F1TENTH car's slalom, a user study) kept no fix at 2 s from either
    end and was refused with "check the clocks" while its truth overlapped it. The clock is
    fitted within a quarter of the shortest run (clock_range), here ±0.825 s: δ and the car
    come back exactly (noise-free, the model exact), and an offset beyond that range is
    refused at its edge naming the range and --truth-time-offset."""
    from odomkit.calibrate.positions import clock_range

    logs, truths = zip(*(slalom(seed, 0.12) for seed in (1, 2, 3)), strict=True)
    assert clock_range(logs) == pytest.approx(0.25 * 3.3)
    cal = calibrate_positions(logs, truths, NOMINAL_CAR, fit_time_offset=True)
    assert cal.time_offset == pytest.approx(0.12, abs=1e-6)
    np.testing.assert_allclose(cal.values, TRUE_VALUES, rtol=1e-6)
    late = [slalom(seed, 1.0) for seed in (1, 2, 3)]
    with pytest.raises(ModelError, match=r"clock offset \+0\.825 s reached, the range ±0\.825 s "
                       r"\(0\.25 of the shortest run; give --truth-time-offset"):
        calibrate_positions([a for a, _ in late], [b for _, b in late], NOMINAL_CAR, fit_time_offset=True)
    # A 5 Hz truth over the same runs leaves too few fixes: said so, not "does not move".
    sparse = [slalom(seed, 0.12, fix_period=0.2) for seed in (1, 2, 3)]
    with pytest.raises(InputError, match=r"only \d+ truth fixes of the run are compared"):
        calibrate_positions([a for a, _ in sparse], [b for _, b in sparse], NOMINAL_CAR, fit_time_offset=True)


def _problem(log: OdometryLog, truth: Truth) -> _Problem:
    """The fit's internal problem over the whole run, every parameter free, δ fitted."""
    model = calibration_model(NOMINAL_CAR, [log])
    free = np.arange(len(model.names), dtype=np.intp)
    runs = _runs_with_truth([log], [truth], MAX_TIME_OFFSET)
    return _Problem(model, runs, [log], free, "exact", True)


def test_the_clock_offset_column_of_the_jacobian_is_the_derivative_of_the_residuals(numeric_jacobian):
    """q = (c_scale, steering_offset, wheel_base, δ, x₀, y₀, θ₀). At δ = 0.262 every fix
    falls 0.025 s from the nearest log row (stamps 0.037 + 0.2 k, rows every 0.1 s), so a
    central difference with a step of 1e-4 s stays inside each fix's log segment, where the
    residual is linear in δ: the difference is then exact up to round-off (~1e-16 · 1e2 m /
    1e-4 s ≈ 1e-10 m/s against columns of metres per second). The other columns are smooth
    and checked with a step of 1e-6 (truncation error O(step²))."""
    log, truth = drive(3, 0.2)
    problem = _problem(log, truth)
    delta = 0.262
    gap = np.abs(((truth.t - delta) / DT) - np.round((truth.t - delta) / DT)) * DT
    assert gap.min() > 0.02  # no fix near a row at δ, so ±1e-4 s stays in its segment
    q = np.array([1.01, 0.004, 2.72, delta, 10.3, -4.8, 0.31])
    res, jac = problem.residuals_and_jacobian(q)
    assert jac.shape == (res.size, q.size) and res.size == 2 * np.count_nonzero(problem.used(0))
    k = 3  # the δ column: after the free robot parameters

    def with_delta(d):
        x = q.copy()
        x[k] = d[0]
        return problem.residuals_and_jacobian(x)[0]

    fd = numeric_jacobian(with_delta, [delta], eps=1e-4)[:, 0]
    np.testing.assert_allclose(jac[:, k], fd, rtol=1e-7, atol=1e-9)
    # It is minus the odometry's velocity in the fix's segment: its length is the logged
    # speed there (held over the step) times c_scale = 1.01, less the arc's chord shortening
    # (turning at most 0.1 rad a step: under 5e-4 relative).
    kept = truth.t[(truth.t >= log.t[0] + MAX_TIME_OFFSET) & (truth.t <= log.t[-1] - MAX_TIME_OFFSET)]
    row = np.floor((kept - delta) / DT + 1e-9).astype(int)
    speed = np.hypot(jac[0::2, k], jac[1::2, k])
    np.testing.assert_allclose(speed, 1.01 * log.channels["speed"][row], rtol=1e-3)
    full = numeric_jacobian(lambda x: problem.residuals_and_jacobian(x)[0], q, eps=1e-6)
    others = [j for j in range(q.size) if j != k]
    for j in others:
        scale = np.abs(full[:, j]).max()
        np.testing.assert_allclose(jac[:, j], full[:, j], rtol=1e-5, atol=1e-6 * scale, err_msg=f"column {j}")


def test_without_the_flag_nothing_changes_and_a_zero_offset_moves_no_parameter():
    """GPS-like fixes (0.5 m) on the log's own clock (δ = 0): the fit without
    ``fit_time_offset`` reports no offset; with it, δ is within 3 standard errors of 0 and
    every parameter within half its standard error of the fit without (the data
    differ only by the 2 s left out at each end, 4 s of 300 s)."""
    logs, truths = zip(*(drive(seed, 0.0, n=3000, sigma=0.5) for seed in (4, 5)), strict=True)
    plain = calibrate_positions(logs, truths, NOMINAL_CAR)
    assert plain.time_offset is None and plain.time_offset_std_error is None
    assert "truth_time_offset" not in plain.to_dict()
    fitted = calibrate_positions(logs, truths, NOMINAL_CAR, fit_time_offset=True)
    assert fitted.time_offset is not None and fitted.time_offset_std_error is not None
    assert abs(fitted.time_offset) < 3 * fitted.time_offset_std_error
    assert fitted.time_offset_std_error < 0.01
    se = np.minimum(plain.std_errors, fitted.std_errors)
    assert np.all(np.abs(fitted.values - plain.values) < se / 2), (fitted.values - plain.values) / se
    # and both find the true car (its noise is the fixes' alone, so the intervals hold)
    assert np.all(np.abs(plain.values - TRUE_VALUES) < 4 * plain.std_errors)


def test_a_clock_offset_injected_into_real_motion_capture_is_found():
    """The built-in OptiOdom squares (a real differential drive, OptiTrack positions at the
    log's rows). The truth's stamps moved 0.3 s later make it 0.3 s later than it already
    is: the fitted offsets differ by 0.3 s, to 0.01 s (the fixes left out at the log's ends
    differ by the shift; nothing else does)."""
    from odomkit.data import builtin_data_path
    from odomkit.io.optiodom import read_run
    from odomkit.io.robotfile import read_robot

    robot, _ = read_robot(builtin_data_path("optiodom_diff.toml"))
    logs = [read_run(builtin_data_path(f"230620202042_run-0{i}.csv")) for i in (1, 4, 6)]

    def fit(shift):
        truths = []
        for log in logs:
            assert log.ground_truth is not None
            truths.append(Truth(log.t + shift, log.ground_truth[:, :2], None, 0.0, f"mocap+{shift}"))
        return calibrate_positions(logs, truths, robot, fit_time_offset=True)

    recorded, late = fit(0.0), fit(0.3)
    assert recorded.time_offset is not None and late.time_offset is not None
    assert late.time_offset - recorded.time_offset == pytest.approx(0.3, abs=0.01)
    # the same problem up to the shift: the wheel scales and base agree within their errors
    assert np.all(np.abs(late.values - recorded.values) < 2 * recorded.std_errors)


def _lagging_car(seed: int, lag: float, gps_late: float, seconds: float = 600.0):
    """A car that stops and goes (speed 0–10 m/s) through bends; its yaw follows the logged
    steering ``lag`` s late (a steering sensor ahead of the wheels' response), and its 5 Hz
    GPS (5 cm) runs ``gps_late`` s late: the log, the GPS, the nominal car."""
    from odomkit.log import OdometryLog
    from odomkit.robot import Car
    from odomkit.track import dead_reckon_log
    from odomkit.truth import Truth

    rng = np.random.default_rng(seed)
    dt = 0.05
    t = np.arange(0.0, seconds, dt)
    speed = np.clip(10.0 * np.sin(t / 15.0) ** 2 + rng.normal(0.0, 0.02, t.size), 0.0, None)
    knots = rng.uniform(-0.25, 0.25, int(t[-1] / 6.0) + 2)
    steer = np.interp(t, 6.0 * np.arange(knots.size), knots)
    car = Car(2.7, 0.0, "rear")
    moved = OdometryLog(t, {"speed": speed, "steer": np.interp(t - lag, t, steer)})
    poses = dead_reckon_log(moved, car, pose0=(0.0, 0.0, 0.3)).poses
    stamps = np.arange(1.013, t[-1] - 1.0, 0.2)
    xy = np.column_stack([np.interp(stamps - gps_late, t, poses[:, k]) for k in (0, 1)])
    gps = Truth(stamps, xy + rng.normal(0.0, 0.05, xy.shape), None, 0.05, "gps")
    return OdometryLog(t, {"speed": speed, "steer": steer}, source="drive"), gps, car


def test_a_lag_in_the_turning_taken_for_the_truths_clock_is_said():
    """A car whose yaw follows its logged steering 0.8 s late, against a GPS on the log's own
    clock: a fit of positions in 60 s windows takes the lag for a clock offset (+0.8 s), which every
    command then applies to the truth. The speeds, which the turning does not move, put
    the clock at 0 within their standard error, and the calibration says the two differ
    and what to try. A GPS really 0.3 s late, on a car without the lag: both agree, nothing
    said."""
    import warnings

    from odomkit.calibrate.check_ratios import speed_clock
    from odomkit.calibrate.positions import calibrate_positions

    log, gps, car = _lagging_car(4, lag=0.8, gps_late=0.0)
    offset, se = speed_clock([log], car, [gps])
    assert abs(offset) < 3 * se + 0.02 and se < 0.1
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = calibrate_positions([log], [gps], car, fit_time_offset=True, window="60s")
    assert abs(cal.time_offset) > 0.3  # the lag, taken for the clock (a later truth: +0.4 s here)
    said = [str(w.message) for w in caught if "is not the one the speeds give" in str(w.message)]
    assert len(said) == 1 and "a lag in the turning" in said[0], said
    assert abs(float(said[0].split("--truth-time-offset ")[1].split()[0])) < 0.05  # the speeds' clock

    log, gps, car = _lagging_car(5, lag=0.0, gps_late=0.3)
    offset, se = speed_clock([log], car, [gps])
    assert abs(offset - 0.3) < 3 * se + 0.02
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = calibrate_positions([log], [gps], car, fit_time_offset=True)
    assert cal.time_offset == pytest.approx(0.3, abs=0.05)
    assert not [w for w in caught if "speeds give" in str(w.message)]


def test_a_short_drives_clock_is_checked_against_its_speeds_too():
    """A 60 s drive has 28 stretches of 2 s: the speeds' clock needed 50 (the correlation's
    minimum), so a half drive's calibration (user study: 56 s, fitted −0.91 s against the
    speeds' 0.00 ± 0.02 s) wrote a lag in the turning as the truth's clock without a word.
    Its standard error comes from the misfit itself, so 15 stretches do: the lagging car
    is told, and a GPS really 0.3 s late is found so by both."""
    import warnings

    from odomkit.calibrate.check_ratios import speed_clock
    from odomkit.calibrate.positions import calibrate_positions

    log, gps, car = _lagging_car(4, lag=0.8, gps_late=0.0, seconds=60.0)
    offset, se = speed_clock([log], car, [gps])
    assert abs(offset) < 3 * se + 0.02 and se < 0.1
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = calibrate_positions([log], [gps], car, fit_time_offset=True)
    assert abs(cal.time_offset) > 0.3
    assert [w for w in caught if "is not the one the speeds give" in str(w.message)]
    log, gps, car = _lagging_car(5, lag=0.0, gps_late=0.3, seconds=60.0)
    offset, se = speed_clock([log], car, [gps])
    assert abs(offset - 0.3) < 3 * se + 0.02
