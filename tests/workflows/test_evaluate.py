"""``odomkit evaluate`` workflows: metrics against a direct computation, evo, known noise."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2

from odomkit.errors import InputError
from odomkit.io.trackio import read_track_csv
from odomkit.workflows.evaluate import evaluate_logs, evaluate_tracks
from odomkit.workflows.logs import LogOptions
from odomkit.workflows.track import run_track
from odomkit.workflows.truth import TruthOptions

DATA = Path(__file__).resolve().parents[2] / "src" / "odomkit" / "data"
RUN = DATA / "230620202042_run-01.csv"
ROBOT = DATA / "optiodom_diff.toml"
SIM_COLUMNS = "t=t,dist_left=L,dist_right=R"


def _track_csv(path, t, poses, cov=None):
    cols = "t,x,y,theta,cov_xx,cov_xy,cov_xtheta,cov_yy,cov_ytheta,cov_thetatheta"
    rows = []
    for i in range(t.size):
        c = cov[i] if cov is not None else np.full((3, 3), np.nan)
        cells = [t[i], *poses[i], c[0, 0], c[0, 1], c[0, 2], c[1, 1], c[1, 2], c[2, 2]]
        rows.append(",".join("" if np.isnan(v) else repr(float(v)) for v in cells))
    path.write_text(cols + "\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture()
def synthetic(tmp_path):
    """A curving track at 20 Hz and its truth on another clock (50 Hz, offset, one gap)."""
    rng = np.random.default_rng(8)
    truth_t = np.arange(-0.5, 31.0, 0.02)
    truth_t = truth_t[(truth_t < 12.0) | (truth_t > 13.2)]  # a 1.2 s gap

    def true_pose(t):
        return np.column_stack((0.5 * t, np.sin(0.2 * t), np.arctan2(0.2 * np.cos(0.2 * t), 0.5)))

    gt = true_pose(truth_t)
    gt_path = tmp_path / "gt.csv"
    np.savetxt(gt_path, np.column_stack((truth_t, gt)), delimiter=",", header="t,x,y,theta",
               comments="")
    t = np.arange(0.0, 32.0, 0.05)  # runs past the truth's end
    est = true_pose(t) + np.cumsum(rng.normal(0, 0.003, (t.size, 3)), axis=0)
    A = rng.normal(0, 0.02, (t.size, 3, 3))
    cov = A @ A.transpose(0, 2, 1) + 1e-4 * np.eye(3)
    cov[0] = 0.0  # the start: a singular covariance, left out of NEES
    track = _track_csv(tmp_path / "track.csv", t, est, cov)
    return track, gt_path, t, est, cov, truth_t, gt


def _direct_keep(t, truth_t, max_gap=0.5):
    """Rows inside the truth's span and not strictly inside a gap longer than max_gap."""
    i = int(np.flatnonzero(np.diff(truth_t) > max_gap)[0])
    return (t >= truth_t[0]) & (t <= truth_t[-1]) & ~((t > truth_t[i]) & (t < truth_t[i + 1]))


def test_metrics_match_a_direct_numpy_computation(synthetic):
    track, gt_path, t, est, cov, truth_t, gt = synthetic
    out = evaluate_tracks([track], [TruthOptions(gt_path, max_gap=0.5)], rpe_distances=(1.0, 2.5))
    keep = _direct_keep(t, truth_t)
    ref = np.column_stack([np.interp(t[keep], truth_t, gt[:, k]) for k in range(3)])
    e = est[keep, :2] - ref[:, :2]
    d = np.linalg.norm(e, axis=1)
    assert out["rows_evaluated"] == keep.sum() and out["rows_skipped"] == (~keep).sum()
    assert out["ate_rmse"] == pytest.approx(np.sqrt(np.mean(d**2)), rel=1e-12)
    assert out["final_position_error"] == pytest.approx(d[-1], rel=1e-12)
    assert out["max_position_error"] == pytest.approx(d.max(), rel=1e-12)
    travel = np.sum(np.linalg.norm(np.diff(ref[:, :2], axis=0), axis=1))
    assert out["drift_percent"] == pytest.approx(100 * d[-1] / travel, rel=1e-12)
    P = cov[keep][:, :2, :2]
    regular = np.linalg.det(P) > 0
    q = np.array([ei @ np.linalg.inv(Pi) @ ei for ei, Pi in zip(e[regular], P[regular], strict=True)])
    assert out["nees_position_mean"] == pytest.approx(q.mean(), rel=1e-9)
    assert out["nees_position_median"] == pytest.approx(np.median(q), rel=1e-9)
    n = q.size
    assert out["nees_bounds"] == pytest.approx([chi2.ppf(0.025, 2 * n) / n, chi2.ppf(0.975, 2 * n) / n])
    for level in ("0.5", "0.9", "0.95", "0.99"):
        assert out["coverage"][level] == pytest.approx(np.mean(q <= chi2.ppf(float(level), 2)))
    assert out["inside_95_fraction"] == out["coverage"]["0.95"]
    assert out["windows"] == 0 and out["per_log"][0]["log"] == str(track)
    assert set(out["rpe"]) == {"1", "2.5"}


def test_se2_alignment_minimises_the_ate(synthetic):
    from scipy.optimize import minimize_scalar

    track, gt_path, t, est, _, truth_t, gt = synthetic
    opts = [TruthOptions(gt_path)]
    ate = {a: evaluate_tracks([track], opts, align=a)["ate_rmse"] for a in ("none", "start")}
    with pytest.warns(UserWarning, match="do not test the covariance"):
        ate["se2"] = evaluate_tracks([track], opts, align="se2")["ate_rmse"]
    keep = _direct_keep(t, truth_t)
    ref = np.column_stack([np.interp(t[keep], truth_t, gt[:, k]) for k in range(2)])

    def rms(phi):  # for a fixed rotation the best translation joins the centroids
        c, s = np.cos(phi), np.sin(phi)
        moved = est[keep, :2] @ np.array([[c, -s], [s, c]]).T
        moved += ref.mean(axis=0) - moved.mean(axis=0)
        return np.sqrt(np.mean(np.sum((moved - ref) ** 2, axis=1)))

    best = minimize_scalar(rms, bounds=(-1.0, 1.0), method="bounded", options={"xatol": 1e-10})
    assert ate["se2"] == pytest.approx(best.fun, rel=1e-9)
    assert ate["se2"] <= min(ate["none"], ate["start"])


@pytest.mark.filterwarnings("ignore:.*the track has no covariance")
def test_ate_and_rpe_agree_with_evo(tmp_path):
    """Same TUM files through evo (GPL: a test-only comparison, never a dependency)."""
    pytest.importorskip("evo")
    from evo.core import metrics, sync
    from evo.tools import file_interface

    rng = np.random.default_rng(9)
    n = 800
    t = np.arange(n) * 0.05
    gt = np.column_stack((np.cumsum(np.full(n, 0.01)), np.sin(t / 5), 0.2 * np.sin(t / 3)))
    est = gt + np.cumsum(rng.normal(0, 0.002, (n, 3)), axis=0) + [0.3, -0.2, 0.25]

    def tum(path, p):
        q = np.column_stack((np.zeros(n), np.zeros(n), np.sin(p[:, 2] / 2), np.cos(p[:, 2] / 2)))
        np.savetxt(path, np.column_stack((t, p[:, :2], np.zeros(n), q)), fmt="%.17g")
        return path

    est_path, gt_path = tum(tmp_path / "est.tum", est), tum(tmp_path / "gt.tum", gt)
    ref_traj, est_traj = sync.associate_trajectories(file_interface.read_tum_trajectory_file(str(gt_path)),
                                                     file_interface.read_tum_trajectory_file(str(est_path)))
    for align in ("none", "start", "se2"):
        ours = evaluate_tracks([est_path], [TruthOptions(gt_path)], align=align, rpe_distances=(1.0, 2.0))
        e = est_traj.__class__(poses_se3=est_traj.poses_se3, timestamps=est_traj.timestamps)
        if align == "start":
            e.align_origin(ref_traj)
        elif align == "se2":
            e.align(ref_traj)
        ape = metrics.APE(metrics.PoseRelation.translation_part)
        ape.process_data((ref_traj, e))
        assert ours["ate_rmse"] == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), rel=1e-9)
        for delta in (1.0, 2.0):
            rpe = metrics.RPE(metrics.PoseRelation.translation_part, delta=delta,
                              delta_unit=metrics.Unit.meters, pairs_from_reference=True)
            rpe.process_data((ref_traj, e))
            assert ours["rpe"][f"{delta:g}"] == pytest.approx(rpe.get_statistic(metrics.StatisticsType.rmse),
                                                              rel=1e-9)


def test_track_with_truth_then_evaluate_equals_the_log_form(tmp_path):
    """Whole-run figures: track --out (truth from the log) + evaluate TRACK.csv are the log form's."""
    run_track(RUN, ROBOT, out=tmp_path / "track.csv")
    assert read_track_csv(tmp_path / "track.csv").truth is not None
    a = evaluate_tracks([tmp_path / "track.csv"], [TruthOptions()])
    b = evaluate_logs([RUN], ROBOT, [TruthOptions()])
    for key in ("rows_evaluated", "final_position_error", "max_position_error", "ate_rmse", "drift_percent"):
        assert b[key] == pytest.approx(a[key], rel=1e-12), key
    assert b["rpe"]["1"] == pytest.approx(a["rpe"]["1"], rel=1e-12)
    assert b["windows"] == 1 and a["windows"] == 0  # one window per log without --window


def _simulate(make, tmp_path, k_true, k_model, seconds=600.0, seed=11, truth_noise=0.0):
    """A diff-drive log whose wheel noise is known (``make``: the ``noisy_diff_log`` fixture of
    tests/conftest.py)."""
    return make(tmp_path, k_true, k_model, seconds, seed, truth_noise)


@pytest.mark.slow
def test_windowed_coverage_is_right_when_the_noise_is_known(noisy_diff_log, tmp_path):
    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01)
    out = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                        window="3s")
    n = out["windows"]
    assert n == 200
    for level, got in out["coverage"].items():
        p = float(level)
        assert got == pytest.approx(p, abs=4 * np.sqrt(p * (1 - p) / n)), level
    lo, hi = out["nees_bounds"]
    assert lo < out["nees_position_mean"] < hi
    # The same errors under a model with half the true noise (a quarter of the variance):
    # the test must see it.
    _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.005)
    low = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                        window="3s")
    assert low["coverage"]["0.95"] < 0.8 and low["nees_position_mean"] > hi


def test_position_only_truth_and_truth_sigma_in_the_log_form(noisy_diff_log, tmp_path):
    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01, seconds=60.0)
    data = np.loadtxt(gt, delimiter=",", skiprows=1)
    np.savetxt(tmp_path / "xy.csv", data[:, :3], delimiter=",")  # t,x,y: no heading
    opts = LogOptions(columns=SIM_COLUMNS)
    full = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=opts, window="10s")
    with pytest.warns(UserWarning, match="no RPE over 1 m"):
        xy = evaluate_logs([log], robot, [TruthOptions(tmp_path / "xy.csv", sigma=0.001)], log_options=opts,
                           window="10s")
    assert xy["windows"] == full["windows"] == 6
    # fitted start headings add variance, and the window ends stay inside their NEES bounds
    # (or below: the start variance is a cautious one, the larger of σ² and the fit's residual)
    assert xy["nees_position_mean"] < xy["nees_bounds"][1]
    assert full["nees_position_mean"] < full["nees_bounds"][1]
    assert xy["rpe"]["1"] is None and any("no heading" in w for w in xy["warnings"])


@pytest.mark.parametrize(("make", "match"), [
    ("late_truth", "do not overlap in time"),
    ("long_window", "longer than the log"),
    ("standing", "no motion"),
])
def test_bad_log_form_input(noisy_diff_log, tmp_path, make, match):
    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01, seconds=20.0)
    window = "10s"
    if make == "late_truth":
        data = np.loadtxt(gt, delimiter=",", skiprows=1)
        data[:, 0] += 100.0
        np.savetxt(gt, data, delimiter=",")
    elif make == "long_window":
        window = "30s"
    else:
        data = np.loadtxt(log, delimiter=",", skiprows=1)
        data[:, 1:] = 0.0
        np.savetxt(log, data, delimiter=",", header="t,L,R", comments="")
    with pytest.raises(InputError, match=match):
        evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                      window=window)


def test_track_form_bad_input(tmp_path, synthetic):
    track, gt_path, t, est, *_ = synthetic
    with pytest.raises(InputError, match="no truth"):
        evaluate_tracks([track], [TruthOptions()])
    still = _track_csv(tmp_path / "still.csv", t, np.zeros_like(est))
    gt = tmp_path / "still_gt.csv"
    np.savetxt(gt, np.column_stack((t, np.zeros((t.size, 3)))), delimiter=",")
    with pytest.raises(InputError, match="standing still"):
        evaluate_tracks([still], [TruthOptions(gt)])


def test_track_csv_round_trip_with_truth_columns(tmp_path):
    run = run_track(RUN, ROBOT, out=tmp_path / "t.csv")
    back = read_track_csv(tmp_path / "t.csv")
    np.testing.assert_array_equal(back.poses, run.track.poses)
    np.testing.assert_array_equal(back.cov, run.track.cov)
    np.testing.assert_array_equal(back.truth, run.log.ground_truth)


@pytest.mark.slow
def test_snowhite_whole_run_matches_the_data_notes(data_dir, tmp_path):
    """SOURCE.md of the Halmstad data: integrating the handout's model from the first truth
    pose ends 0.23 m from the truth (max 0.27 m); the log form finds the same from its gt."""
    robot = tmp_path / "snowhite.toml"
    robot.write_text('[robot]\ntype = "tricycle"\nwheel_to_axle = 0.68\n'
                     "[noise]\nsigma_speed = 0.005\nsigma_steer = 0.01\nsigma_dt = 0.0001\n")
    out = evaluate_logs([data_dir / "halmstad-khepera-snowhite" / "snowhite.txt"], robot, [TruthOptions()],
                        window="20s")
    assert out["rows_evaluated"] == 4050 and out["rows_skipped"] == 0
    assert out["final_position_error"] == pytest.approx(0.228, abs=0.001)
    assert out["max_position_error"] == pytest.approx(0.266, abs=0.001)
    assert out["windows"] == 10


def test_a_log_with_no_window_is_left_out_and_named_when_others_have_windows(noisy_diff_log, tmp_path):
    """Truth present 20 s out of every 55 s holds no 30 s window (its gaps, 35 s, are longer
    than a window): alone, that log is one line naming the longest stretch between such gaps
    (it used to say "the log shows no motion", a robot driving all along); beside a log with
    windows, it is left out of the windowed test with a warning, and its windows do not
    change the other log's. A 1 s dropout every 20 s, by contrast, costs no window: a window
    needs truth at its two ends only."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    log, gt, robot = _simulate(noisy_diff_log, tmp_path / "a", k_true=0.01, k_model=0.01, seconds=120.0)
    gappy_log, gappy_gt, _ = _simulate(noisy_diff_log, tmp_path / "b", k_true=0.01, k_model=0.01,
                                       seconds=120.0, seed=12)
    data = np.loadtxt(gappy_gt, delimiter=",", skiprows=1)
    opts = LogOptions(columns=SIM_COLUMNS)
    alone = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=opts, window="30s")
    dropouts = (data[:, 0] % 20.0) < 19.0
    np.savetxt(gappy_gt, data[dropouts], delimiter=",", header="t,x,y,theta", comments="")
    spanned = evaluate_logs([gappy_log], robot, [TruthOptions(gappy_gt)], log_options=opts, window="30s")
    assert spanned["windows"] == alone["windows"] == 4
    keep = (data[:, 0] % 55.0) < 20.0
    np.savetxt(gappy_gt, data[keep], delimiter=",", header="t,x,y,theta", comments="")
    with pytest.raises(InputError, match=r"3 stretches of truth between gaps as long as a window \(19.9 s\)"):
        evaluate_logs([gappy_log], robot, [TruthOptions(gappy_gt)], log_options=opts, window="30s")
    both = evaluate_logs([log, gappy_log], robot, [TruthOptions(gt), TruthOptions(gappy_gt)],
                         log_options=opts, window="30s")
    assert both["windows"] == alone["windows"] == 4
    assert both["coverage"] == alone["coverage"]
    left_out = [w for w in both["warnings"] if "1 of 2 logs left out of the windowed test" in w]
    assert len(left_out) == 1 and str(gappy_log) in left_out[0]


def test_evaluate_warns_where_the_scored_covariance_leaves_the_first_order_regime(noisy_diff_log, tmp_path):
    """fit-noise warns when σθ at a window end passes 0.2 rad; evaluate now says the same of
    the covariance it scores (heading σ of a robot file with k = 0.03 m^½ on a 0.4 m wheel
    base: 0.32 rad after 60 s at 0.3 m/s, 0.09 rad after 5 s), and not of the same log in 5 s
    windows."""
    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.03, seconds=240.0)
    opts = LogOptions(columns=SIM_COLUMNS)
    long = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=opts, window="60s")
    short = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=opts, window="5s")
    assert any("first-order model may not hold" in w for w in long["warnings"])
    assert not any("first-order model may not hold" in w for w in short["warnings"])


def test_few_window_ends_are_warned_about_with_an_honest_models_spread(noisy_diff_log, tmp_path):
    """6 window ends: a 95 % figure moves in steps of 1/6, and an honest model's count of
    ends inside is Binomial(6, 0.95): its 2.5 and 97.5 % points (summed here from the
    pmf) are 4 and 6 ends, so the warning says 0.67..1.00. 200 ends (the slow test
    above) get no such warning."""
    from math import comb

    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01, seconds=60.0)
    with pytest.warns(UserWarning, match=r"only 6 window end\(s\)") as caught:
        out = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                            window="10s")
    assert out["windows"] == 6
    cdf = np.cumsum([comb(6, k) * 0.95**k * 0.05 ** (6 - k) for k in range(7)])
    low, high = int(np.searchsorted(cdf, 0.025)), int(np.searchsorted(cdf, 0.975))
    assert (low, high) == (4, 6)
    said = [str(w.message) for w in caught if "window end" in str(w.message)]
    assert f"{low / 6:.2f}..{high / 6:.2f}" in said[0]
    assert any("only 6 window end" in w for w in out["warnings"])
    # Each window end is in the JSON, to find an outlier by: 10 s apart, consecutive, their
    # NEES averaging to the pooled mean.
    ends = out["per_log"][0]["window_ends"]
    assert len(ends) == 6
    assert all(e["end"] - e["start"] == pytest.approx(10.0, abs=0.02) for e in ends)
    assert all(a["end"] == b["start"] for a, b in zip(ends[:-1], ends[1:], strict=True))
    assert np.mean([e["nees"] for e in ends]) == pytest.approx(out["nees_position_mean"], rel=1e-12)


def test_a_robot_file_without_noise_gives_the_errors_alone(tmp_path, run_cli):
    """``evaluate LOG --robot R`` where R has no [noise]: the whole run's errors equal those
    of ``track --out`` + ``evaluate TRACK.csv`` (a second route), NEES and coverage are None
    and said to be missing; ``--window`` is refused (it scores a covariance)."""
    text = Path(ROBOT).read_text()
    bare = tmp_path / "bare.toml"
    bare.write_text(text[: text.index("[noise]")] if "[noise]" in text else text)
    run_track(RUN, bare, out=tmp_path / "track.csv")
    a = evaluate_tracks([tmp_path / "track.csv"], [TruthOptions()])
    with pytest.warns(UserWarning, match=r"no \[noise\] table: the errors alone"):
        b = evaluate_logs([RUN], bare, [TruthOptions()])
    for key in ("rows_evaluated", "final_position_error", "max_position_error", "ate_rmse", "drift_percent"):
        assert b[key] == pytest.approx(a[key], rel=1e-12), key
    assert b["nees_position_mean"] is None and b["coverage"]["0.95"] is None and b["windows"] == 0
    code, out, err = run_cli("evaluate", RUN, "--robot", bare, "--window", "10s")
    assert code == 2 and "no [noise] table" in err and "--window" in err
    code, out, err = run_cli("evaluate", RUN, "--robot", bare)
    assert code == 0 and "position error: final" in out and "NEES" not in out


def test_the_python_api_draws_the_plot_the_command_draws(tmp_path, monkeypatch):
    """evaluate_in_memory(plot=...) draws what evaluate_logs (the command) draws: the same
    coverage series, the noise given and, since it has bias models, its white models alone,
    each with as many window ends; the figure is written (before, the in-memory form had no
    plot at all)."""
    import warnings

    import odomkit.workflows.evaluate as evaluate
    from odomkit.data import builtin_data_path
    from odomkit.io.optiodom import read_run
    from odomkit.io.robotfile import read_robot

    robot_file = tmp_path / "robot.toml"
    robot_file.write_text(Path(builtin_data_path("optiodom_diff.toml")).read_text()
                          + "\n[noise.parameters]\nsigma_scale_left = 0.01\nsigma_scale_right = 0.01\n")
    run = builtin_data_path("230620202042_run-01.csv")
    drawn = []
    real = evaluate._honesty_plot

    def capture(plot, scored, coverages, windows, length=None):
        drawn.append((coverages, windows, length))
        return real(plot, scored, coverages, windows, length)

    monkeypatch.setattr(evaluate, "_honesty_plot", capture)
    robot, noise = read_robot(robot_file)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        command = evaluate.evaluate_logs([run], robot_file, window="10s", plot=tmp_path / "cli.png")
        memory = evaluate.evaluate_in_memory(read_run(run), robot, noise, window="10s",
                                             plot=tmp_path / "api.png")
    assert drawn[0] == drawn[1]
    coverages, windows, length = drawn[1]
    assert set(coverages) == {"window ends (white + bias)", "window ends (white only)",
                              "window ends (white + bias), heading"} and length == "10 s"
    assert coverages["window ends (white + bias), heading"] == memory["coverage_heading"]
    assert coverages["window ends (white + bias)"] == memory["coverage"] == command["coverage"]
    white_models = [m for m in noise if m.kind == "white"]
    white = evaluate.evaluate_in_memory(read_run(run), robot, white_models, window="10s")
    assert coverages["window ends (white only)"] == white["coverage"]
    assert windows["window ends (white + bias)"] == windows["window ends (white only)"] == memory["windows"]
    assert memory["outputs"]["plot"] == str(tmp_path / "api.png")
    assert (tmp_path / "api.png").stat().st_size > 0
