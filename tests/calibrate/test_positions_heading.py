"""Calibration from truth fixes with the truth's heading compared too
(``calibrate_positions(heading_weight=W)``, ``odomkit calibrate --truth GT --heading-weight W``):
each fix adds W·wrap(θ(t) + θ₀ − θ_truth(t)) [m] beside its two position residuals.

The simulated robot is a commanded-velocity unicycle (the log holds the commanded speed and
yaw rate) whose true yaw rate is 0.93 × (commanded − 0.004) and whose true speed is 1.05 ×
the commanded one, less in its turns (a real base slows in a turn that its command does not
say): no constant-scale unicycle fits its path exactly. From positions alone its yaw-rate
scale comes out high (the turns' tighter curvature, ω/v, reads as more turning); the heading
changes by ∫ω dt whatever the speed, and pins it."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from odomkit.angles import wrap_angle
from odomkit.calibrate.positions import MAX_TIME_OFFSET, _Problem, _runs_with_truth, calibrate_positions
from odomkit.calibrate.residuals import calibration_model
from odomkit.errors import InputError
from odomkit.integrate import dead_reckon
from odomkit.log import OdometryLog
from odomkit.robot import Car, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth

YAW_RATE_SCALE, YAW_RATE_BIAS, C_SCALE = 0.93, 0.004, 1.05
DT = 0.05


def drive(seed: int = 0, duration: float = 600.0, slow: float = 1.2, heading: bool = True
          ) -> tuple[OdometryLog, Truth]:
    """The commanded (speed, yaw rate) of a unicycle turning both ways at up to 0.5 rad/s
    (a new yaw-rate knot every 4 s), its rows every 0.05 s, and a motion capture's fixes
    every 0.1 s stamped 0.037 s after a row (1 mm per axis, 0.002 rad of heading noise; no
    heading with ``heading`` False). The true speed is 1.05 × the commanded one × (1 − ``slow``
    × |true yaw rate|), integrated exactly (arcs)."""
    rng = np.random.default_rng(seed)
    t = DT * np.arange(int(round(duration / DT)) + 1)
    knots = rng.uniform(-0.5, 0.5, int(duration / 4) + 2)
    w_cmd = np.interp(t, 4.0 * np.arange(knots.size), knots)
    v_cmd = 0.2 + 0.05 * np.sin(t / 17.0)
    w = YAW_RATE_SCALE * (w_cmd - YAW_RATE_BIAS)
    v = C_SCALE * v_cmd * (1.0 - slow * np.abs(w))
    # Each row's (v, w) held over the step after it, integrated as constant-curvature arcs.
    poses = dead_reckon(v[:-1] * DT, w[:-1] * DT, (0.0, 0.0, 0.0), "exact")
    fix_t = np.arange(0.037, t[-1], 0.1)
    xy = np.column_stack([np.interp(fix_t, t, poses[:, k]) for k in (0, 1)]) + rng.normal(0.0, 0.001,
                                                                                           (fix_t.size, 2))
    theta = np.interp(fix_t, t, poses[:, 2]) + rng.normal(0.0, 0.002, fix_t.size) if heading else None
    return (OdometryLog(t, {"speed": v_cmd, "yaw_rate": w_cmd}, source=f"drive{seed}"),
            Truth(fix_t, xy, theta, 0.001, f"mocap{seed}"))


def quiet(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate_positions(*args, **kwargs)


def _problem(log: OdometryLog, truth: Truth, weight: float) -> _Problem:
    """The fit's internal problem over the whole run, every parameter free, δ fitted."""
    model = calibration_model(Unicycle(), [log])
    free = np.arange(len(model.names), dtype=np.intp)
    runs = _runs_with_truth([log], [truth], MAX_TIME_OFFSET)
    return _Problem(model, runs, [log], free, "exact", True, weight)


def test_the_heading_rows_are_the_dead_reckoned_heading_against_the_truth_and_their_jacobian_its_derivative(
        numeric_jacobian):
    """q = (c_scale, yaw_rate_bias, yaw_rate_scale, δ, x₀, y₀, θ₀), W = 0.7 m/rad. Every third
    residual is 0.7·wrap(θ − θ_truth) with θ the library's own dead reckoning
    (:func:`odomkit.track.dead_reckon_log`) from the start pose at the log time of each fix
    (its stamp − δ), interpolated linearly between rows; the positions are the same track's.
    At δ = 0.262 every fix falls 0.025 s from the nearest row, so the δ column's central
    difference (step 1e-4 s) stays inside each fix's segment, where the residuals are linear
    in δ: exact to round-off. The other columns are smooth (step 1e-6)."""
    log, truth = drive(3, duration=60.0)
    problem = _problem(log, truth, 0.7)
    delta = 0.262
    q = np.array([1.02, 0.003, 0.95, delta, 0.3, -0.2, 0.4])
    res, jac = problem.residuals_and_jacobian(q)
    run = problem.runs[0]
    assert run.theta is not None and res.size == 3 * run.t.size and jac.shape == (res.size, q.size)
    # The residuals against an independent dead reckoning.
    robot = Unicycle(c_scale=1.02, yaw_rate_bias=0.003, yaw_rate_scale=0.95)
    track = dead_reckon_log(log, robot, pose0=(0.3, -0.2, 0.4)).poses
    at = [np.interp(run.t - delta, log.t, track[:, k]) for k in range(3)]
    np.testing.assert_allclose(res[0::3], at[0] - run.xy[:, 0], atol=1e-12)
    np.testing.assert_allclose(res[1::3], at[1] - run.xy[:, 1], atol=1e-12)
    np.testing.assert_allclose(res[2::3], 0.7 * wrap_angle(at[2] - run.theta), atol=1e-12)
    # The Jacobian's heading rows (and the rest) against central differences.
    k = 3  # the δ column

    def with_delta(d):
        x = q.copy()
        x[k] = d[0]
        return problem.residuals_and_jacobian(x)[0]

    gap = np.abs(((run.t - delta) / DT) - np.round((run.t - delta) / DT)) * DT
    assert gap.min() > 0.02  # no fix near a row at δ
    fd = numeric_jacobian(with_delta, [delta], eps=1e-4)[:, 0]
    np.testing.assert_allclose(jac[:, k], fd, rtol=1e-7, atol=1e-9)
    assert np.abs(jac[2::3, k]).max() > 0.1  # the heading's rate is in the δ column
    full = numeric_jacobian(lambda x: problem.residuals_and_jacobian(x)[0], q, eps=1e-6)
    for j in (0, 1, 2, 4, 5, 6):
        scale = np.abs(full[:, j]).max()
        np.testing.assert_allclose(jac[:, j], full[:, j], rtol=1e-5, atol=1e-6 * scale, err_msg=f"column {j}")
    # the start heading moves every heading residual by W, the start position none
    np.testing.assert_array_equal(jac[2::3, 6], 0.7)
    np.testing.assert_array_equal(jac[2::3, 4:6], 0.0)


def test_the_start_pose_eliminated_is_the_optimum_of_every_residual(numeric_jacobian):
    """The windows' variable projection: for the shared g = (parameters, δ) each run's start
    pose is eliminated, and the reduced Jacobian is the shared columns made orthogonal to the
    start pose's (Frisch–Waugh–Lovell). That is right only where the start pose is the optimum
    of all the residuals, headings included: there the start-pose columns are orthogonal to
    the residuals and the reduced cost's gradient is Jᵀr. Checked against central differences
    of the reduced cost (to 1e-6, relative); from the positions' alignment alone (what the
    start was without the heading) Jᵀr misses it by 1e-3 or more (W = 5 m/rad)."""
    log, truth = drive(4, duration=60.0)
    problem = _problem(log, truth, 5.0)
    g = np.array([1.02, 0.003, 0.95, 0.262])
    res, jac, starts, _ = problem.reduced(g)
    _, full = problem.residuals_and_jacobian(np.concatenate([g, starts[0]]))
    # the start-pose columns orthogonal to the residuals (cosines under 1e-9)
    cosines = (full[:, 4:].T @ res) / (np.linalg.norm(full[:, 4:], axis=0) * np.linalg.norm(res))
    np.testing.assert_array_less(np.abs(cosines), 1e-9)

    def cost(x):
        return 0.5 * float(np.sum(problem.reduced(np.asarray(x))[0] ** 2))

    gradient = numeric_jacobian(lambda x: [cost(x)], g, eps=1e-6)[0]
    np.testing.assert_allclose(jac.T @ res, gradient, rtol=1e-6)
    aligned = _problem(log, truth, 0.0).reduced(g)[2]
    res_aligned, jac_aligned, _, _ = problem.reduced(g, aligned)
    assert np.max(np.abs(jac_aligned.T @ res_aligned - gradient) / np.abs(gradient)) > 1e-3


def test_a_robot_that_slows_in_its_turns_gets_its_yaw_rate_scale_from_the_heading():
    """Ten minutes in 60 s windows. From positions alone the yaw-rate scale is 0.96, more than
    3 of its between-window standard errors above the simulation's 0.93 (and 0.03 off); with
    the heading compared (W = 100 m/rad: the positions' misfit, centimetres, against the
    heading's 2 mrad noise) it lies within 3 of them, and less than a tenth as far."""
    log, truth = drive(2)
    positions = quiet([log], [truth], Unicycle(), window="60s")
    heading = quiet([log], [truth], Unicycle(), window="60s", heading_weight=100.0)
    se_positions, se_heading = positions.std_errors_between_runs, heading.std_errors_between_runs
    assert se_positions is not None and se_heading is not None
    bias = positions.values[2] - YAW_RATE_SCALE
    assert bias > 3 * se_positions[2] and bias > 0.02, (positions.values, se_positions)
    off = heading.values[2] - YAW_RATE_SCALE
    assert abs(off) < 3 * se_heading[2] and abs(off) < 0.1 * bias, (heading.values, se_heading)
    note = next(n for n in heading.notes if "heading compared" in n)
    assert "weighted 100 m/rad" in note and "rad in heading" in note
    # the drift checks and the fit's σ̂² take every residual as W·rad beside the metres
    assert heading.n_residuals == 3 * positions.n_residuals // 2


def test_windows_given_as_times_fit_as_the_same_windows_given_as_runs_with_the_heading():
    """The windowed fit eliminates each window's start pose by the positions' alignment
    refined with the heading (Gauss–Newton); a fit of whole runs fits the start poses with
    the parameters (a dense Jacobian). The same three windows given both ways agree: the
    values to 1e-6, the standard errors to 1e-4 (relative)."""
    log, truth = drive(5, duration=180.0)
    edges = [(0.0, 60.0), (60.0, 120.0), (120.0, 179.5)]
    windowed = quiet([log], [truth], Unicycle(), windows=[edges], heading_weight=3.0)
    pieces, fixes = [], []
    for j, (a, b) in enumerate(edges):
        rows = np.flatnonzero((log.t >= a - 1e-9) & (log.t <= b + 1e-9))  # the rows a..b, as cut
        pieces.append(log.rows(int(rows[0]), int(rows[-1]) + 1))
        last = j == len(edges) - 1
        inside = (truth.t >= a) & ((truth.t <= b) if last else (truth.t < b))
        assert truth.theta is not None
        fixes.append(Truth(truth.t[inside], truth.xy[inside], truth.theta[inside], truth.sigma))
    joint = quiet(pieces, fixes, Unicycle(), heading_weight=3.0)
    assert windowed.n_windows == 3 and joint.n_windows is None
    np.testing.assert_allclose(windowed.values, joint.values, rtol=1e-6)
    np.testing.assert_allclose(windowed.std_errors, joint.std_errors, rtol=1e-4)
    assert windowed.n_residuals == joint.n_residuals


def _write(tmp_path, log, truth):
    """The log as t,speed,yaw_rate, the truth as t,x,y (and theta where it has one), a
    nominal unicycle robot file."""
    channels = [log.t, log.channels["speed"], log.channels["yaw_rate"]]
    np.savetxt(tmp_path / "log.csv", np.column_stack(channels), delimiter=",", header="t,speed,yaw_rate",
               comments="")
    cols, header = [truth.t, truth.xy], "t,x,y"
    if truth.theta is not None:
        cols.append(truth.theta)
        header += ",theta"
    np.savetxt(tmp_path / "gt.csv", np.column_stack(cols), delimiter=",", header=header, comments="")
    (tmp_path / "uni.toml").write_text('[robot]\ntype = "unicycle"\n')
    return tmp_path / "log.csv", tmp_path / "gt.csv", tmp_path / "uni.toml"


def test_a_heading_weight_with_a_position_only_truth_is_one_line(run_cli, tmp_path):
    log, truth = drive(1, duration=120.0, heading=False)
    log_path, gt, robot = _write(tmp_path, log, truth)
    code, out, err = run_cli("calibrate", log_path, "--robot", robot, "--truth", gt, "--heading-weight", "1")
    assert code == 2 and out == "" and err.strip().count("\n") == 0 and "Traceback" not in err, err
    assert "gt.csv: the truth has positions only, no heading to compare" in err
    with pytest.raises(InputError, match="mocap1: the truth has positions only, no heading to compare"):
        calibrate_positions([log], [truth], Unicycle(), heading_weight=1.0)
    # without the weight it calibrates from the positions, as before
    code, _, err = run_cli("calibrate", log_path, "--robot", robot, "--truth", gt, "--window", "60s")
    assert code == 0, err


def test_the_command_compares_a_truth_files_heading(run_cli, tmp_path):
    """--truth t,x,y,theta --window 60s --heading-weight 100: the yaw-rate scale within 3 of
    its between-window standard errors of 0.93 (from positions alone more than 3 above), and
    the note says the heading was compared; --from is still refused."""
    log, truth = drive(2)
    log_path, gt, robot = _write(tmp_path, log, truth)
    args = ["calibrate", log_path, "--robot", robot, "--truth", gt, "--truth-time-offset", "0",
            "--window", "60s", "--json"]
    code, out, err = run_cli(*args, "--heading-weight", "100")
    assert code == 0, err
    summary = json.loads(out)
    off = summary["parameters"]["yaw_rate_scale"] - YAW_RATE_SCALE
    assert abs(off) < 3 * summary["std_errors_between_runs"]["yaw_rate_scale"], summary
    assert any("heading compared at every fix, weighted 100 m/rad" in n for n in summary["notes"])
    code, out, err = run_cli(*args)
    assert code == 0, err
    summary = json.loads(out)
    off = summary["parameters"]["yaw_rate_scale"] - YAW_RATE_SCALE
    assert off > 3 * summary["std_errors_between_runs"]["yaw_rate_scale"], summary
    code, _, err = run_cli(*args, "--heading-weight", "1", "--from", "trajectory")
    assert code == 2 and "--from does not apply with --truth" in err


def test_a_heading_weight_of_zero_is_the_fit_before_the_heading_was_compared(car_gps_drive):
    """W = 0 (the default) leaves every result as it was. The numbers are those the code gave
    before the heading could be compared, on the car and 1 m GPS the stability tests share
    (its truth given a heading, which that code did not read), fitted in 60 s windows and
    whole with the clock offset; recorded to the last bit, held to 1e-12 (another BLAS may
    round the least squares differently). A position-only truth and an omitted weight give
    the same to the bit."""
    log, fixes, poses = car_gps_drive()
    truth = Truth(fixes.t, fixes.xy, np.interp(fixes.t, log.t, poses[:, 2]), fixes.sigma)
    recorded = {
        "60s": ([0.9997178696380717, -3.4628118725219506e-06, 2.698421207716717],
                [0.00034160425246802063, 1.1188263716356851e-05, 0.0012730074372660437],
                [0.00042845211743138304, 1.1296937695222693e-05, 0.001396135342480152],
                0.02934226270484674, 0.9508819085211225),
        None: ([1.00001907675071, -3.014581588805887e-07, 2.7000807548402435],
               [7.631100432971678e-05, 4.3649834832254026e-07, 0.0002505778833266443],
               None, 0.028483742046794554, 0.9617282427193783),
    }
    for window, (values, std, between, offset, variance) in recorded.items():
        cal = quiet([log], [truth], Car(2.65), window=window, fit_time_offset=True, heading_weight=0.0)
        np.testing.assert_allclose(cal.values, values, rtol=1e-12)
        np.testing.assert_allclose(cal.std_errors, std, rtol=1e-12)
        if between is None:
            assert cal.std_errors_between_runs is None
        else:
            assert cal.std_errors_between_runs is not None
            np.testing.assert_allclose(cal.std_errors_between_runs, between, rtol=1e-12)
        assert cal.time_offset == pytest.approx(offset, rel=1e-12)
        assert cal.residual_variance == pytest.approx(variance, rel=1e-12) and cal.n_residuals == 1192
        assert any("heading is not compared" in n for n in cal.notes)
        for other in (quiet([log], [truth], Car(2.65), window=window, fit_time_offset=True),
                      quiet([log], [fixes], Car(2.65), window=window, fit_time_offset=True,
                            heading_weight=0.0)):
            np.testing.assert_array_equal(other.values, cal.values)
            np.testing.assert_array_equal(other.cov, cal.cov)
            assert other.residual_variance == cal.residual_variance and other.time_offset == cal.time_offset
