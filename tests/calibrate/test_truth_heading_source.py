"""Two truths whose heading is not an independent measurement of the robot's, from a user
study on a lawn mower's RTK "ground truth" (CMU Plaza):

* a heading offset by π: the robot seems to drive backwards all the way. Every start taken
  from it drives the odometry backwards (evaluate scored ATE 74.8 m against 1.48 m from the
  positions alone, silently), and ``check`` named only "the distance sign flipped";
* a heading that is the odometry's own, integrated from the same gyro: ``check`` said
  "ok turn_ratio 1 ± 3.5e-09", an agreement no two sensors give.

The drives are simulated (tests/conftest.py ``husky_drive``): the truth is the true path,
with 2 mm and 2 mrad of noise where it is meant to be independent.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from odomkit.calibrate.check_channels import check_channels
from odomkit.calibrate.check_ratios import check_truth_motion
from odomkit.robot import Unicycle
from odomkit.truth import Truth, heading_backwards
from odomkit.workflows.truth import warn_of_truth


def _truth(log, poses, heading, seed=0):
    rng = np.random.default_rng(seed)
    every = slice(None, None, 2)
    return Truth(log.t[every], poses[every, :2] + rng.normal(0.0, 0.002, poses[every, :2].shape),
                 heading[every], 0.002, "mocap")


def test_a_heading_pi_off_is_said_by_every_reader_and_named_by_check(husky_drive):
    log, poses = husky_drive(3, duration=200.0)
    rng = np.random.default_rng(1)
    right = _truth(log, poses, poses[:, 2] + rng.normal(0.0, 0.002, len(log.t)))
    reversed_ = _truth(log, poses, poses[:, 2] + math.pi + rng.normal(0.0, 0.002, len(log.t)))
    assert heading_backwards(right) is None
    said = heading_backwards(reversed_)
    assert said is not None and "π off" in said and "100 %" in said
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_of_truth(reversed_, log)
    assert any("points against the direction its positions move" in str(w.message) for w in caught)
    (found,) = [f for f in check_channels(log, Unicycle(), reversed_) if f.check == "channels"]
    assert found.status == "fail" and "distance sign flipped" in found.message
    assert "the truth's heading points backwards" in (found.advice or "")


def test_a_truth_heading_that_is_the_odometrys_own_is_not_a_check(husky_drive):
    log, poses = husky_drive(4, duration=200.0)
    rng = np.random.default_rng(2)
    own = _truth(log, poses, poses[:, 2])  # the odometry's own heading, exactly
    independent = _truth(log, poses, poses[:, 2] + rng.normal(0.0, 0.002, len(log.t)))
    (same,) = [f for f in check_truth_motion(log, Unicycle(), own) if f.check == "turn_ratio"]
    assert same.status == "warn" and "the odometry's own" in same.message
    (apart,) = [f for f in check_truth_motion(log, Unicycle(), independent) if f.check == "turn_ratio"]
    assert apart.status == "ok" and "own" not in apart.message
