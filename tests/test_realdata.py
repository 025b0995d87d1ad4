"""Dead reckoning of the real logs against their ground truth.

Reference figures come from the data folders' SOURCE.md files, computed by the data
curators independently of this code; tolerances are the precision those notes state.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.io.halmstad import read_khepera, read_snowhite
from odomkit.io.optiodom import read_experiment
from odomkit.robot import DiffDrive, Tricycle
from odomkit.track import dead_reckon_log

pytestmark = pytest.mark.slow


def test_snowhite_with_the_exercise_model(data_dir):
    log = read_snowhite(data_dir / "halmstad-khepera-snowhite" / "snowhite.txt")
    track = dead_reckon_log(log, Tricycle(wheel_to_axle=0.68), "exact")  # L = 680 mm, T = 50 ms
    err = np.hypot(*(track.poses[:, :2] - log.ground_truth[:, :2]).T)
    # SOURCE.md: final error "about 0.23 m (maximum 0.27 m)", Σ v·cos α·T "31.9 m",
    # ground-truth path "about 31.6 m", 4,050 samples "make 202.5 s" (we span 202.45 s
    # between the first and last sample).
    assert err[-1] == pytest.approx(0.23, abs=0.005)
    assert err.max() == pytest.approx(0.27, abs=0.005)
    assert track.path_length == pytest.approx(31.9, abs=0.05)
    gt_length = np.sum(np.hypot(*np.diff(log.ground_truth[:, :2], axis=0).T))
    assert gt_length == pytest.approx(31.6, abs=0.05)
    assert track.duration == pytest.approx(4049 * 0.05)


def test_khepera_circle_closes(data_dir):
    log = read_khepera(data_dir / "halmstad-khepera-snowhite" / "khepera_circle.txt")
    robot = DiffDrive.from_wheels(0.053, 0.0153, encoder_resolution=600)  # handout values
    track = dead_reckon_log(log, robot, "exact", pose0=(0.0, 0.0, np.pi / 2))
    # SOURCE.md: "turns about +378° and ends about 24 mm from its start point".
    assert np.degrees(track.poses[-1, 2] - np.pi / 2) == pytest.approx(378, abs=0.5)
    assert np.hypot(*track.poses[-1, :2]) == pytest.approx(0.024, abs=0.001)


def test_khepera_with_wrong_parameters_scales_as_expected(data_dir):
    """The handout's Task 5 (D = 14 mm, B = 45 mm): heading scales by (14/15.3)·(53/45)
    and positions by 14/15.3 — exact consequences of the kinematics, independent of data."""
    log = read_khepera(data_dir / "halmstad-khepera-snowhite" / "khepera.txt")
    good = dead_reckon_log(log, DiffDrive.from_wheels(0.053, 0.0153, encoder_resolution=600))
    bad = dead_reckon_log(log, DiffDrive.from_wheels(0.045, 0.014, encoder_resolution=600))
    ratio = (0.014 / 0.0153) * (0.053 / 0.045)
    assert bad.poses[-1, 2] == pytest.approx(good.poses[-1, 2] * ratio, rel=1e-12)
    assert bad.path_length == pytest.approx(good.path_length * 0.014 / 0.0153, rel=1e-12)
    assert np.any(np.diff(np.cumsum(log.channels["ticks_left"])) < 0)  # it does reverse


SQUARES = ["230620202042", "230620202144", "230620202258", "230620202317",
           "231220200029", "231220200040", "231220200045", "231220200048"]


@pytest.mark.parametrize("experiment", SQUARES)
def test_optiodom_umbmark_squares_against_optitrack(data_dir, experiment):
    ex = read_experiment(data_dir / "optiodom" / "diff" / "square" / experiment)
    robot = ex.metadata.robot()  # each experiment's own nominal parameters
    errors = {"cw": [], "ccw": []}
    for run, direction in zip(ex.runs, ex.directions, strict=True):
        track = dead_reckon_log(run, robot, "exact")
        gt = run.ground_truth
        # Both directions end after four 90° turns: |Δθ| ≈ 2π (SOURCE.md: −6.250 vs −6.222).
        assert abs(gt[-1, 2] - gt[0, 2]) == pytest.approx(2 * np.pi, abs=0.3)
        heading_error = track.poses[-1, 2] - gt[-1, 2]
        position_error = np.hypot(*(track.poses[-1, :2] - gt[-1, :2]))
        # Uncalibrated odometry: heading within 0.15 rad (9°) and position within 5 % of
        # the 4·side path after a full square.
        assert abs(heading_error) < 0.15
        assert position_error < 0.05 * 4 * ex.metadata.side * 1.15
        errors[direction].append(heading_error)
    # Systematic (wheel-base type) errors turn the two directions the opposite way:
    # the UMBmark signature Borenstein–Feng exploit (Type A error, section 4).
    assert np.sign(np.mean(errors["cw"])) == -np.sign(np.mean(errors["ccw"]))


def test_khepera_sampling_period_study(data_dir):
    """Reading the encoders every n-th sample (the exercise's question 3): the exact arc
    keeps the decimated track on the full-rate one, Euler drifts off linearly in n."""
    log = read_khepera(data_dir / "halmstad-khepera-snowhite" / "khepera_circle.txt")
    robot = DiffDrive.from_wheels(0.053, 0.0153, encoder_resolution=600)
    full = dead_reckon_log(log, robot, "exact", pose0=(0, 0, np.pi / 2)).poses[-1]
    miss = {}
    for method in ("exact", "euler"):
        for n in (5, 10):
            end = dead_reckon_log(log.decimate(n), robot, method, pose0=(0, 0, np.pi / 2)).poses[-1]
            miss[method, n] = np.hypot(*(end[:2] - full[:2]))
    # The arc is exact only for constant curvature; a merged real step is not quite, so
    # the exact track moves too, but by an order of magnitude less than Euler's.
    assert miss["exact", 10] < 0.1 * miss["euler", 10]
    # Euler's global error is first order in the step: doubling n roughly doubles it.
    assert 1.6 < miss["euler", 10] / miss["euler", 5] < 2.4
