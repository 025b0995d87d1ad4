"""The travel and turning ratios (``odomkit check``) where the odometry turns the wrong way or
not at all, and against a GPS whose error wanders (a Husky's bag in a user study).

Independent truth: the true path of a simulated base, its log exact, so that the true ratios
are 1 (or −1 for a flipped sign, 0 for a yaw rate read about another axis); the GPS's error
is an Ornstein–Uhlenbeck process (σ 0.8 m per axis, correlated over 12 s, as the Husky's
fixes about its calibrated track: 0.48 m per axis over 2.4 s, 0.84 m over 10 s) plus 5 cm of
white noise, at 2.5 Hz. Its scatter about a smooth path is then about 0.13 m, and the check,
judging 2.4 s chords against that, took the wander for turning: the odometry "turned" 0.2–0.5 ×
as much as the truth and was told to check its yaw rate's unit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.calibrate.check import check_log
from odomkit.calibrate.check_ratios import check_truth_motion, judging_noise, motion_problems
from odomkit.log import OdometryLog
from odomkit.robot import Car, GyroOdometry, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth, scatter_sigma


def wandering_gps(log, poses, seed, sigma=0.8, tau=12.0, white=0.05, rate=2.5):
    """Fixes at ``rate`` Hz whose error is an OU process (``sigma`` per axis, correlation time
    ``tau`` [s]) plus ``white`` noise: times and positions."""
    rng = np.random.default_rng(seed + 7)
    tg = np.arange(0.13, log.t[-1], 1.0 / rate)
    xy = np.column_stack([np.interp(tg, log.t, poses[:, k]) for k in (0, 1)])
    keep = math.exp(-1.0 / (rate * tau))
    error = np.zeros_like(xy)
    error[0] = rng.normal(0.0, sigma, 2)
    for i in range(1, tg.size):
        error[i] = keep * error[i - 1] + math.sqrt(1 - keep**2) * rng.normal(0.0, sigma, 2)
    return tg, xy + error + rng.normal(0.0, white, xy.shape)


def by_check(found):
    return {f.check: f for f in found}


def with_channel(log, name, values):
    return OdometryLog(log.t, {**log.channels, name: values})


def motion_capture(log, poses, every=2, seed=0):
    """Every ``every``-th pose with 2 mm and 2 mrad of noise, at 2 mm stated."""
    rng = np.random.default_rng(seed + 50)
    xy, theta = poses[::every, :2], poses[::every, 2]
    return Truth(log.t[::every], xy + rng.normal(0.0, 0.002, xy.shape),
                 theta + rng.normal(0.0, 0.002, theta.shape), 0.002, "mocap")


# --- the odometry turns the other way, or not at all -------------------------------------

@pytest.mark.parametrize("heading", [True, False])
def test_a_flipped_yaw_rate_turns_the_opposite_way_and_names_the_sign(heading, husky_drive):
    """The yaw rate's sign flipped: the turning gain is −1 (the ratio of sums signed by the
    larger turn). Before: math.log(−1), "the numerics failed (math domain error)"."""
    log, poses = husky_drive(1)
    truth = motion_capture(log, poses, 2 if heading else 4)
    truth = truth if heading else Truth(truth.t, truth.xy, None, 0.002)
    flipped = with_channel(log, "yaw_rate", -log.channels["yaw_rate"])
    turn = by_check(check_truth_motion(flipped, Unicycle(), truth))["turn_ratio"]
    assert turn.status == "fail" and "opposite way" in turn.message
    assert turn.value == pytest.approx(-1.0, abs=0.1)
    assert "sign" in (turn.advice or "") and "yaw rate" in (turn.advice or "")
    # The whole check runs (the channel check names the flipped sign first, where it can).
    assert any(f.status == "fail" for f in check_log(flipped, Unicycle(), truth))


def test_a_car_whose_steering_sign_is_flipped_turns_the_opposite_way_per_metre():
    car = Car(2.7)
    rng = np.random.default_rng(3)
    t = 0.1 * np.arange(3000)
    knots = rng.uniform(-0.1, 0.1, 32) * (rng.random(32) < 0.5)
    log = OdometryLog(t, {"speed": np.full(t.size, 6.0), "steer": np.interp(t, np.arange(32) * 10.0, knots)})
    poses = dead_reckon_log(log, car, pose0=np.zeros(3)).poses
    flipped = with_channel(log, "steer", -log.channels["steer"])
    turn = by_check(check_truth_motion(flipped, car, motion_capture(log, poses)))["turn_ratio"]
    assert turn.status == "fail" and "opposite way" in turn.message
    assert turn.value == pytest.approx(-1.0, abs=0.1)
    assert "steering angle's sign" in (turn.advice or "")


@pytest.mark.parametrize("robot", [Unicycle(), GyroOdometry()])
def test_a_yaw_rate_about_another_axis_hardly_turns_and_names_the_imu(robot, husky_drive):
    """An IMU on its side: the channel read as the yaw rate is its rotation about a horizontal
    axis (a pitch wobble of a few mrad/s, nothing to do with the turning). The gain is about 0:
    no unit's factor, no scale. Before: a gain ≤ 0 stopped the check (math domain error), a
    small positive one was told to check the yaw rate's unit."""
    log, poses = husky_drive(2)
    rng = np.random.default_rng(2)
    pitch = 0.003 * np.sin(log.t / 1.7) + rng.normal(0.0, 0.002, log.t.size)
    sideways = with_channel(log, "yaw_rate", pitch)
    for truth in (motion_capture(log, poses), Truth(log.t[::4], poses[::4, :2], None, 0.002)):
        turn = by_check(check_truth_motion(sideways, robot, truth))["turn_ratio"]
        assert turn.status == "fail" and "hardly turns" in turn.message, turn.message
        assert turn.value is not None and abs(turn.value) < 0.05
        assert "not mounted level" in (turn.advice or "")
    # calibrate's and fit-noise's lines say the same, without stopping.
    [line] = motion_problems(sideways, robot, motion_capture(log, poses))
    assert "hardly turns" in line
    # What the log would pin is not judged on a model that does not describe it (a Husky
    # bag's figures read ±1e+11 %): one line saying so instead.
    found = [f for f in check_log(sideways, robot, motion_capture(log, poses)) if f.check == "identifiable"]
    assert len(found) == 1 and found[0].message.startswith("not judged: the odometry's turning")


def test_a_log_that_does_not_move_fails_its_travel_without_a_logarithm(husky_drive):
    """A speed channel all zero while the truth drives: the travel ratio is 0 (math.log(0)
    stopped the check before)."""
    log, poses = husky_drive(4)
    still = with_channel(log, "speed", np.zeros(log.t.size))
    travel = by_check(check_truth_motion(still, Unicycle(), motion_capture(log, poses)))["travel_ratio"]
    assert travel.status == "fail" and travel.value == 0.0
    assert "does not move" in travel.message


# --- a GPS whose error wanders, stating its σ ----------------------------------------------

@pytest.mark.parametrize("seed", range(6))
def test_a_wandering_gps_is_judged_at_the_sigma_its_fixes_state(seed, husky_drive):
    """The log is exact: its ratios are 1. Judged at the fixes' scatter (about 0.13 m) the
    wander of a 0.8 m GPS over 2.4 s chords reads as turning, and the check fails the turning
    as a unit mixup; judged at the σ the fixes state (Truth.stated_sigma: a NavSatFix's
    covariance, not given as --truth-sigma) over the chords that σ asks for, it is ok, and the
    finding says whose σ judged it."""
    log, poses = husky_drive(seed)
    t, xy = wandering_gps(log, poses, seed)
    plain = Truth(t, xy, None, 0.0, "gps")
    assert scatter_sigma(plain) == pytest.approx(0.13, abs=0.03)
    before = by_check(check_truth_motion(log, Unicycle(), plain))["turn_ratio"]
    assert before.status != "ok" and before.value is not None and before.value < 0.8  # the trap
    stated = Truth(t, xy, None, 0.0, "gps", stated_sigma=0.8)
    assert judging_noise(stated)[0] == 0.8 and judging_noise(stated)[1] == pytest.approx(scatter_sigma(plain))
    found = by_check(check_truth_motion(log, Unicycle(), stated))
    for check in ("travel_ratio", "turn_ratio"):
        assert found[check].status == "ok", found[check].message
        assert "0.8 m sigma the fixes state" in found[check].message
    # Never used to fit: the stated σ stays out of the truth's own sigma.
    assert stated.sigma == 0.0


def test_a_given_sigma_is_the_sigmas_own_and_no_note_is_made(husky_drive):
    log, poses = husky_drive(0)
    t, xy = wandering_gps(log, poses, 0)
    found = by_check(check_truth_motion(log, Unicycle(), Truth(t, xy, None, 0.8, "gps")))
    assert found["turn_ratio"].status == "ok" and "fixes state" not in found["turn_ratio"].message
    assert judging_noise(Truth(t, xy, None, 0.8, "gps")) == (0.8, None)


def test_a_ratio_within_two_standard_errors_of_one_is_not_failed(husky_drive):
    """A few long chords of a noisy GPS give a ratio far from 1 with a standard error as
    large: no evidence of a unit, so ok, and said why. Seed 1 of the drives above gave a
    turning of 1.83 ± 1.14 (a warning before)."""
    log, poses = husky_drive(1)
    t, xy = wandering_gps(log, poses, 1)
    turn = by_check(check_truth_motion(log, Unicycle(), Truth(t, xy, None, 0.8, "gps")))["turn_ratio"]
    assert turn.value is not None and abs(turn.value - 1) > 0.25  # beyond TURN_WARN on its own
    assert turn.status == "ok" and "within 2 standard errors of 1" in turn.message


def test_calibrates_residual_warning_holds_them_against_the_sigma_the_fixes_state(husky_drive):
    """calibrate's "residuals are Nx the truth's noise" takes the σ the fixes state where none
    is given, as check does (a Husky's residuals were "15.38x the truth's scatter (0.1 m)"
    against fixes stating 0.8 m); given a σ, that one."""
    import warnings

    from odomkit.calibrate.exact import warn_if_drifting

    log, poses = husky_drive(3)
    tg, xy = wandering_gps(log, poses, 3)
    stated = Truth(tg, xy, None, 0.0, "gps", stated_sigma=0.8)
    assert scatter_sigma(stated) < 0.3  # the scatter about a smooth path misses the wander

    def said(truth, rms):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            warn_if_drifting(rms**2, 2 * len(truth), [truth])
        return [str(w.message) for w in caught]

    assert said(stated, 0.7) == []  # under the 0.8 m the fixes state
    [line] = said(stated, 1.54)
    assert "1.93x the truth's σ its fixes state (0.8 m)" in line
    [line] = said(Truth(tg, xy, None, 0.0, "gps"), 0.7)  # nothing stated: the scatter, as before
    assert "scatter about a smooth path" in line


# --- a drive too straight for a turning ratio ----------------------------------------------

def highway(seed, seconds=60.0):
    """A car at 17 m/s keeping its lane for ``seconds``: its steering wheel (ratio 14.5)
    wobbles by about 2° over a few seconds and holds a 0.2° offset, the road wheels' angle
    1/14.5 of it. Returns the log of the steering-wheel angle, and the true poses."""
    rng = np.random.default_rng(seed)
    t = 0.01 * np.arange(int(seconds / 0.01) + 1)
    knots = np.deg2rad(rng.normal(0.2, 2.0, int(seconds / 3) + 2))
    wheel = np.interp(t, 3.0 * np.arange(knots.size), knots)
    log = OdometryLog(t, {"speed": np.full(t.size, 17.0), "steer": wheel})
    poses = dead_reckon_log(log, Car(2.65, steering_ratio=14.5), pose0=np.zeros(3)).poses
    return log, poses


@pytest.mark.parametrize("seed", range(4))
def test_a_car_on_a_highway_read_without_its_steering_ratio_fails_its_turning(seed):
    """A RAV4's 60 s on a highway against its 10 Hz GPS, the robot file without its
    steering_ratio (a user study): the GPS turns within its noise between stretches, so no
    pair gave a ratio, and check said "not compared" while the track ended 521 m off. The
    odometry's turns between stretches, about their steady turn, vary 14.5× the true ones,
    far beyond the truth's; with the ratio they are the truth's and nothing fails."""
    log, poses = highway(seed)
    rng = np.random.default_rng(seed + 100)
    tg = np.arange(0.05, log.t[-1], 0.1)
    xy = np.column_stack([np.interp(tg, log.t, poses[:, k]) for k in (0, 1)])
    gps = Truth(tg, xy + rng.normal(0.0, 0.09, xy.shape))
    without = by_check(check_truth_motion(log, Car(2.65), gps))["turn_ratio"]
    assert without.status == "fail" and "steering_ratio" in (without.advice or ""), without
    assert without.value >= 10.0
    right = by_check(check_truth_motion(log, Car(2.65, steering_ratio=14.5), gps))["turn_ratio"]
    assert right.status != "fail", right
    # A GPS whose error wanders (0.8 m over 12 s) does not make a right file fail either.
    tw, xw = wandering_gps(log, poses, seed, rate=10.0)
    wander = Truth(tw, xw)
    right = by_check(check_truth_motion(log, Car(2.65, steering_ratio=14.5), wander))["turn_ratio"]
    assert right.status != "fail", right
