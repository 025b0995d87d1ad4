"""The data checks before calibrating (issue 12 item 7), on logs made to have each fault.

Each log is built from known wheel motion (and its truth dead-reckoned from the same
motion by the library's integrator), then spoilt in exactly one way; the check for that
fault must name it and the others must stay quiet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.calibrate.check import (
    check_counters,
    check_log,
    check_motion,
    check_stuck,
    check_time,
    check_values,
    next_steps,
)
from odomkit.calibrate.check_channels import check_channels
from odomkit.calibrate.check_identifiable import check_identifiable
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive, Tricycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth

ROBOT = DiffDrive(0.3, 1e-4, 1e-4)
PERIOD = 0.05


def square_both_ways() -> tuple[NDArrayPair, NDArrayPair]:
    """Wheel ticks per row of a 1 m square driven counter-clockwise, then clockwise."""
    straight = np.full(40, 250.0)  # 40 rows of 2.5 cm: 1 m
    turn = np.full(30, math.pi / 2 * 0.15 / 30 / 1e-4)  # a quarter spin in 30 rows
    left, right = [0.0], [0.0]
    for direction in (1, -1):
        for _ in range(4):
            left += list(straight)
            right += list(straight)
            left += list(-direction * turn)
            right += list(direction * turn)
    return np.array(left), np.array(right)


NDArrayPair = np.ndarray


def make_log(left, right, robot=ROBOT):
    t = PERIOD * np.arange(len(left))
    return OdometryLog(t, {"ticks_left": np.asarray(left, float), "ticks_right": np.asarray(right, float)})


def truth_of(log, robot=ROBOT, sigma=0.0):
    poses = dead_reckon_log(log, robot, pose0=np.zeros(3)).poses
    return Truth(log.t, poses[:, :2].copy(), poses[:, 2].copy(), sigma)


def statuses(findings, check):
    return [f.status for f in findings if f.check == check]


def test_a_clean_square_both_ways_passes_every_check():
    log = make_log(*square_both_ways())
    exact = truth_of(log)
    # A motion capture's 1 mrad of heading noise: a heading equal to the odometry's own, to
    # round-off, is no independent truth and is warned about (test_truth_heading_source.py).
    theta = exact.theta + np.random.default_rng(0).normal(0.0, 0.001, exact.theta.shape)
    found = check_log(log, ROBOT, Truth(exact.t, exact.xy, theta, exact.sigma))
    assert all(f.status == "ok" for f in found), [f for f in found if f.status != "ok"]
    assert next_steps(found) == []


def test_values_and_time():
    left, right = square_both_ways()
    log = make_log(left, right)
    t = log.t.copy()
    t[100:] += 2.0  # a 2 s dropout
    t[50] = t[49]  # a repeated stamp
    found = check_time(OdometryLog(t, log.channels))
    assert sorted(statuses(found, "time")) == ["warn", "warn"]
    assert any("2.05 s" in f.message for f in found)
    # OdometryLog refuses time going back and NaN when it is built; its arrays are the
    # caller's, though, and a log changed in place afterwards reaches the checks.
    back = OdometryLog(t.copy(), log.channels)
    back.t[60] = back.t[58]
    assert "fail" in statuses(check_time(back), "time")
    bad = OdometryLog(log.t, {name: values.copy() for name, values in log.channels.items()})
    bad.channels["ticks_left"][7] = np.nan
    found = check_values(bad)
    assert statuses(found, "values") == ["fail"] and "row(s) 8" in found[0].message


@pytest.mark.parametrize(("scale", "unit"), [(1e3, "ms"), (1e6, "us")])
def test_a_time_column_in_another_unit_is_named(scale, unit):
    """A 20 Hz log whose time is in ms (or µs) read as seconds has a period of 50 s (or
    50 000 s): the time finding warns and names the flag, where it said "steady period 50 s,
    ok"; the same log in seconds, and a 1 Hz one, pass."""
    left, right = square_both_ways()
    log = make_log(left, right)
    assert np.median(np.diff(log.t)) == pytest.approx(0.05)
    found = check_time(OdometryLog(log.t * scale, log.channels))
    assert statuses(found, "time") == ["warn"]
    assert f"--time-unit {unit}" in found[0].advice and "slower than any odometry logger" in found[0].message
    assert statuses(check_time(log), "time") == ["ok"]
    assert statuses(check_time(OdometryLog(log.t * 20, log.channels)), "time") == ["ok"]  # 1 s rows


def test_time_jumps_in_a_log_of_rates_are_said_but_not_warned_about():
    """A log of commanded speed and yaw rate written when a command changes (cmd_vel, the
    MRCLAM robots: 10 ms to 1 s between rows) loses nothing in its gaps, since each row's
    rates hold until the next; the same gaps in a tick log lose motion and are warned about.
    The track of the irregular rate log equals that of the same commands on a regular grid."""
    from odomkit.robot import Unicycle

    changes = np.array([0.0, 0.01, 0.02, 1.02, 1.03, 1.04, 2.5, 2.51, 2.52, 3.0])
    speed = np.array([0.1, 0.1, 0.2, 0.2, 0.2, 0.0, 0.3, 0.3, 0.3, 0.3])
    rate = np.array([0.0, 0.0, 0.5, 0.5, 0.5, 0.0, -0.2, -0.2, -0.2, -0.2])
    rates = OdometryLog(changes, {"speed": speed, "yaw_rate": rate})
    found = check_time(rates)
    assert statuses(found, "time") == ["ok"] and "held until the next" in found[0].message
    assert next_steps(found) == []
    ticks = OdometryLog(changes, {"ticks_left": np.ones(10), "ticks_right": np.ones(10)})
    assert statuses(check_time(ticks), "time") == ["warn"]
    grid = np.round(np.arange(0.0, 3.0 + 1e-9, 0.01), 2)
    held = np.searchsorted(changes, grid, side="right") - 1
    regular = OdometryLog(grid, {"speed": speed[held], "yaw_rate": rate[held]})
    robot = Unicycle()
    end, end_on_grid = dead_reckon_log(rates, robot).poses[-1], dead_reckon_log(regular, robot).poses[-1]
    np.testing.assert_allclose(end, end_on_grid, rtol=0, atol=1e-12)


def test_counter_wrap_names_the_counter_width():
    left, right = square_both_ways()
    wrapped = left.copy()
    wrapped[200] -= 2**16  # a differenced 16-bit counter that wrapped, read without --wrap-bits
    found = check_counters(make_log(wrapped, right))
    assert statuses(found, "counters") == ["fail"]
    assert "--wrap-bits 16" in found[0].advice and "ticks_left" in found[0].message
    spiked = left.copy()
    spiked[200] += 9000.0  # a glitch, not a power of two
    found = check_counters(make_log(spiked, right))
    assert statuses(found, "counters") == ["warn"] and "spike" in found[0].message


def test_stuck_wheel_told_from_a_pivot_by_the_truth():
    left, right = square_both_ways()
    log = make_log(left, right)
    truth = truth_of(log)
    stuck = left.copy()
    stuck[5:45] = 0.0  # the left encoder reads nothing for 2 s of straight driving
    bad = make_log(stuck, right)
    assert statuses(check_stuck(bad, ROBOT), "stuck") == ["warn"]  # without truth: stuck or pivot
    assert statuses(check_stuck(bad, ROBOT, truth), "stuck") == ["fail"]  # the truth drove straight
    # a real pivot: the left wheel stands, the right turns, and the truth turns with it
    pivot_left = np.concatenate((left[:41], np.zeros(40), left[41:]))
    pivot_right = np.concatenate((right[:41], np.full(40, 100.0), right[41:]))
    pivot = make_log(pivot_left, pivot_right)
    assert statuses(check_stuck(pivot, ROBOT, truth_of(pivot)), "stuck") == ["ok"]
    # every channel silent while the truth moves
    early = np.arange(len(left)) < 60
    silent = make_log(np.where(early, 0.0, left), np.where(early, 0.0, right))
    assert "fail" in statuses(check_stuck(silent, ROBOT, truth), "stuck")


@pytest.mark.parametrize(("spoil", "words"), [
    (lambda le, r: (r, le), "left and right swapped"),
    (lambda le, r: (-le, r), "the left channel's sign flipped"),
    (lambda le, r: (le, -r), "the right channel's sign flipped"),
    (lambda le, r: (-le, -r), "both channels' signs flipped"),
    (lambda le, r: (-r, le), "left and right swapped, with the left channel also negated"),
    (lambda le, r: (r, -le), "left and right swapped, with the right channel also negated"),
])
def test_channel_mapping_against_truth(spoil, words):
    left, right = square_both_ways()
    truth = truth_of(make_log(left, right))
    found = check_channels(make_log(*spoil(left, right)), ROBOT, truth)
    assert statuses(found, "channels") == ["fail"]
    assert f"with {words} the odometry" in found[0].message


def test_channel_mapping_from_a_spin():
    spin_left, spin_right = np.r_[0.0, np.full(100, -200.0)], np.r_[0.0, np.full(100, 200.0)]  # ccw
    assert statuses(check_channels(make_log(spin_left, spin_right), ROBOT, spin="ccw"), "channels") == ["ok"]
    found = check_channels(make_log(spin_right, spin_left), ROBOT, spin="ccw")
    assert statuses(found, "channels") == ["fail"] and "swapped" in found[0].message
    found = check_channels(make_log(-spin_left, spin_right), ROBOT, spin="ccw")
    assert "left wheel's sign" in found[0].message
    found = check_channels(make_log(spin_left, -spin_right), ROBOT, spin="cw")
    assert "left wheel's sign" in found[0].message  # cw: the left wheel must go forward
    # no truth, no spin: a flipped wheel makes a robot that mostly drives straight spin all the time
    left = np.r_[0.0, np.full(300, 250.0), np.full(30, -100.0)]
    right = np.r_[0.0, np.full(300, 250.0), np.full(30, 100.0)]
    found = check_channels(make_log(-left, right), ROBOT)
    assert statuses(found, "channels") == ["warn"] and "opposite" in found[0].message


def test_straight_only_log_cannot_identify_the_wheel_base():
    n = 400
    log = make_log(np.r_[0.0, np.full(n, 250.0)], np.r_[0.0, np.full(n, 250.0)])
    found = check_identifiable(log, ROBOT, sigma=0.005)
    by_name = {f.message.split(":")[0]: f for f in found}
    assert by_name["wheel base E_b"].status == "fail" and by_name["wheel base E_b"].value == math.inf
    # The scale moves only x, along the line, by x_k per unit scale; nothing else does, so
    # its standard error is σ/‖x‖ over the positions sampled once a second.
    x = 0.025 * np.arange(0, n + 1, 20)[1:]
    assert by_name["wheel scale E_s"].value == pytest.approx(0.005 / np.linalg.norm(x), rel=1e-9)
    assert statuses(check_motion(log, ROBOT), "turning") == ["warn"]


def test_one_way_circle_confounds_wheel_base_and_diameter_ratio():
    """A constant-curvature circle one way: a wheel-base error and a wheel-size ratio error
    bend it alike; driving it back the other way separates them."""
    one_way = make_log(np.r_[0.0, np.full(600, 200.0)], np.r_[0.0, np.full(600, 260.0)])
    both = make_log(np.r_[0.0, np.full(300, 200.0), np.full(300, 260.0)],
                    np.r_[0.0, np.full(300, 260.0), np.full(300, 200.0)])
    se_one = {f.message.split(":")[0]: f.value for f in check_identifiable(one_way, ROBOT)}
    se_both = {f.message.split(":")[0]: f.value for f in check_identifiable(both, ROBOT)}
    assert se_one["wheel base E_b"] > 5 * se_both["wheel base E_b"]
    assert statuses(check_motion(one_way, ROBOT), "turning") == ["warn"]
    assert statuses(check_motion(both, ROBOT), "turning") == ["ok"]


def test_tricycle_steering_sign_against_truth():
    robot = Tricycle(0.15, 1e-4)
    t = PERIOD * np.arange(400)
    log = OdometryLog(t, {"ticks": np.full(t.size, 200.0), "steer": 0.3 * np.sin(t / 3)})
    truth = truth_of(log, robot)
    flipped = OdometryLog(t, {"ticks": log.channels["ticks"], "steer": -log.channels["steer"]})
    assert statuses(check_channels(log, robot, truth), "channels") == ["ok"]
    found = check_channels(flipped, robot, truth)
    assert statuses(found, "channels") == ["fail"] and "steering sign flipped" in found[0].message


def test_a_log_that_cannot_tell_the_mappings_apart_is_a_warning():
    """Driving dead straight, a flipped steering sign changes nothing the truth sees: the
    mapping is not confirmed, so the finding is a warning (it was an "ok" with a note)."""
    robot = Tricycle(0.15, 1e-4)
    t = PERIOD * np.arange(400)
    log = OdometryLog(t, {"ticks": np.full(t.size, 200.0), "steer": np.zeros(t.size)})
    found = check_channels(log, robot, truth_of(log, robot))
    assert statuses(found, "channels") == ["warn"], found
    assert "the steering sign flipped" in found[0].message and "tell the mappings apart" in found[0].message


def test_no_check_passes_a_figure_that_is_not_a_number():
    """A NaN compares False with every limit, so a check that does not look for it passes
    it: the travel and turning ("the robot travels nan m") and the channels against truth
    did. Each must now say the figure is not a number, never "ok"."""
    left, right = square_both_ways()
    truth = truth_of(make_log(left, right))
    log = make_log(left.copy(), right)
    # changed in place after it was built (OdometryLog refuses a NaN given to it)
    log.channels["ticks_left"][100] = np.nan
    found = [*check_time(log), *check_counters(log), *check_stuck(log, ROBOT, truth),
             *check_channels(log, ROBOT, spin="ccw"), *check_motion(log, ROBOT),
             *check_identifiable(log, ROBOT)]
    for f in found:
        assert not (f.status == "ok" and "nan" in f.message.lower()), f
    assert statuses(found, "channels") == ["warn"]
    # Against truth the channel check builds the log anew with its channels remapped, which
    # refuses the NaN by name (check_log stops at check_values' failure before it).
    from odomkit.errors import InputError

    with pytest.raises(InputError, match=r"channel 'ticks_left' is nan at row 100"):
        check_channels(log, ROBOT, truth)
    assert statuses(found, "distance") == ["warn"] and statuses(found, "turning") == ["warn"]
    log = OdometryLog(log.t.copy(), make_log(left, right).channels)
    log.t[5] = np.nan
    found = check_time(log)
    assert statuses(found, "time") == ["fail"] and "row(s) 6" in found[0].message


def _unicycle_stand_then_drive(stand=40.0, dt=0.1, drive=30.0, v=0.4):
    """A unicycle that stands ``stand`` s, speeds up over 1 s to ``v`` and drives straight:
    its log (speed, yaw rate) and true positions at each row."""
    t = np.arange(0.0, stand + drive, dt)
    speed = np.clip((t - stand) / 1.0, 0.0, 1.0) * v
    log = OdometryLog(t, {"speed": speed, "yaw_rate": np.zeros(t.size)})
    x = np.concatenate(([0.0], np.cumsum(speed[:-1] * dt)))
    return log, np.column_stack((x, np.zeros(t.size)))


def test_a_truth_that_moves_before_the_odometry_starts_is_its_clock_not_a_stuck_encoder():
    """TUC SLAM study: the robot stands 42 s, and the truth starts moving 0.5 s before the
    odometry does (its fixes stamped 0.5 s early: it leads). That was a FAIL blaming a truth
    that *lags*; it is a warning that measures the lead."""
    from odomkit.robot import Unicycle

    log, xy = _unicycle_stand_then_drive()
    lead = 0.5
    truth = Truth(log.t[::2] - lead, xy[::2], None)  # each pose stamped 0.5 s early
    found = check_stuck(log, Unicycle(), truth)
    assert statuses(found, "stuck") == ["warn"], found
    assert "before the odometry" in found[0].message and "leads" in found[0].message
    said = float(found[0].message.split("all of it in the last ")[1].split()[0])
    assert said == pytest.approx(lead, abs=0.25)
    # stamped late (it lags): the same stand, the truth still moving after the odometry stops
    back = OdometryLog(log.t, {"speed": log.channels["speed"][::-1].copy(), "yaw_rate": np.zeros(len(log))})
    x_back = np.concatenate(([0.0], np.cumsum(back.channels["speed"][:-1] * 0.1)))
    late = Truth(log.t[::2] + lead, np.column_stack((x_back, np.zeros(len(log))))[::2], None)
    found = check_stuck(back, Unicycle(), late)
    assert statuses(found, "stuck") == ["warn"] and "lags" in found[0].message


def test_a_truth_that_creeps_while_the_robot_stands_is_a_warning():
    """The truth drifts 8 cm evenly over 40 s while the robot stands (its clock right): no
    robot drives on a stuck encoder at 2 mm/s beside 0.4 m/s."""
    from odomkit.robot import Unicycle

    log, xy = _unicycle_stand_then_drive()
    creep = np.where(log.t < 40.0, 0.002 * log.t, 0.08)
    drifting = xy + np.column_stack((np.zeros(len(log)), creep))
    found = check_stuck(log, Unicycle(), Truth(log.t, drifting, None))
    assert statuses(found, "stuck") == ["warn"] and "creep" in found[0].message


def test_a_speed_that_reads_zero_at_a_crawl_is_named_and_a_stuck_speed_still_fails():
    """smartLoc car study: the speed reads 0 below 0.3 m/s as the car stops for 1 s, and the
    GNSS fixes jump 0.4 m while it stands. A warning naming a cutoff near 0.3 m/s. The same
    speed channel stuck at 0 for 3 s of driving at 8 m/s still fails."""
    from odomkit.robot import Unicycle

    dt = 0.2
    t = np.arange(0.0, 60.0, dt)
    # 8 m/s, brake at 1 m/s² to a stop at t = 28 s, stand 1 s, speed up again at 1 m/s²
    true_speed = np.clip(np.minimum(np.abs(t - 28.5) - 0.5, 8.0), 0.0, None)
    x = np.concatenate(([0.0], np.cumsum(true_speed[:-1] * dt)))
    rng = np.random.default_rng(3)
    xy = np.column_stack((x, np.zeros(t.size))) + rng.normal(0.0, 0.02, (t.size, 2))
    xy[(t >= 28.0) & (t < 33.0), 1] += 0.4  # a multipath jump while the car stands
    truth = Truth(t, xy, None)
    read = np.where(true_speed < 0.3, 0.0, true_speed)
    log = OdometryLog(t, {"speed": read, "yaw_rate": np.zeros(t.size)})
    found = check_stuck(log, Unicycle(), truth)
    assert statuses(found, "stuck") == ["warn"], found
    cutoff = float(found[0].message.split("reads 0 below about ")[1].split()[0])
    assert 0.3 <= cutoff <= 0.6
    stuck = np.where((t > 10.0) & (t < 13.0), 0.0, true_speed)
    found = check_stuck(OdometryLog(t, {"speed": stuck, "yaw_rate": np.zeros(t.size)}), Unicycle(), truth)
    assert statuses(found, "stuck") == ["fail"] and "stuck encoder" in found[0].message


def test_times_on_an_epoch_clock_are_said_to_the_millisecond():
    """MRCLAM logs (and ROS bags) stamp rows with Unix time: ``.6g`` printed every time of
    the day as 1.24844e+09, so a stuck stretch "from t = 1.24844e+09 s to 1.24844e+09 s"
    named no time at all. The stretch is said to the millisecond (:func:`odomkit.log.clock_text`)."""
    left, right = square_both_ways()
    epoch = 1248444187.156
    stuck = left.copy()
    stuck[5:45] = 0.0  # the left encoder reads nothing for 2 s of straight driving
    log = make_log(left, right)
    truth = truth_of(log)
    late = OdometryLog(log.t + epoch, make_log(stuck, right).channels)
    found = check_stuck(late, ROBOT, Truth(truth.t + epoch, truth.xy, truth.theta))
    assert statuses(found, "stuck") == ["fail"]
    said = found[0].message.split("from t = ")[1].split(" s while")[0].split(" s to ")
    start, end = (float(x) for x in said)
    assert "e+09" not in found[0].message and all(len(x.split(".")[1]) == 3 for x in said)
    assert start == pytest.approx(epoch + 5 * PERIOD, abs=PERIOD)
    assert end == pytest.approx(epoch + 45 * PERIOD, abs=PERIOD)


def test_a_slalom_under_a_quarter_turn_each_way_is_not_called_hardly_turning():
    """A slalom that turns about 1.4 rad each way (a user study's F1TENTH car: 1.47 and
    1.32 rad) was told "hardly any turning"; it turns, only under the quarter turn each way
    that the warning's threshold (π/2) asks for."""
    from odomkit.kinematics import body_steps

    steps = np.arange(1, 4001)
    wave = 1.65 * np.sin(2 * np.pi * steps / 1000.0)  # the wheels' tick difference: a slalom
    log = make_log(np.r_[0.0, 250.0 - wave], np.r_[0.0, 250.0 + wave])
    dtheta = body_steps(ROBOT, log).dtheta
    ccw, cw = float(np.sum(dtheta[dtheta > 0])), float(-np.sum(dtheta[dtheta < 0]))
    assert 1.0 < min(ccw, cw) and max(ccw, cw) < 0.5 * math.pi  # turning, but under a quarter each way
    (f,) = [f for f in check_motion(log, ROBOT) if f.check == "turning"]
    assert f.status == "warn" and "hardly" not in f.message
    assert "under a quarter turn either way" in f.message


def test_a_cars_turning_advice_names_a_drive_a_car_can_make():
    """A car on a highway was told to drive "a square each way" (a user study's RAV4)."""
    from odomkit.robot import Car

    t = np.arange(0, 60.0, 0.1)
    log = OdometryLog(t, {"speed": np.full(t.size, 17.0), "steer": np.full(t.size, 0.001)})
    (f,) = [f for f in check_motion(log, Car(2.65)) if f.check == "turning"]
    assert f.status == "warn" and "roundabout" in (f.advice or "") and "square" not in (f.advice or "")
