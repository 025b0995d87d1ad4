"""The truth's heading against the direction its positions move in (``odomkit check``).

Independent truth: a differential drive driven in straight legs and turns, its truth the
true path with a motion capture's millimetre of noise, and the truth's heading turned by a
known δ (a rigid body glued on askew). The estimate must find δ within its stated
standard error's tolerance, warn when δ matters, stay quiet at δ = 0, and say so when the
robot never drives straight. On OptiOdom's real runs every square run of the tricycle
gives the same body misalignment (about +19 mrad): a property of the rigid body, not of
any one run.
"""

from __future__ import annotations

import glob
import math

import numpy as np
import pytest

from odomkit.calibrate.check import check_log
from odomkit.calibrate.check_truth import MATERIAL, check_truth_heading, heading_misalignment
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth

ROBOT = DiffDrive(0.3)


def legs_log(straight=True, seed=0, period=0.02):
    """Straight 2 m legs at 0.3 m/s joined by 90° turns on the spot (or, with ``straight``
    False, a steady circle), as wheel distances per row."""
    rng = np.random.default_rng(seed)
    v, w = [], []
    for _ in range(8):
        v += [0.3] * round(2.0 / 0.3 / period) if straight else [0.3] * round(6.0 / period)
        w += [0.0] * round(2.0 / 0.3 / period) if straight else [0.3] * round(6.0 / period)
        v += [0.0] * round(1.0 / period)
        w += [math.pi / 2] * round(1.0 / period)
    v, w = np.array(v), np.array(w)
    # Each wheel's distance per row with a little encoder noise (sign both ways).
    half = 0.5 * ROBOT.wheel_base * w * period
    left = v * period - half + 1e-5 * rng.standard_normal(v.size)
    right = v * period + half + 1e-5 * rng.standard_normal(v.size)
    t = period * np.arange(v.size + 1)
    return OdometryLog(t, {"dist_left": np.r_[0.0, left], "dist_right": np.r_[0.0, right]})


def truth_of(log, delta, sigma=0.001, seed=1):
    rng = np.random.default_rng(seed)
    poses = dead_reckon_log(log, ROBOT, pose0=np.array([1.0, 2.0, 0.4])).poses
    xy = poses[:, :2] + sigma * rng.standard_normal((len(log.t), 2))
    return Truth(np.asarray(log.t), xy, poses[:, 2] + delta + 0.002 * rng.standard_normal(len(log.t)))


@pytest.mark.parametrize("delta", [0.02, -0.01, 0.0])
def test_a_truth_heading_turned_by_delta_is_found_within_its_standard_error(delta):
    log = legs_log()
    found, se, n = heading_misalignment(log, ROBOT, truth_of(log, delta))
    assert n >= 40
    assert 0 < se < 0.002
    assert abs(found - delta) < 4 * se + 1e-4, (found, se)
    [finding] = check_truth_heading(log, ROBOT, truth_of(log, delta))
    assert finding.check == "truth_heading"
    assert finding.value == pytest.approx(found)
    if abs(delta) > MATERIAL:
        assert finding.status == "warn"
        assert f"{1000 * abs(delta):.0f} mm across its track per metre" in finding.message
        assert "truth_heading_sigma" in (finding.advice or "")
    else:
        assert finding.status == "ok"


def test_no_straight_driving_says_it_cannot_tell_and_position_only_truth_is_not_checked():
    log = legs_log(straight=False)
    [finding] = check_truth_heading(log, ROBOT, truth_of(log, 0.02))
    assert finding.status == "ok" and "too little straight driving" in finding.message
    truth = truth_of(log, 0.0)
    assert check_truth_heading(log, ROBOT, Truth(truth.t, truth.xy)) == []
    assert check_truth_heading(log, ROBOT, None) == []


def test_check_log_reports_the_misaligned_truth():
    log = legs_log()
    found = check_log(log, ROBOT, truth_of(log, 0.03))
    [finding] = [f for f in found if f.check == "truth_heading"]
    assert finding.status == "warn" and finding.value == pytest.approx(0.03, abs=0.003)


@pytest.mark.slow
def test_optiodom_tricycle_rigid_body_is_misaligned_alike_in_every_square_run(data_dir):
    from odomkit.io.optiodom import read_experiment
    from odomkit.truth import truth_from_log

    found = []
    for folder in sorted(glob.glob(str(data_dir / "optiodom" / "tricyc" / "square" / "*"))):
        experiment = read_experiment(folder)
        for log in experiment.runs:
            delta, se, n = heading_misalignment(log, experiment.metadata.robot(), truth_from_log(log))
            assert n >= MIN_SQUARE_STRETCHES
            found.append((delta, se))
    deltas = np.array([d for d, _ in found])
    assert len(deltas) == 14
    # One rigid body: every run's value agrees with the others within a few of its own
    # standard errors, and all are material.
    mean, spread = float(np.mean(deltas)), float(np.max([se for _, se in found]))
    assert np.all(np.abs(deltas - mean) < 4 * spread + 0.002)
    assert 0.015 < mean < 0.023


MIN_SQUARE_STRETCHES = 30


@pytest.mark.parametrize("straight", [True, False])
def test_a_heading_that_is_no_heading_of_the_robot_fails(straight):
    """A truth heading in degrees, or turned a quarter turn (a motion capture's body defined
    along another axis), fails whether or not the robot drives straight; on a circle it
    used to be "ok: too little straight driving"."""
    log = legs_log(straight=straight)
    truth = truth_of(log, 0.0)
    for wrong in (Truth(truth.t, truth.xy, np.degrees(truth.theta)), truth_of(log, math.pi / 2)):
        [finding] = check_truth_heading(log, ROBOT, wrong)
        assert finding.status == "fail", finding
        assert "does not follow the direction" in finding.message
        assert "theta_deg" in (finding.advice or "")


def test_a_truth_measured_far_ahead_of_a_tight_turning_tricycle_is_named():
    """A tricycle (rear axle 1.4 m behind its steered wheel) tracked at a sensor 1.5 m ahead of
    its rear axle: in a turn of steering angle α that point moves atan(tan α · 1.5 / 1.4) off
    the heading (48° at α = 0.8 rad), as in a user study's real tricycle (58°). The finding's
    causes named degrees, quaternions and bodies but not this; they now name a truth measured
    far off the reference point. At the rear axle itself the same drive is fine."""
    from odomkit.robot import Tricycle

    tricycle = Tricycle(wheel_to_axle=1.4)
    t = np.arange(0.0, 120.0, 0.05)
    steer = 0.8 * np.sign(np.sin(2 * math.pi * t / 40.0))  # circles one way, then the other
    log = OdometryLog(t, {"speed": np.full(t.size, 0.5), "steer": steer}, source="tricycle")
    poses = dead_reckon_log(log, tricycle).poses
    assert 180 * math.atan(math.tan(0.8) * 1.5 / 1.4) / math.pi == pytest.approx(48.0, abs=0.5)
    ahead = poses[:, :2] + 1.5 * np.column_stack([np.cos(poses[:, 2]), np.sin(poses[:, 2])])
    [finding] = check_truth_heading(log, tricycle, Truth(t, ahead, poses[:, 2]))
    assert finding.status == "fail" and "reference point" in (finding.advice or "")
    assert check_truth_heading(log, tricycle, Truth(t, poses[:, :2], poses[:, 2]))[0].status != "fail"
