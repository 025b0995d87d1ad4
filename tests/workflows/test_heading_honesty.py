"""``odomkit evaluate`` scores the predicted heading variance where the truth has heading.

Against independent truth: the heading NEES and interval coverage of the pure functions
against scipy's normal and χ² quantiles; on the simulated diff-drive log of known wheel
noise (tests/conftest.py ``noisy_diff_log``) the verdict of a model of the right size and
of one whose heading variance is 4× too small; every window end's heading NEES against a
direct computation from the files (a diff drive's heading is θ_start + Σ(d_R − d_L)/B, and
its variance Σ k²(|d_L| + |d_R|)/B², exactly, plus the truth's own heading noise at both
ends); position-only truth gives nulls.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from odomkit.evaluate import COVERAGE_LEVELS, heading_coverage, heading_nees, heading_nees_summary
from odomkit.workflows.evaluate import evaluate_logs
from odomkit.workflows.logs import LogOptions
from odomkit.workflows.truth import TruthOptions

SIM_COLUMNS = "t=t,dist_left=L,dist_right=R"
LEVELS = tuple(f"{p:g}" for p in COVERAGE_LEVELS)
HEADING_KEYS = ("nees_heading_mean", "nees_heading_median", "nees_heading_bounds", "coverage_heading",
                "coverage_heading_bounds", "coverage_heading_verdict", "coverage_heading_overall",
                "nees_heading_verdict")


def test_heading_nees_and_coverage_against_scipy():
    rng = np.random.default_rng(4)
    sigma = rng.uniform(0.01, 0.5, 5000)
    e = sigma * rng.standard_normal(5000) + 2 * np.pi * rng.integers(-2, 3, 5000)  # whole turns off
    e[:3] = np.nan  # truth without heading there
    var = sigma**2
    q = heading_nees(e, var)
    # Second method: the error wrapped by atan2, then e²/σ².
    wrapped = np.arctan2(np.sin(e), np.cos(e))
    np.testing.assert_allclose(q[3:], wrapped[3:] ** 2 / var[3:], rtol=1e-9)
    assert np.isnan(q[:3]).all()
    cover = heading_coverage(e, var)
    for p in COVERAGE_LEVELS:
        z = stats.norm.ppf((1 + p) / 2)
        assert cover[f"{p:g}"] == pytest.approx(np.mean(np.abs(wrapped[3:]) <= z * sigma[3:]), abs=1e-12)
        # 5000 honest samples: within 4 binomial standard errors of p.
        assert abs(cover[f"{p:g}"] - p) < 4 * np.sqrt(p * (1 - p) / 4997)
    summary = heading_nees_summary(e, var)
    assert summary["count"] == 4997
    assert summary["mean"] == pytest.approx(np.mean(wrapped[3:] ** 2 / var[3:]))
    lo, hi = summary["bounds"]
    assert lo == pytest.approx(stats.chi2.ppf(0.025, 4997) / 4997)
    assert hi == pytest.approx(stats.chi2.ppf(0.975, 4997) / 4997)
    # No variance, no claim: left out, as a singular covariance is.
    assert np.isnan(heading_nees([0.1, 0.1], [0.0, np.nan])).all()
    assert heading_coverage([0.1], [0.0]) == dict.fromkeys(LEVELS)


@pytest.mark.parametrize(("k_model", "expected"), [(0.01, "consistent"), (0.005, "optimistic")])
def test_heading_verdict_of_a_model_of_known_size(noisy_diff_log, tmp_path, k_model, expected):
    """The log's wheels have k = 0.01 m^½; k = 0.005 makes every variance, the heading's
    too, 4× too small. The right model's heading coverage is consistent in most of 5 seeds
    (each misses with probability ~12 %), its NEES mean inside its bounds in most; the small
    one's optimistic in every seed, both ways."""
    overall, by_nees = [], []
    for seed in range(5):
        log, gt, robot = noisy_diff_log(tmp_path, 0.01, k_model, 300.0, seed)
        out = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                            window="3s")
        assert out["windows"] == 100
        overall.append(out["coverage_heading_overall"])
        by_nees.append(out["nees_heading_verdict"])
        for level in LEVELS:
            lo, hi = out["coverage_heading_bounds"][level]
            got = out["coverage_heading"][level]
            side = "optimistic" if got < lo else "pessimistic" if got > hi else "consistent"
            assert out["coverage_heading_verdict"][level] == side
        lo, hi = out["nees_heading_bounds"]
        assert (lo, hi) == pytest.approx((stats.chi2.ppf(0.025, 100) / 100, stats.chi2.ppf(0.975, 100) / 100))
        assert out["per_log"][0]["nees_heading_mean"] == out["nees_heading_mean"]
    need = 4 if expected == "consistent" else 5
    assert overall.count(expected) >= need, overall
    assert by_nees.count(expected) >= need, by_nees


@pytest.mark.parametrize("truth_heading_sigma", [0.0, 0.02])
def test_window_end_heading_nees_against_the_files(noisy_diff_log, tmp_path, truth_heading_sigma):
    """Each window end's heading NEES, and their mean, median and coverage, against a direct
    numpy computation from the log and truth files: e = θ_truth(end) − θ_truth(start) −
    Σ(d_R − d_L)/B, σ² = Σ k²(|d_L| + |d_R|)/B² + 2 σθ_truth² (the truth's heading noise at
    the start, carried unchanged to the end, and at the end). With σθ_truth = 0.02 rad the
    truth's headings are noisy by that much, so the model stays honest only with it added."""
    k, B = 0.01, 0.4
    log, gt, robot = noisy_diff_log(tmp_path, k, k, 300.0, 7)
    truth = np.loadtxt(gt, delimiter=",", skiprows=1)
    if truth_heading_sigma:
        truth[:, 3] += truth_heading_sigma * np.random.default_rng(99).standard_normal(len(truth))
        np.savetxt(gt, truth, delimiter=",", header="t,x,y,theta", comments="")
    out = evaluate_logs([log], robot, [TruthOptions(gt, heading_sigma=truth_heading_sigma)],
                        log_options=LogOptions(columns=SIM_COLUMNS), window="3s")
    data = np.loadtxt(log, delimiter=",", skiprows=1)
    t, dl, dr = data.T
    ends = out["per_log"][0]["window_ends"]
    q, errors = [], []
    for end in ends:
        a, b = (int(np.flatnonzero(np.isclose(t, end[key]))[0]) for key in ("start", "end"))
        turn = np.sum(dr[a + 1:b + 1] - dl[a + 1:b + 1]) / B
        e = np.arctan2(np.sin(truth[b, 3] - truth[a, 3] - turn), np.cos(truth[b, 3] - truth[a, 3] - turn))
        var = np.sum(k**2 * (np.abs(dl[a + 1:b + 1]) + np.abs(dr[a + 1:b + 1]))) / B**2 \
            + 2 * truth_heading_sigma**2
        assert end["heading_error"] == pytest.approx(e, abs=1e-9)
        assert end["nees_heading"] == pytest.approx(e**2 / var, rel=1e-6)
        q.append(e**2 / var)
        errors.append(e / np.sqrt(var))
    q, z = np.array(q), np.abs(errors)
    assert out["nees_heading_mean"] == pytest.approx(q.mean(), rel=1e-6)
    assert out["nees_heading_median"] == pytest.approx(np.median(q), rel=1e-6)
    for p in COVERAGE_LEVELS:
        assert out["coverage_heading"][f"{p:g}"] == pytest.approx(np.mean(z <= stats.norm.ppf((1 + p) / 2)))
    # The truth's noise, 2 × 0.02² = 8e-4 rad² beside the odometry's ~1.1e-3 over 3 s: left
    # out, the NEES grows by ~1.7 and the model looks optimistic.
    if truth_heading_sigma:
        noisy = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                              window="3s")
        assert noisy["coverage_heading_overall"] == "optimistic"
        assert noisy["nees_heading_mean"] > 1.3 * out["nees_heading_mean"]


def test_position_only_truth_gives_null_heading_keys(noisy_diff_log, tmp_path):
    log, _, robot = noisy_diff_log(tmp_path, 0.01, 0.01, 60.0, 3)
    out = evaluate_logs([log], robot, [TruthOptions(tmp_path / "xy.csv")],
                        log_options=LogOptions(columns=SIM_COLUMNS), window="3s")
    assert out["windows"] > 0 and out["nees_position_mean"] is not None
    for key in HEADING_KEYS:
        assert out[key] is None and out["per_log"][0][key] is None, key
    assert {e["nees_heading"] for e in out["per_log"][0]["window_ends"]} == {None}


def test_whole_run_form_scores_the_heading_without_a_verdict(noisy_diff_log, tmp_path):
    """Without --window each log is one window: its heading NEES and coverage are given, the
    verdicts are not (one end is no test), as for the position."""
    log, gt, robot = noisy_diff_log(tmp_path, 0.01, 0.01, 60.0, 3)
    out = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS))
    end = out["per_log"][0]["window_ends"][0]
    assert out["nees_heading_mean"] == pytest.approx(end["nees_heading"])
    assert out["nees_heading_bounds"] == pytest.approx([stats.chi2.ppf(0.025, 1), stats.chi2.ppf(0.975, 1)])
    assert set(out["coverage_heading"]) == set(LEVELS)
    assert out["coverage_heading_verdict"] is None and out["nees_heading_verdict"] is None


def test_cli_prints_the_heading_line(noisy_diff_log, tmp_path, run_cli):
    log, gt, robot = noisy_diff_log(tmp_path, 0.01, 0.005, 300.0, 1)
    code, out, _ = run_cli("evaluate", log, "--robot", robot, "--columns", SIM_COLUMNS, "--truth", gt,
                           "--window", "3s")
    assert code == 0
    line = [x for x in out.splitlines() if x.startswith("heading NEES over 100 window ends")]
    assert len(line) == 1 and "above its bounds (optimistic)" in line[0]
    assert "inside the predicted 50/90/95/99 % intervals" in line[0] and "coverage optimistic" in line[0]
    code, out, _ = run_cli("evaluate", log, "--robot", robot, "--columns", SIM_COLUMNS, "--truth",
                           tmp_path / "xy.csv", "--window", "3s", "--json")
    assert code == 0 and json.loads(out)["coverage_heading"] is None
    code, out, _ = run_cli("evaluate", log, "--robot", robot, "--columns", SIM_COLUMNS, "--truth",
                           tmp_path / "xy.csv", "--window", "3s")
    assert code == 0 and "heading NEES" not in out


@pytest.mark.parametrize("truth_heading_sigma", [0.0, 0.01])
def test_track_rows_heading_nees_against_the_csv(noisy_diff_log, tmp_path, run_cli, truth_heading_sigma):
    """The track form: each row's heading NEES from the track CSV's own θ and cov_thetatheta
    against the truth file's θ (same times), plus ``--truth-heading-sigma``²; the first row
    (started at the truth, zero variance) has none without it. No verdict (rows of one run)."""
    log, gt, robot = noisy_diff_log(tmp_path, 0.01, 0.01, 60.0, 5)
    track = tmp_path / "track.csv"
    code, _, _ = run_cli("track", log, "--robot", robot, "--columns", SIM_COLUMNS, "--out", track)
    assert code == 0
    code, out, _ = run_cli("evaluate", track, "--truth", gt, "--truth-heading-sigma",
                           str(truth_heading_sigma), "--json")
    assert code == 0
    got = json.loads(out)
    rows = np.genfromtxt(track, delimiter=",", names=True)
    truth = np.loadtxt(gt, delimiter=",", skiprows=1)
    e = np.arctan2(np.sin(rows["theta"] - truth[:, 3]), np.cos(rows["theta"] - truth[:, 3]))
    var = rows["cov_thetatheta"] + truth_heading_sigma**2
    keep = var > 0
    assert keep.sum() == len(rows) - (truth_heading_sigma == 0)
    q = e[keep] ** 2 / var[keep]
    assert got["nees_heading_mean"] == pytest.approx(q.mean(), rel=1e-6)
    assert got["nees_heading_median"] == pytest.approx(np.median(q), rel=1e-6)
    inside = np.abs(e[keep]) <= stats.norm.ppf(0.975) * np.sqrt(var[keep])
    assert got["coverage_heading"]["0.95"] == pytest.approx(np.mean(inside))
    assert got["nees_heading_verdict"] is None and got["coverage_heading_verdict"] is None
