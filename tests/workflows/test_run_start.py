"""Where a run starts from truth that starts with the log (a GPS switched on with the logger),
and what the NEES of rows with a singular covariance is worth (user study 18).

A simulated car (bicycle model) with a 1 Hz position-only GPS whose first fix is at the log's
first row: at the first rows its fixes lie on one side only, too few for a heading. The row
every command starts from is checked against an independent scan of every row with
:func:`odomkit.truth.start_heading` (the truth module's own verdict on where a heading can
be had), and the track after its start against a track started there by hand.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

L = 2.7
COLUMNS = "t=t,speed=speed,steer=steer"


def _drive(folder, *, gps_from=0.0, heading=False, seconds=60.0, dt=0.02, still=False, seed=3):
    """A car's log (``t,speed,steer``), its GPS (fixes a second from ``gps_from`` [s], 0.3 m
    noise; with ``heading`` a ``theta`` column too; ``still``: every fix at one place, a
    receiver stuck) and its robot file. Returns (robot, log, gps)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(seconds / dt)) + 1) * dt
    v = 8.0 + 2.0 * np.sin(t / 13.0)
    steer = 0.05 * np.sin(t / 7.0) + 0.03 * np.sin(t / 3.0 + 1.0)
    theta = 0.3 + np.concatenate(([0.0], np.cumsum(v[:-1] * np.tan(steer[:-1]) / L * dt)))
    x = np.concatenate(([0.0], np.cumsum(v[:-1] * np.cos(theta[:-1]) * dt)))
    y = np.concatenate(([0.0], np.cumsum(v[:-1] * np.sin(theta[:-1]) * dt)))
    log = folder / "car.csv"
    np.savetxt(log, np.column_stack((t, v + rng.normal(0, 0.05, t.size), steer)), delimiter=",",
               header="t,speed,steer", comments="", fmt="%.5f")
    fixes = np.arange(gps_from, t[-1], 1.0)
    xy = np.column_stack((np.interp(fixes, t, x), np.interp(fixes, t, y)))
    xy += rng.normal(0, 0.3, xy.shape)
    if still:
        xy[:] = xy[0]
    cols, header = [fixes, xy], "t,x,y"
    if heading:
        cols, header = [*cols, np.interp(fixes, t, theta)], "t,x,y,theta"
    gps = folder / "gps.csv"
    np.savetxt(gps, np.column_stack(cols), delimiter=",", header=header, comments="", fmt="%.10g")
    robot = folder / "car.toml"
    robot.write_text(f'[robot]\ntype = "car"\nwheel_base = {L}\n\n'
                     "[noise]\nsigma_speed = 0.05\nsigma_steer = 0.002\nsigma_dt = 0.0\n")
    return robot, log, gps


def _loaded(robot_path, log_path, gps):
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows.logs import LogOptions, load_log
    from odomkit.workflows.truth import TruthOptions, load_truth

    robot, _ = read_robot(robot_path)
    log = load_log(log_path, robot, LogOptions(columns=COLUMNS))
    return robot, log, load_truth(TruthOptions(gps), log)


def _first_heading_row(robot, log, truth):
    """The first row with valid truth where the truth gives a start heading, found by trying
    every row (the commands try rows 0.5 s apart, then look back), and the odometry's own
    path from the origin that the heading is aligned to."""
    from odomkit.integrate import dead_reckon
    from odomkit.kinematics import body_steps
    from odomkit.truth import start_heading, truth_at

    steps = body_steps(robot, log)
    own = dead_reckon(steps.dd, steps.dtheta, np.zeros(3))
    for row in np.flatnonzero(truth_at(truth, log.t).valid):
        if start_heading(truth, float(log.t[row]), log.t, own) is not None:
            return int(row), own
    raise AssertionError("no row gives a heading")


def _json(run_cli, *args):
    code, out, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(out)


# ------------------------------------------------------------------ fit-noise, evaluate


def test_the_whole_log_window_starts_where_the_position_only_truth_first_gives_a_heading(run_cli, tmp_path):
    from odomkit.calibrate.fit_noise import models_to_fit
    from odomkit.truth import truth_at
    from odomkit.window_errors import log_window_basis

    robot_path, log_path, gps = _drive(tmp_path)
    robot, log, truth = _loaded(robot_path, log_path, gps)
    first, _ = _first_heading_row(robot, log, truth)
    assert first > 0  # the GPS starts with the log: no heading at its first row
    models, _ = models_to_fit(robot, (), ("white", "bias"))
    basis, skipped = log_window_basis(log, robot, models, truth, [None])
    assert basis is not None and skipped == 0 and basis.dropped == 0
    last = int(np.flatnonzero(truth_at(truth, log.t).valid)[-1])  # the last fix's row
    assert [(w.start, w.end) for w in basis.windows] == [(first, last)]
    assert len(basis.notes) == 1 and f"starts at {log.t[first]:.6g} s" in basis.notes[0]
    assert f"the {first} row(s) before it" in basis.notes[0]
    # fit-noise without --window: one window per log, from that row (it failed here before
    # for want of a start heading); one window's end gives 2 numbers, too few to fit the car's
    # variances, and that is now what it says
    code, _, err = run_cli("fit-noise", "--robot", robot_path, "--log", log_path, "--truth", gps,
                           "--columns", COLUMNS, "--out", tmp_path / "fit.toml")
    assert code == 2 and "1 window(s) give 2 numbers" in err and not (tmp_path / "fit.toml").exists()
    # evaluate's whole run and its window start at the same row (its window was dropped before)
    got = _json(run_cli, "evaluate", log_path, "--robot", robot_path, "--truth", gps,
                "--columns", COLUMNS)
    assert got["windows"] == 1 and got["rows_skipped"] == first + (len(log) - 1 - last)  # and after the fixes
    assert any(f"starts at {log.t[first]:.6g} s" in w for w in got["warnings"])


def test_truth_that_gives_a_heading_nowhere_is_named_as_the_cause(run_cli, tmp_path):
    robot_path, log_path, gps = _drive(tmp_path, still=True)  # the receiver never moves
    code, _, err = run_cli("fit-noise", "--robot", robot_path, "--log", log_path, "--truth", gps,
                           "--columns", COLUMNS, "--out", tmp_path / "fit.toml")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "no start for the whole-log window" in err and "give none at any of the log's rows" in err
    code, _, err = run_cli("track", log_path, "--robot", robot_path, "--truth", gps, "--columns", COLUMNS)
    assert code == 2 and "give none at any of the log's rows" in err and "give --initial-pose" in err


def test_run_start_finds_a_first_heading_between_the_rows_it_tries():
    """Fixes a second apart with one late (4.3 s): five fixes lie within the 6 s heading fit
    from 1.3 s on, between the rows tried 0.5 s apart (1.0, 1.5 s); the look back finds it."""
    from odomkit.truth import Truth, start_heading, truth_at
    from odomkit.windows import START_STRIDE, run_start

    fixes = np.concatenate((np.arange(4.0), np.arange(4.3, 20.0, 1.0)))
    heading = 0.7
    truth = Truth(fixes, np.column_stack((np.cos(heading) * fixes, np.sin(heading) * fixes)))
    t = np.arange(0.0, 20.0, 0.01)
    own = np.column_stack((t, np.zeros_like(t), np.zeros_like(t)))  # the same line in its own frame
    valid = truth_at(truth, t).valid
    every = [r for r in np.flatnonzero(valid) if start_heading(truth, float(t[r]), t, own) is not None]
    row, pose, cov = run_start(t, truth, valid, own)
    assert row == every[0] and t[row] == pytest.approx(1.3)
    assert (t[row] - t[0]) % START_STRIDE > 0.01  # not a row the stride tries
    assert pose[:2] == pytest.approx([np.cos(heading) * 1.3, np.sin(heading) * 1.3], abs=1e-12)
    assert pose[2] == pytest.approx(heading, abs=1e-9) and cov[2, 2] < 1e-12


# ------------------------------------------------------------------ track


def _table(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def test_the_track_starts_where_the_position_only_truth_first_gives_a_heading(run_cli, tmp_path):
    from odomkit.truth import start_pose

    robot_path, log_path, gps = _drive(tmp_path)
    robot, log, truth = _loaded(robot_path, log_path, gps)
    first, own = _first_heading_row(robot, log, truth)
    args = ("--robot", robot_path, "--truth", gps, "--columns", COLUMNS)
    got = _json(run_cli, "track", log_path, *args, "--out", tmp_path / "a.csv")
    assert got["samples"] == len(log) - first
    notes = [w for w in got["warnings"] if "the track starts at" in w]
    assert len(notes) == 1 and f"starts at {log.t[first]:.6g} s" in notes[0]
    assert f"the {first} row(s) before it ({log.t[first]:.4g} s)" in notes[0]
    a = _table(tmp_path / "a.csv")
    assert a["t"][0] == log.t[first] and a.size == len(log) - first
    # The same track as one started by hand at that row from the truth's pose there.
    pose, cov = start_pose(truth, float(log.t[first]), odometry=(log.t, own))
    lines = log_path.read_text().splitlines(keepends=True)
    (tmp_path / "b_log.csv").write_text(lines[0] + "".join(lines[1 + first:]))
    by_hand = _json(run_cli, "track", tmp_path / "b_log.csv", "--robot", robot_path, "--columns", COLUMNS,
                    "--initial-pose", ",".join(repr(float(v)) for v in pose),
                    "--initial-cov", ",".join(repr(float(v)) for v in cov.ravel()),
                    "--out", tmp_path / "b.csv")
    b = _table(tmp_path / "b.csv")
    for name in ("t", "x", "y", "theta", "cov_xx", "cov_xy", "cov_yy", "cov_thetatheta"):
        np.testing.assert_allclose(a[name], b[name], rtol=1e-12, atol=1e-15, err_msg=name)
    assert got["pose"] == pytest.approx(by_hand["pose"], abs=1e-12)
    # final_position_error keeps its meaning: the last row inside the truth, against the fixes
    fixes = np.loadtxt(gps, delimiter=",", skiprows=1)
    inside = a["t"] <= fixes[-1, 0]
    err = np.hypot(a["x"] - np.interp(a["t"], fixes[:, 0], fixes[:, 1]),
                   a["y"] - np.interp(a["t"], fixes[:, 0], fixes[:, 2]))[inside]
    assert got["final_position_error"] == pytest.approx(err[-1], rel=1e-9)
    assert got["max_position_error"] == pytest.approx(err.max(), rel=1e-9)
    # --initial-pose given: from the first row, as before, without a note
    given = _json(run_cli, "track", log_path, *args, "--initial-pose", "1,2,0.3", "--out", tmp_path / "c.csv")
    c = _table(tmp_path / "c.csv")
    assert given["samples"] == len(log) and c["t"][0] == log.t[0]
    assert (c["x"][0], c["y"][0], c["theta"][0]) == (1.0, 2.0, 0.3)
    assert not any("starts at" in w for w in given.get("warnings", []))


def test_the_track_starts_at_the_first_row_inside_a_truth_that_starts_late(run_cli, tmp_path):
    robot_path, log_path, gps = _drive(tmp_path, gps_from=2.01, heading=True)
    t = np.loadtxt(log_path, delimiter=",", skiprows=1)[:, 0]
    fixes = np.loadtxt(gps, delimiter=",", skiprows=1)
    first = int(np.searchsorted(t, fixes[0, 0]))  # the first log row at or after the first fix
    got = _json(run_cli, "track", log_path, "--robot", robot_path, "--truth", gps, "--columns", COLUMNS,
                "--out", tmp_path / "a.csv")
    a = _table(tmp_path / "a.csv")
    assert a["t"][0] == t[first] and got["samples"] == t.size - first
    want = [np.interp(t[first], fixes[:, 0], fixes[:, k]) for k in (1, 2, 3)]
    np.testing.assert_allclose([a["x"][0], a["y"][0], a["theta"][0]], want, atol=1e-12)
    assert any("the first log time inside the truth" in w and f"the {first} row(s)" in w
               for w in got["warnings"])


# ------------------------------------------------------------------ evaluate: singular covariances


def _track_file(path, n=400, zero=3, near=7, sigma=0.05, zero_error=False, seed=5):
    """A track along x whose estimate is exact and whose gt_* columns carry ``sigma`` noise:
    its first ``zero`` rows have zero covariance, the next ``near`` a covariance with
    standard deviations 10⁶ apart (variances 1e-12 and 1 m²), the rest ``sigma``² I (honest).
    Returns (errors (n, 2), variances (n, 2))."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    est = np.column_stack((t, np.zeros(n), np.zeros(n)))
    noise = rng.normal(0.0, sigma, (n, 2))
    if zero_error:
        noise[:zero] = 0.0
    var = np.full((n, 2), sigma**2)
    var[:zero] = 0.0
    var[zero:zero + near] = (1e-12, 1.0)
    cov = np.zeros((n, 6))  # xx, xy, xθ, yy, yθ, θθ
    cov[:, 0], cov[:, 3], cov[:, 5] = var[:, 0], var[:, 1], 1e-4
    gt = np.column_stack((est[:, :2] + noise, np.zeros(n)))
    header = "t,x,y,theta,cov_xx,cov_xy,cov_xtheta,cov_yy,cov_ytheta,cov_thetatheta,gt_x,gt_y,gt_theta"
    np.savetxt(path, np.column_stack((t, est, cov, gt)), delimiter=",", header=header, comments="",
               fmt="%.17g")
    return -noise, var


def test_rows_with_a_singular_covariance_are_named_and_counted(run_cli, tmp_path):
    errors, var = _track_file(tmp_path / "track.csv")
    got = _json(run_cli, "evaluate", tmp_path / "track.csv")
    notes = [w for w in got["warnings"] if "singular" in w]
    assert len(notes) == 1
    assert "3 of 400 rows have a singular covariance but an error" in notes[0]
    assert "% of the summed NEES comes from 7 of 400 rows whose covariance is nearly singular" in notes[0]
    assert "--truth-sigma" in notes[0] and "--initial-cov" in notes[0]
    # ATE untouched; the NEES is that of every row with a regular covariance, by hand
    assert got["ate_rmse"] == pytest.approx(np.sqrt(np.mean(np.sum(errors**2, axis=1))), rel=1e-12)
    regular = slice(3, None)
    by_hand = np.sum(errors[regular] ** 2 / var[regular], axis=1)
    assert got["nees_position_mean"] == pytest.approx(by_hand.mean(), rel=1e-9)
    # the truth's own noise given: every row is regular, and nothing to say
    fair = _json(run_cli, "evaluate", tmp_path / "track.csv", "--truth-sigma", "0.05")
    assert not any("singular" in w for w in fair.get("warnings", []))
    assert fair["ate_rmse"] == got["ate_rmse"]


def test_a_track_that_starts_exactly_on_its_truth_is_flagged_only_where_it_errs(run_cli, tmp_path):
    # zero covariance where the error is zero too (a track compared with the truth it started
    # from), and no nearly singular rows: the NEES loses nothing
    _track_file(tmp_path / "track.csv", near=0, zero_error=True)
    got = _json(run_cli, "evaluate", tmp_path / "track.csv")
    assert not any("singular" in w for w in got.get("warnings", []))
    # the same with the truth's noise in those rows: their NEES would be infinite, and is counted
    _track_file(tmp_path / "off.csv", near=0)
    notes = [w for w in _json(run_cli, "evaluate", tmp_path / "off.csv")["warnings"] if "singular" in w]
    assert len(notes) == 1 and "3 of 400 rows have a singular covariance but an error" in notes[0]
    assert "nearly singular" not in notes[0]
