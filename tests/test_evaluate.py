"""Evaluation metrics against hand-computable cases and a chi-square property."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from odomkit.errors import ModelError
from odomkit.evaluate import (
    COVERAGE_LEVELS,
    align_track,
    coverage,
    evaluate_track,
    nees,
    nees_bounds,
    nees_summary,
    relative_pose_errors,
    rpe_pairs,
    umeyama_se2,
)


def test_constant_offset_gives_known_metrics():
    truth = np.column_stack((np.linspace(0, 10, 101), np.zeros(101), np.zeros(101)))
    est = truth + [0.0, 0.3, 0.0]
    ev = evaluate_track(est, truth)
    assert ev.final_position_error == pytest.approx(0.3)
    assert ev.ate_rmse == pytest.approx(0.3)
    assert ev.true_path_length == pytest.approx(10.0)
    assert ev.drift_per_distance == pytest.approx(0.03)
    # a rigid offset has no relative error
    assert np.allclose(relative_pose_errors(est, truth, 1.0), 0.0, atol=1e-12)


def test_rpe_sees_a_heading_bias_as_across_track_error():
    n = 1001
    s = np.linspace(0, 10, n)
    truth = np.column_stack((s, np.zeros(n), np.zeros(n)))
    est = np.column_stack((s * np.cos(0.01), s * np.sin(0.01), np.full(n, 0.01)))
    rpe = relative_pose_errors(est, truth, 2.0)
    # over 2 m the estimate moves 2 m at its own heading: same local motion, so the
    # only relative error is none in position and none in heading
    assert np.allclose(rpe, 0.0, atol=1e-12)


def test_nees_of_gaussian_samples_follows_chi_square():
    rng = np.random.default_rng(5)
    n = 20000
    A = np.array([[2.0, 0.3], [0.0, 0.5]])
    cov = np.broadcast_to(A @ A.T, (n, 2, 2))
    e = rng.standard_normal((n, 2)) @ A.T
    values = nees(e, cov)
    # mean of χ²₂ is 2 with standard error sqrt(4/n) = 0.014; 4 standard errors
    assert values.mean() == pytest.approx(2.0, abs=4 * np.sqrt(4 / n))
    inside = np.mean(values <= chi2.ppf(0.95, 2))
    # binomial standard error sqrt(0.95·0.05/n) = 0.0015
    assert inside == pytest.approx(0.95, abs=4 * np.sqrt(0.95 * 0.05 / n))


def test_singular_covariance_gives_nan_not_inf():
    assert np.isnan(nees(np.ones((1, 2)), np.zeros((1, 2, 2))))[0]


# ----------------------------------------------------------------------- alignment

def _rot(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


@pytest.mark.parametrize("phi", [0.0, 0.7, -2.9, np.pi - 1e-9])
def test_umeyama_recovers_a_known_se2_transform_exactly(phi):
    rng = np.random.default_rng(1)
    src = rng.normal(size=(50, 2)) * [3.0, 0.5]
    t = np.array([4.0, -1.5])
    got_phi, got_t = umeyama_se2(src, src @ _rot(phi).T + t)
    assert np.cos(got_phi - phi) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(got_t, t, atol=1e-12)


def test_umeyama_is_the_least_squares_optimum_with_noise():
    """A second method: minimise the same sum of squares over φ numerically (t is the
    centroid difference once φ is fixed)."""
    from scipy.optimize import minimize_scalar

    rng = np.random.default_rng(2)
    src = np.column_stack((np.linspace(0, 5, 40), np.sin(np.linspace(0, 3, 40))))
    dst = src @ _rot(0.4).T + [1.0, 2.0] + rng.normal(0, 0.05, src.shape)

    def cost(phi):
        moved = src @ _rot(phi).T
        return np.sum((dst - moved - (dst - moved).mean(axis=0)) ** 2)

    best = minimize_scalar(cost, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-12})
    phi, t = umeyama_se2(src, dst)
    assert phi == pytest.approx(best.x, abs=1e-7)
    np.testing.assert_allclose(t, dst.mean(axis=0) - _rot(phi) @ src.mean(axis=0), atol=1e-12)


def test_umeyama_never_reflects():
    src = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    mirrored = src * [1.0, -1.0]  # the best orthogonal map is a reflection: not allowed
    phi, _ = umeyama_se2(src, mirrored)
    assert np.isfinite(phi)


def test_umeyama_refuses_points_that_do_not_spread():
    with pytest.raises(ModelError, match="undetermined"):
        umeyama_se2(np.ones((5, 2)), np.ones((5, 2)))


def test_align_track_start_and_se2_move_the_track_onto_the_truth():
    n = 60
    s = np.linspace(0, 6, n)
    truth = np.column_stack((s, 0.3 * s**2 / 6, 0.1 * s))
    phi, t = 1.1, np.array([-2.0, 5.0])
    est = np.column_stack((truth[:, :2] @ _rot(phi).T + t, truth[:, 2] + phi))
    cov = np.broadcast_to(np.diag([4.0, 1.0, 0.5]), (n, 3, 3))
    J = np.eye(3)
    J[:2, :2] = _rot(-phi)  # the covariance turns with the track, by −φ
    for mode in ("start", "se2"):
        moved, P = align_track(est, truth, mode, cov)
        np.testing.assert_allclose(moved, truth, atol=1e-12)
        np.testing.assert_allclose(P[0], J @ np.diag([4.0, 1.0, 0.5]) @ J.T, atol=1e-12)
    same, _ = align_track(est, truth, "none")
    np.testing.assert_array_equal(same, est)


# ----------------------------------------------------------------------- RPE pairs

def _evo_consecutive_pairs(xy, delta):
    """evo's filters.filter_pairs_by_path (all_pairs=False), written out independently."""
    ids, current = [0], 0.0
    for i in range(1, len(xy)):
        current += float(np.linalg.norm(xy[i] - xy[i - 1]))
        if current >= delta:
            ids.append(i)
            current = 0.0
    return list(zip(ids, ids[1:], strict=False))


def test_consecutive_pairs_follow_evo():
    rng = np.random.default_rng(4)
    xy = np.cumsum(rng.uniform(0, 0.05, (500, 2)), axis=0)
    for delta in (0.3, 1.0, 2.5):
        i, j = rpe_pairs(xy, delta)
        assert list(zip(i.tolist(), j.tolist(), strict=True)) == _evo_consecutive_pairs(xy, delta)


def test_rpe_position_norm_is_evo_relative_error_norm():
    """|translation of (Q_i⁻¹Q_j)⁻¹(P_i⁻¹P_j)| with SE(2) matrices, against the local form."""
    rng = np.random.default_rng(5)
    n = 300
    truth = np.column_stack((np.cumsum(rng.uniform(0, 0.05, n)), np.cumsum(rng.normal(0, 0.02, n)),
                             np.cumsum(rng.normal(0, 0.02, n))))
    est = truth + rng.normal(0, 0.01, truth.shape)

    def se2(p):
        c, s = np.cos(p[2]), np.sin(p[2])
        return np.array([[c, -s, p[0]], [s, c, p[1]], [0, 0, 1]])

    i, j = rpe_pairs(truth[:, :2], 1.0)
    want = [np.linalg.norm((np.linalg.inv(np.linalg.inv(se2(truth[a])) @ se2(truth[b]))
                            @ (np.linalg.inv(se2(est[a])) @ se2(est[b])))[:2, 2])
            for a, b in zip(i, j, strict=True)]
    got = relative_pose_errors(est, truth, 1.0, pairs="consecutive")
    np.testing.assert_allclose(np.hypot(got[:, 0], got[:, 1]), want, rtol=1e-10, atol=1e-15)


# ----------------------------------------------------------------------- NEES and coverage

@pytest.mark.parametrize("level", COVERAGE_LEVELS)
def test_coverage_is_right_for_gaussian_errors_of_known_covariance(level):
    rng = np.random.default_rng(6)
    n = 20000
    # A different, correlated covariance for every sample.
    A = rng.normal(size=(n, 2, 2)) * [[1.0, 0.3], [0.0, 0.2]]
    cov = A @ A.transpose(0, 2, 1) + 1e-3 * np.eye(2)
    e = np.einsum("nij,nj->ni", np.linalg.cholesky(cov), rng.standard_normal((n, 2)))
    got = coverage(e, cov)[f"{level:g}"]
    # binomial standard error sqrt(p(1-p)/n); 4 of them
    assert got == pytest.approx(level, abs=4 * np.sqrt(level * (1 - level) / n))
    # too small a covariance is caught: errors twice the predicted size
    assert coverage(2 * e, cov)[f"{level:g}"] < level - 0.1


def test_coverage_counts_the_boundary_by_the_closed_form_quantile():
    # eᵀP⁻¹e = r² with r² on either side of −2 ln(1 − p)
    r2 = -2 * np.log(1 - 0.9)
    e = np.array([[np.sqrt(r2 * 0.999), 0.0], [np.sqrt(r2 * 1.001), 0.0]])
    assert coverage(e, np.broadcast_to(np.eye(2), (2, 2, 2)), (0.9,)) == {"0.9": 0.5}


def test_nees_bounds_hold_95_percent_of_means_of_consistent_samples():
    rng = np.random.default_rng(7)
    n, trials = 30, 20000
    means = rng.chisquare(2, (trials, n)).mean(axis=1)
    lo, hi = nees_bounds(n, 2)
    inside = np.mean((means >= lo) & (means <= hi))
    assert inside == pytest.approx(0.95, abs=4 * np.sqrt(0.95 * 0.05 / trials))
    assert np.mean(means < lo) == pytest.approx(0.025, abs=0.006)


def test_nees_summary_leaves_out_singular_rows():
    e = np.array([[1.0, 0.0], [0.0, 2.0], [5.0, 5.0]])
    cov = np.array([np.eye(2), np.eye(2), np.zeros((2, 2))])
    out = nees_summary(e, cov)
    assert out["count"] == 2 and out["mean"] == pytest.approx(2.5) and out["median"] == pytest.approx(2.5)
    assert out["bounds"] == pytest.approx(list(nees_bounds(2, 2)))
    assert nees_summary(e[2:], cov[2:])["mean"] is None


def _near_singular_track(n=50, near=3):
    """A track started at the truth pose with zero covariance: its first rows' covariance is
    nearly singular (σ 1e-6 m across, 0.1 m along) while the truth's own noise puts 1 mm
    between estimate and truth on every row; the rest have σ 0.1 m both ways."""
    t = np.arange(n, dtype=float)
    truth = np.column_stack((0.1 * t, np.zeros(n), np.zeros(n)))
    poses = truth + [0.0, 1e-3, 0.0]
    poses[0] = truth[0]  # the start: no error, zero covariance (singular, nothing lost)
    cov = np.zeros((n, 3, 3))
    cov[1:near + 1] = np.diag([1e-2, 1e-12, 1e-4])
    cov[near + 1:] = np.diag([1e-2, 1e-2, 1e-4])
    return t, poses, truth, cov


def test_evaluate_track_warns_where_near_singular_rows_make_most_of_the_nees(tmp_path, run_cli):
    """User study s24, M2: evaluate_track returned a NEES mean of 6.6e7 on Snowhite silently,
    where ``odomkit evaluate`` of the same track warns that a few nearly singular rows make
    most of the summed NEES. Both now say it, from one function (odomkit.evaluate)."""
    import json
    import warnings

    from odomkit.evaluate import evaluate_track

    t, poses, truth, cov = _near_singular_track()
    # Directly: each row's eᵀP⁻¹e, and the share of the three nearly singular rows.
    err = poses - truth
    values = (err[:, 0] ** 2 / np.where(cov[:, 0, 0] > 0, cov[:, 0, 0], np.nan)
              + err[:, 1] ** 2 / np.where(cov[:, 1, 1] > 0, cov[:, 1, 1], np.nan))[1:]
    share = values[:3].sum() / values.sum()
    assert share > 0.5
    with pytest.warns(UserWarning, match=rf"{100 * share:.4g} % of the summed NEES comes from 3 of 50 rows"):
        got = evaluate_track(poses, truth, cov)
    assert got.nees_position_mean == pytest.approx(values.mean(), rel=1e-12)
    # The same line as odomkit evaluate's on the same track (which names the file first).
    cells = np.column_stack((t, poses, cov[:, 0, 0], cov[:, 0, 1], cov[:, 0, 2], cov[:, 1, 1], cov[:, 1, 2],
                             cov[:, 2, 2], truth))
    track = tmp_path / "track.csv"
    np.savetxt(track, cells, delimiter=",", comments="", fmt="%.17g",
               header="t,x,y,theta,cov_xx,cov_xy,cov_xtheta,cov_yy,cov_ytheta,cov_thetatheta,gt_x,gt_y,gt_theta")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        evaluate_track(poses, truth, cov)
    code, out, err = run_cli("evaluate", track, "--json")
    assert code == 0, err
    [said] = [str(w.message) for w in caught]
    assert f"{track}: {said}" in json.loads(out)["warnings"]
    # Rows of one regular covariance say nothing.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        evaluate_track(poses, truth, np.broadcast_to(np.diag([1e-2, 1e-2, 1e-4]), cov.shape))


def test_evaluate_track_warns_on_snowhite_as_the_user_study_found(data_dir):
    from pathlib import Path

    from odomkit.evaluate import evaluate_track
    from odomkit.io.halmstad import read_snowhite
    from odomkit.io.robotfile import read_robot
    from odomkit.track import dead_reckon_log

    path = data_dir / "halmstad-khepera-snowhite" / "snowhite.txt"
    if not path.exists():
        pytest.skip("snowhite.txt is not in the data folder")
    robot, noise = read_robot(Path(__file__).resolve().parents[1] / "examples" / "snowhite.toml")
    log = read_snowhite(path)
    track = dead_reckon_log(log, robot, noise=noise)
    with pytest.warns(UserWarning, match="of the summed NEES comes from"):
        got = evaluate_track(track.poses, log.ground_truth, track.cov)
    assert got.nees_position_mean > 1e6


def test_the_two_nees_means_and_error_signs_are_told_apart_where_defined():
    """User study s24, M3: ``nees_position_mean`` is over a track's rows in evaluate_track and
    track --json's ground_truth, over window ends in evaluate --robot (246.9 against 17.96 for
    one run); errors are estimate − truth in pose_errors, truth − odometry at window ends.
    Each definition says so, beside the other."""
    from pathlib import Path

    from odomkit.evaluate import TrackEvaluation, pose_errors
    from odomkit.window_errors import WindowErrors
    from odomkit.workflows.evaluate import evaluate_logs

    def said(text):
        return " ".join((text or "").split())

    assert "window ends" in said(TrackEvaluation.__doc__) and "rows" in said(TrackEvaluation.__doc__)
    assert "over window ends" in said(evaluate_logs.__doc__) and "rows" in said(evaluate_logs.__doc__)
    assert "truth − odometry" in said(pose_errors.__doc__)
    assert "estimate − truth" in said(WindowErrors.__doc__)
    docs = Path(__file__).resolve().parents[1] / "docs" / "reference" / "commands"
    track, evaluate = (said((docs / f"{name}.md").read_text()) for name in ("track", "evaluate"))
    assert "`ground_truth`" in track and "over every row" in track
    assert "mean over window ends" in evaluate and "estimate − truth" in evaluate
