"""A truth interpolated between sparse keyframes (:mod:`odomkit.truth_knots`), ``odomkit
check``'s ``truth_interpolated`` finding, and the warnings of ``evaluate --window`` and
``fit-noise``.

Independent truth: a simulated unicycle's turning drive, integrated in closed form on a fine
grid; its "reference" is built the way the TUC SLAM dataset's is, the true poses at sparse
keyframes interpolated linearly to a 5 Hz grid and the keyframe's heading held until the
next. The numbers the detector must give follow from the construction (which fixes are
knots, how far apart, how many fixes lie between them), not from the code. Negative cases:
the same drive measured (a noisy GPS, a motion capture, the noise-free dense poses), a
noise-free straight line at constant speed, a noise-free square with stops at its corners,
the keyframes alone, a noise-free drive written with 3 decimals, and OptiOdom's real runs.
"""

from __future__ import annotations

import glob
import json
import math

import numpy as np
import pytest

from odomkit.calibrate.check import check_log
from odomkit.calibrate.check_truth import check_truth_interpolated
from odomkit.log import OdometryLog
from odomkit.robot import Unicycle
from odomkit.truth import Truth
from odomkit.truth_knots import INTERPOLATED_ADVICE, MIN_RUN_FIXES, interpolated_note, truth_knots

FINE = 0.01  # [s] the simulation's step
RATE = 0.2  # [s] the reference's grid (5 Hz)
EVERY = 11  # a keyframe every 11 fixes: 2.2 s apart


def speed_and_rate(t):
    """The drive's speed [m/s] and yaw rate [rad/s]: always moving, turning both ways."""
    return 0.5 + 0.2 * np.sin(t / 7.0), 0.6 * np.sin(t / 5.0) + 0.2 * np.sin(t / 1.7)


def drive(duration=120.0):
    """The true poses on a fine grid: heading the integral of the yaw rate (trapezoid, to
    rounding), positions the exact arcs' chords summed (fine enough to be the path)."""
    t = FINE * np.arange(round(duration / FINE) + 1)
    v, w = speed_and_rate(t)
    theta = 0.3 + np.concatenate(([0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * FINE)))
    mid = 0.5 * (theta[1:] + theta[:-1])
    ds = 0.5 * (v[1:] + v[:-1]) * FINE
    x = 3.0 + np.concatenate(([0.0], np.cumsum(ds * np.cos(mid))))
    y = -7.0 + np.concatenate(([0.0], np.cumsum(ds * np.sin(mid))))
    return t, np.column_stack((x, y, theta))


def interpolated(t_fine, poses, key_t, grid):
    """The reference: true poses at ``key_t`` interpolated linearly to ``grid``, the
    heading held from one keyframe to the next."""
    key = np.column_stack([np.interp(key_t, t_fine, poses[:, k]) for k in range(3)])
    xy = np.column_stack([np.interp(grid, key_t, key[:, k]) for k in (0, 1)])
    held = key[np.searchsorted(key_t, grid, side="right") - 1, 2]
    return Truth(grid, xy, held, source="reference"), key


def on_grid_reference(duration=121.0):
    t, poses = drive(duration)
    grid = RATE * np.arange(round(duration / RATE) + 1)
    return interpolated(t, poses, grid[::EVERY], grid)


def turns_between(key):
    """Turns of the keyframes' chords by more than 0.01 rad (the runs' directions, where the
    knots are the keyframes)."""
    chord = np.diff(key[:, :2], axis=0)
    turn = np.abs(np.angle(np.exp(1j * np.diff(np.arctan2(chord[:, 1], chord[:, 0])))))
    return turn[turn > 0.01]


def test_an_interpolated_reference_is_found_with_the_numbers_of_its_construction():
    truth, key = on_grid_reference()
    found = truth_knots(truth)
    fixes = len(truth)
    knots = len(key) - 2  # every keyframe but the first and the last joins two lines
    assert (fixes - 1) % EVERY == 0
    # Every triple moves; those centred on an inner keyframe bend, all others are on a line.
    assert found.moving == fixes - 2
    assert found.share == pytest.approx(1 - knots / (fixes - 2), abs=1e-12)
    assert found.spacing == pytest.approx(EVERY * RATE, abs=1e-9)
    turned = turns_between(key)
    assert found.turns == turned.size >= 10
    assert found.largest_turn == pytest.approx(turned.max(), rel=1e-9)
    # The heading changes at every keyframe after the first (the last too: it ends the grid),
    # by the keyframes' own differences.
    assert found.heading_held == pytest.approx(1 - (len(key) - 1) / (fixes - 1), abs=1e-12)
    assert found.heading_interval == pytest.approx(EVERY * RATE, abs=1e-9)
    assert found.heading_step == pytest.approx(np.max(np.abs(np.diff(key[:, 2]))), rel=1e-9)
    assert found.interpolated


def test_keyframes_between_the_grids_fixes_are_found_at_their_own_times():
    """Keyframes 0.1 s off the grid (as a SLAM's are): each leaves the two fixes around it
    off both lines, and the knot lies halfway between them, 2.2 s from the next."""
    t, poses = drive(121.0)
    grid = RATE * np.arange(round(121.0 / RATE) + 1)
    key_t = np.concatenate(([0.0], np.arange(0.1 + EVERY * RATE, 120.0, EVERY * RATE), [grid[-1]]))
    truth, key = interpolated(t, poses, key_t, grid)
    found = truth_knots(truth)
    inner = len(key_t) - 2
    assert found.share == pytest.approx(1 - 2 * inner / (len(grid) - 2), abs=1e-12)
    assert found.spacing == pytest.approx(EVERY * RATE, abs=1e-9)
    assert found.interpolated


def test_the_keyframes_alone_and_the_dense_true_poses_are_no_interpolation():
    truth, key = on_grid_reference()
    alone = truth_knots(Truth(truth.t[::EVERY], key[:, :2], key[:, 2]))
    assert alone.share == 0.0 and not alone.interpolated
    t, poses = drive()
    dense = truth_knots(Truth(t[::20], poses[::20, :2], poses[::20, 2]))
    assert dense.share == 0.0 and not dense.interpolated


@pytest.mark.parametrize("rate, sigma", [(1.0, 1.0), (0.1, 0.02), (0.01, 0.0005)])
def test_a_measured_truth_is_no_interpolation(rate, sigma):
    """A GPS (1 Hz, 1 m; 10 Hz, 2 cm) and a motion capture (100 Hz, 0.5 mm) of the drive."""
    t, poses = drive()
    rng = np.random.default_rng(7)
    step = round(rate / FINE)
    xy = poses[::step, :2] + sigma * rng.standard_normal((len(t[::step]), 2))
    found = truth_knots(Truth(t[::step], xy, sigma=sigma))
    assert found.share < 0.01 and not found.interpolated
    assert check_truth_interpolated(Truth(t[::step], xy)) == []


def test_a_noise_free_straight_line_at_constant_speed_is_no_interpolation():
    """Every fix on one line, equally spaced: collinear throughout, but one run, no turn."""
    t = 0.05 * np.arange(2000)
    xy = np.column_stack((1.5 + 0.8 * np.cos(0.4) * t, -2.0 + 0.8 * np.sin(0.4) * t))
    found = truth_knots(Truth(t, xy, np.full(t.size, 0.4)))
    assert found.share == 1.0 and found.turns == 0
    assert not found.interpolated and interpolated_note(Truth(t, xy)) is None


def test_a_noise_free_square_driven_with_stops_at_its_corners_is_no_interpolation():
    """Straight legs at constant speed, each turn on the spot: the lines meet only where the
    truth stands."""
    period, rows = 0.05, []
    x, y, heading = 0.0, 0.0, 0.0
    for _ in range(8):
        for _ in range(100):  # 5 s at 0.4 m/s
            x, y = x + 0.4 * period * math.cos(heading), y + 0.4 * period * math.sin(heading)
            rows.append((x, y, heading))
        for _ in range(20):  # 1 s turning on the spot
            heading += math.pi / 2 / 20
            rows.append((x, y, heading))
    poses = np.array(rows)
    t = period * np.arange(len(poses))
    found = truth_knots(Truth(t, poses[:, :2], poses[:, 2]))
    assert found.share == pytest.approx(1.0) and found.turns == 0
    assert not found.interpolated


def test_a_noise_free_drive_written_with_three_decimals_is_not_taken_for_one():
    """Rounded to a millimetre, a slow drive at 100 Hz puts many triples on lines by chance,
    and turns between them by a millimetre's angle: too coarse to tell, so not said."""
    t, poses = drive(60.0)
    xy = np.round(poses[:, :2] * 0.2, 3)  # 0.1 m/s at 100 Hz: a millimetre a fix
    found = truth_knots(Truth(t, xy))
    assert found.resolution == pytest.approx(1e-3)
    assert not found.interpolated


def test_check_log_warns_with_the_numbers_and_what_to_do():
    truth, _ = on_grid_reference()
    t = FINE * np.arange(round(120.0 / FINE) + 1)
    v, w = speed_and_rate(t)
    log = OdometryLog(t, {"speed": v, "yaw_rate": w})
    found = truth_knots(truth)
    [finding] = [f for f in check_log(log, Unicycle(), truth) if f.check == "truth_interpolated"]
    assert finding.status == "warn" and finding.value == pytest.approx(found.share)
    assert "lie on straight lines between knots about 2.2 s apart" in finding.message
    assert f"({100 * found.share:.0f} % of its moving fixes" in finding.message
    assert "its heading holds for 2.2 s then steps" in finding.message
    assert finding.advice == INTERPOLATED_ADVICE and "longer than the knots' spacing" in finding.advice


@pytest.mark.slow
def test_optiodom_runs_are_no_interpolation(data_dir):
    """Real motion capture (20 Hz): no run comes near (its fixes are never exactly on a line)."""
    from odomkit.io.optiodom import read_experiment
    from odomkit.truth import truth_from_log

    for kind in ("diff", "tricyc"):
        for folder in sorted(glob.glob(str(data_dir / "optiodom" / kind / "*" / "*")))[::3]:
            for log in read_experiment(folder).runs:
                truth = truth_from_log(log)
                assert truth is not None
                found = truth_knots(truth)
                assert found.share < 0.01 and not found.interpolated, (folder, found)


# --- through the command line ------------------------------------------------------------------------


def _files(tmp_path, truth):
    """The drive's log (100 Hz speed and yaw rate), ``truth`` written in full, and a
    unicycle's robot file with noise."""
    t = FINE * np.arange(round(120.0 / FINE) + 1)
    v, w = speed_and_rate(t)
    log = tmp_path / "log.csv"
    np.savetxt(log, np.column_stack((t, v, w)), delimiter=",", header="t,speed,yaw_rate", comments="",
               fmt="%.17g")
    ref = tmp_path / "reference.txt"
    np.savetxt(ref, np.column_stack((truth.t, truth.xy, truth.theta)), header="t x y theta", comments="",
               fmt="%.17g")
    robot = tmp_path / "uni.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n\n[noise]\nalpha_ss = 0.001\npsd_gyro = 1e-5\n')
    return log, ref, robot


def test_check_names_an_interpolated_truth(run_cli, tmp_path):
    truth, _ = on_grid_reference()
    log, ref, robot = _files(tmp_path, truth)
    code, out, err = run_cli("check", log, "--robot", robot, "--truth", ref, "--json")
    report = json.loads(out)
    [finding] = [f for f in report["findings"] if f["check"] == "truth_interpolated"]
    assert finding["status"] == "warn" and "about 2.2 s apart" in finding["message"]
    assert INTERPOLATED_ADVICE in report["next"]


def test_evaluate_window_and_fit_noise_warn_once_per_log(run_cli, tmp_path):
    truth, _ = on_grid_reference()
    log, ref, robot = _files(tmp_path, truth)
    note = interpolated_note(truth)
    assert note is not None
    code, out, err = run_cli("evaluate", log, "--robot", robot, "--truth", ref, "--window", "10s",
                             "--window", "30s", "--json")
    assert code == 0, err
    said = [w for w in json.loads(out)["warnings"] if "interpolated between keyframes" in w]
    assert said == [f"{log}: {note}"]
    code, out, err = run_cli("fit-noise", "--robot", robot, "--log", log, "--truth", ref, "--window", "10s",
                             "--kinds", "white", "--out", tmp_path / "fitted.toml", "--json")
    assert code == 0, err
    said = [w for w in json.loads(out)["warnings"] if "interpolated between keyframes" in w]
    assert said == [f"{log}: {note}"]


def test_evaluate_of_a_measured_truth_says_nothing_of_knots(run_cli, tmp_path):
    t, poses = drive()
    dense = Truth(t[::20], poses[::20, :2], poses[::20, 2])
    log, ref, robot = _files(tmp_path, dense)
    code, out, err = run_cli("evaluate", log, "--robot", robot, "--truth", ref, "--window", "10s", "--json")
    assert code == 0, err
    assert not any("interpolated between keyframes" in w for w in json.loads(out)["warnings"])
    assert MIN_RUN_FIXES >= 3  # a chance line of noise is one triple: the runs' floor is above it
