"""The honesty verdicts of ``odomkit evaluate`` and ``odomkit fit-noise`` (a user study on two
unseen real logs: "inside its bounds" read as honest beside 95 % coverage 0.78; every window
left out still ended in "this is the test to trust"; the whole-run figures hung on a start
heading never shown; a fit missing its own in-sample coverage said nothing).

Each verdict is checked on errors whose noise is known: a model of the right size is
"consistent" in most seeds (as often as the binomial ranges promise), one too small
"optimistic", one too large "pessimistic".
"""

from __future__ import annotations

import warnings
from math import comb

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.evaluate import COVERAGE_LEVELS, coverage, coverage_range, coverage_verdicts, overall_verdict
from odomkit.workflows._scoring import Scored, summarise, verdicts
from odomkit.workflows.evaluate import evaluate_logs
from odomkit.workflows.logs import LogOptions
from odomkit.workflows.truth import TruthOptions

SIM_COLUMNS = "t=t,dist_left=L,dist_right=R"
LEVELS = tuple(f"{p:g}" for p in COVERAGE_LEVELS)


def _binomial_points(n, p):
    """The 2.5 and 97.5 % points of Binomial(n, p), summed from the pmf (not scipy)."""
    cdf = np.cumsum([comb(n, k) * p**k * (1 - p) ** (n - k) for k in range(n + 1)])
    return int(np.searchsorted(cdf, 0.025)), int(np.searchsorted(cdf, 0.975))


@pytest.mark.parametrize("n", [1, 6, 9, 37, 86, 200])
@pytest.mark.parametrize("p", COVERAGE_LEVELS)
def test_coverage_range_is_the_binomial_95_percent_range(n, p):
    low, high = _binomial_points(n, p)
    assert coverage_range(n, p) == pytest.approx((low / n, high / n), abs=1e-12)


def _gaussian_ends(rng, n, scale):
    """n window ends with errors ~ N(0, Σ) scored against scale·Σ (Σ a random SPD matrix)."""
    a = rng.standard_normal((2, 2))
    sigma = a @ a.T + 0.1 * np.eye(2)
    e = rng.multivariate_normal(np.zeros(2), sigma, size=n)
    return e, np.broadcast_to(scale * sigma, (n, 2, 2))


@pytest.mark.parametrize(("scale", "expected", "at_least"), [
    (1.0, "consistent", 0.80),  # each level misses its range in < 5 % of seeds; the four together in ~12 %
    (0.5, "optimistic", 0.99),  # half the variance: 77.7 % inside the 95 % ellipse
    (2.0, "pessimistic", 0.99),  # twice: 77.7 % inside the 50 % ellipse
])
def test_the_coverage_verdict_of_a_model_of_known_size(scale, expected, at_least):
    rng = np.random.default_rng(5)
    seeds, n = 400, 100
    got = []
    for _ in range(seeds):
        e, cov = _gaussian_ends(rng, n, scale)
        got.append(overall_verdict(coverage_verdicts(coverage(e, cov), n)))
    share = got.count(expected) / seeds
    # The share's own sampling error over 400 seeds is at most 0.025: 3 of them below the bound.
    assert share >= at_least - 3 * np.sqrt(at_least * (1 - at_least) / seeds)
    if expected == "consistent":
        # and each level alone misses in at most 5 % of seeds (the range is conservative: discrete)
        per_level = [[coverage_verdicts(coverage(*_gaussian_ends(rng, n, 1.0)), n)[k] for _ in range(200)]
                     for k in ("0.5", "0.95")]
        for level in per_level:
            assert sum(v != "consistent" for v in level) / 200 <= 0.05 + 3 * np.sqrt(0.05 * 0.95 / 200)


def test_overall_verdict_words():
    assert overall_verdict({"0.5": "consistent", "0.95": None}) == "consistent"
    assert overall_verdict({"0.5": "consistent", "0.95": "optimistic"}) == "optimistic"
    assert overall_verdict({"0.5": "pessimistic", "0.99": "optimistic"}) == "mixed"
    assert overall_verdict({"0.5": None}) is None


def _scored(nees_values):
    """A log whose window ends have exactly these position eᵀΣ⁻¹e under Σ = I."""
    q = np.asarray(nees_values, dtype=float)
    errors = np.column_stack((np.sqrt(q), np.zeros_like(q)))
    return Scored("a.csv", 10, 0, np.array([1.0, 2.0]), 5.0, {"1": None}, errors,
                  np.broadcast_to(np.eye(2), (q.size, 2, 2)).copy(), windows=q.size)


def test_nees_inside_its_bounds_but_coverage_optimistic_says_to_trust_coverage():
    """The study's 30 s case: the mean inside its bounds, the 95 % coverage far below its
    range. 50 ends at eᵀΣ⁻¹e 0.1, 30 at 2 and 20 at 7: mean 2.05 (inside 1.64..2.41 for 100
    ends), 80 % inside the 90 and 95 % ellipses (χ² 4.61, 5.99), all inside 99 % (9.21)."""
    s = _scored([0.1] * 50 + [2.0] * 30 + [7.0] * 20)
    summary = summarise([s], (1.0,))
    got = verdicts(summary, [s], windowed=True)
    assert summary["nees_position_mean"] == pytest.approx(2.05)
    assert got["nees_verdict"] == "consistent"
    assert got["coverage_verdict"] == {"0.5": "consistent", "0.9": "optimistic", "0.95": "optimistic",
                                       "0.99": "consistent"}
    assert got["coverage_overall"] == "optimistic"
    assert "trust coverage" in got["verdict_note"] and "says consistent" in got["verdict_note"]
    assert got["coverage_bounds"]["0.95"] == pytest.approx([p / 100 for p in _binomial_points(100, 0.95)])
    # One large end pulls the mean above its bounds while coverage stays consistent.
    honest = list(-2 * np.log1p(-(np.arange(99) + 0.5) / 99)) + [150.0]  # χ²₂ quantiles, and one
    s = _scored(honest)
    got = verdicts(summarise([s], (1.0,)), [s], windowed=True)
    assert got["nees_verdict"] == "optimistic" and got["coverage_overall"] == "consistent"
    # An end at 150 is not "a few large ends" but one an honest covariance never gives
    # (chance 100·e^-75): the note says so and does not send the user to coverage.
    assert "the largest end (NEES 150" in got["verdict_note"] and "heavier tail" in got["verdict_note"]
    assert "trust coverage" not in got["verdict_note"]
    # Large but plausible ends (two of 30 at 14.5: the largest has a chance of 0.021 over 30
    # ends) keep the advice to trust coverage.
    plausible = list(-2 * np.log1p(-(np.arange(28) + 0.5) / 28)) + [14.5] * 2
    s = _scored(plausible)
    got = verdicts(summarise([s], (1.0,)), [s], windowed=True)
    assert got["nees_verdict"] == "optimistic" and got["coverage_overall"] == "consistent"
    assert "trust coverage" in got["verdict_note"] and "pull the mean up (largest 14.5" in got["verdict_note"]
    # Track rows (not independent): no verdict at all.
    assert set(verdicts(summarise([s], (1.0,)), [s], windowed=False).values()) == {None}


def test_a_few_ends_with_one_far_outside_are_not_called_consistent():
    """A user study's held-out 60 s test: 3 window ends, one at NEES 28.2 (chance ~2e-6 for an
    honest covariance). Coverage over 3 ends calls it consistent; the note must not send the
    user to coverage, and must say that 3 ends can hardly tell."""
    s = _scored([0.5, 1.2, 28.2])
    got = verdicts(summarise([s], (1.0,)), [s], windowed=True)
    assert got["nees_verdict"] == "optimistic" and got["coverage_overall"] != "optimistic"
    note = got["verdict_note"]
    assert "trust coverage" not in note and "with only 3 ends" in note and "NEES 28.2" in note
    chance = 1 - (1 - np.exp(-28.2 / 2)) ** 3
    assert f"a chance of {chance:.1g} over 3 ends" in note


@pytest.mark.parametrize(("n", "q", "dof"), [(1, 4.0, 2), (5, 7.0, 2), (40, 12.0, 2), (1, 3.0, 1),
                                             (8, 6.0, 1), (40, 9.0, 1)])
def test_the_chance_of_the_largest_end_matches_monte_carlo(n, q, dof):
    """P(max of n χ² ≥ q) by simulation (200 000 sets of n Gaussian errors in ``dof``
    dimensions: a position's 2, a heading's 1), within 4 of its standard errors."""
    from odomkit.workflows._scoring import _largest_end_chance

    rng = np.random.default_rng(3)
    sets = 200_000
    largest = np.zeros(sets)
    for _ in range(n):
        largest = np.maximum(largest, (rng.standard_normal((sets, dof)) ** 2).sum(axis=1))
    seen = float(np.mean(largest >= q))
    values = np.r_[np.zeros(n - 1), q]
    want = _largest_end_chance(values, dof)
    assert abs(seen - want) <= 4 * np.sqrt(want * (1 - want) / sets)


def test_ends_all_on_the_truth_have_certain_chance_and_no_numpy_warning():
    """Window ends with NEES 0 (perfect odometry): any end reaches 0, chance 1. It was right,
    but log1p(-1) printed numpy's "divide by zero" RuntimeWarning on the user's terminal."""
    import warnings

    from odomkit.workflows._scoring import _largest_end_chance

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _largest_end_chance(np.zeros(5), 2) == 1.0
        assert _largest_end_chance(np.zeros(3), 1) == 1.0


def test_the_heading_gets_its_own_disagreement_note():
    """The heading's NEES and coverage verdicts disagree as the position's do (a user asked why
    run 01's heading NEES said optimistic while its coverage said consistent): the same note,
    for a 1-dof interval. One end 6σ off among 8 honest ones (chance ~2e-8)."""
    from dataclasses import replace as _replace

    honest = [0.1, 0.3, 0.5, 0.8, 1.0, 1.3, 1.8, 2.5]
    q = np.array(honest + [36.0])
    s = _scored([1.0] * q.size)
    # 10 mrad σ: errors of a few σ stay far inside ±π (heading errors are wrapped).
    s = _replace(s, heading_errors=0.01 * np.sqrt(q), heading_var=np.full(q.size, 1e-4))
    got = verdicts(summarise([s], (1.0,)), [s], windowed=True)
    assert got["nees_heading_verdict"] == "optimistic" and got["coverage_heading_overall"] != "optimistic"
    note = got["verdict_heading_note"]
    assert "NEES 36" in note and "99 % interval" in note and "with only 9 ends" in note
    assert "trust coverage" not in note
    # Where both agree there is no note; position-only truth has none either.
    assert verdicts(summarise([_scored([1.0] * 9)], (1.0,)), [_scored([1.0] * 9)],
                    windowed=True)["verdict_heading_note"] is None


def _simulate(make, tmp_path, k_true, k_model, seconds=300.0, seed=11, truth_noise=0.0):
    """A diff-drive log whose wheel noise is known (``make``: the ``noisy_diff_log`` fixture of
    tests/conftest.py)."""
    return make(tmp_path, k_true, k_model, seconds, seed, truth_noise)


@pytest.mark.parametrize(("k_model", "expected"), [(0.01, "consistent"), (0.005, "optimistic"),
                                                   (0.02, "pessimistic")])
def test_evaluate_gives_the_verdict_of_a_model_of_known_size(noisy_diff_log, tmp_path, k_model, expected):
    """The log's wheels have k = 0.01 m^½; a robot file with k half or twice that is told
    optimistic or pessimistic, one with the true k consistent in most of 5 seeds (each
    misses with probability ~12 %: 5 seeds all but one pass with probability 0.88)."""
    got = []
    for seed in range(5):
        log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=k_model, seed=seed)
        out = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=LogOptions(columns=SIM_COLUMNS),
                            window="3s")
        assert out["windows"] == 100
        got.append(out["coverage_overall"])
        assert out["per_log"][0]["coverage_overall"] == out["coverage_overall"]
        for level in LEVELS:
            lo, hi = out["coverage_bounds"][level]
            got_level = out["coverage"][level]
            side = "optimistic" if got_level < lo else "pessimistic" if got_level > hi else "consistent"
            assert out["coverage_verdict"][level] == side
    assert got.count(expected) >= (4 if expected == "consistent" else 5), got


def test_every_window_left_out_is_an_error_unless_another_length_was_scored(noisy_diff_log, tmp_path):
    """Position-only truth whose fixes scatter 2 cm, stated as 1 mm (--truth-sigma), but for
    2 s: no start heading can be fitted at any window start (the fit's residual is 20 σ), so
    every window is left out, while the whole run starts in the clean 2 s. Alone that is an
    error saying why and what to do, not a report that ends with "this is the test to
    trust"; beside a length that was scored, a warning."""
    log, _, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01, seconds=60.0,
                              truth_noise=0.02)
    data = np.loadtxt(tmp_path / "xy.csv", delimiter=",", skiprows=1)
    # Clean fixes from 1.5 to 3.5 s: the whole run starts there, but no 5 s window does.
    data[15:36, 1:] = np.loadtxt(tmp_path / "gt.csv", delimiter=",", skiprows=1)[15:36, 1:3]
    np.savetxt(tmp_path / "xy.csv", data, delimiter=",", header="t,x,y", comments="")
    opts = LogOptions(columns=SIM_COLUMNS)
    truth = [TruthOptions(tmp_path / "xy.csv", sigma=0.001)]
    with pytest.raises(InputError, match=r"no window end could be scored.*no start heading.*truth with head"):
        evaluate_logs([log], robot, truth, log_options=opts, window="5s")
    # 2 s windows start at 2 s too, inside the clean fixes: that length is scored, 5 s is warned of.
    with pytest.warns(UserWarning, match="5 s windows: no window end could be scored"):
        both = evaluate_logs([log], robot, truth, log_options=opts, window=["5s", "2s"])
    assert both["by_window"]["5 s"]["windows"] == 0 and both["by_window"]["2 s"]["windows"] >= 1
    assert both["by_window"]["5 s"]["coverage_overall"] is None


def test_evaluate_shows_the_fitted_start_heading_and_warns_where_the_whole_run_hangs_on_it(
        noisy_diff_log, tmp_path, run_cli):
    """Position-only truth scattering 2 cm: the whole run starts from a heading fitted to the
    fixes, with a σ of its own; the report shows both, and where 2σθ × the run's distance
    from its start is over half the final error (or 2σθ × its RMS over half the ATE) it warns
    with that figure (2σ), computed here from the truth file. With --align se2 the heading is
    refitted and nothing is said; with heading truth nothing is fitted."""
    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.002, k_model=0.002, seconds=120.0,
                               truth_noise=0.02)
    opts = LogOptions(columns=SIM_COLUMNS)
    with pytest.warns(UserWarning):
        out = evaluate_logs([log], robot, [TruthOptions(tmp_path / "xy.csv")], log_options=opts)
    truth = np.loadtxt(gt, delimiter=",", skiprows=1)
    assert out["start_heading_fitted"] and out["per_log"][0]["start_heading_fitted"]
    row = int(np.searchsorted(truth[:, 0], out["start_time"]))
    sigma = out["start_heading_sigma"]
    assert 0 < sigma < 0.1
    assert abs(out["start_heading"] - truth[row, 3]) < 4 * sigma  # the true heading there, within its σ
    xy = np.loadtxt(tmp_path / "xy.csv", delimiter=",", skiprows=1)[row:, 1:]
    distance = np.hypot(*(xy - xy[0]).T)
    end = 2 * sigma * distance[-1]
    said = [w for w in out["warnings"] if "start heading" in w]
    expected = end > 0.5 * out["final_position_error"] or \
        2 * sigma * np.sqrt(np.mean(distance**2)) > 0.5 * out["ate_rmse"]
    assert expected  # 2 cm fixes, a robot of 2 mm^½ noise: the heading's share is large here
    assert len(said) == 1 and f"moves the end by ±{end:.3g} m" in said[0]
    assert "--align se2" in said[0] and "--window for the honesty test" in said[0]
    # Asked for the windowed test already, it is not advised again (a user study).
    with pytest.warns(UserWarning):
        windowed = evaluate_logs([log], robot, [TruthOptions(tmp_path / "xy.csv")], log_options=opts,
                                 window="10s")
    again = [w for w in windowed["warnings"] if "start heading" in w]
    assert len(again) == 1 and "--align se2" in again[0] and "--window" not in again[0]
    code, text, _ = run_cli("evaluate", log, "--robot", robot, "--columns", SIM_COLUMNS, "--truth",
                            tmp_path / "xy.csv")
    assert code == 0 and f"start heading {out['start_heading']:.4g} ± {sigma:.2g} rad" in text
    assert "(the whole run starts from it)" in text
    code, text, _ = run_cli("evaluate", log, "--robot", robot, "--columns", SIM_COLUMNS, "--truth",
                            tmp_path / "xy.csv", "--align", "se2")
    assert code == 0 and "--align se2 then turns the track onto the truth" in text  # said, not hidden
    with pytest.warns(UserWarning):
        aligned = evaluate_logs([log], robot, [TruthOptions(tmp_path / "xy.csv")], log_options=opts,
                                align="se2")
    assert not any("start heading" in w for w in aligned["warnings"])
    headed = evaluate_logs([log], robot, [TruthOptions(gt)], log_options=opts)
    assert not headed["start_heading_fitted"] and headed["start_heading"] == pytest.approx(truth[0, 3])
    assert not any("start heading" in w for w in headed["warnings"])


def test_every_window_left_out_is_one_line_and_exit_2(noisy_diff_log, tmp_path, run_cli):
    log, _, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01, seconds=60.0,
                              truth_noise=0.02)
    data = np.loadtxt(tmp_path / "xy.csv", delimiter=",", skiprows=1)
    data[15:36, 1:] = np.loadtxt(tmp_path / "gt.csv", delimiter=",", skiprows=1)[15:36, 1:3]
    np.savetxt(tmp_path / "xy.csv", data, delimiter=",", header="t,x,y", comments="")
    code, out, err = run_cli("evaluate", log, "--robot", robot, "--columns", SIM_COLUMNS, "--truth",
                             tmp_path / "xy.csv", "--truth-sigma", "0.001", "--window", "5s")
    assert code == 2 and "test to trust" not in out
    line = [x for x in err.splitlines() if x.startswith("odomkit: error:")]
    assert len(line) == 1 and "no window end could be scored" in line[0] and "Traceback" not in err


def _fit(make, tmp_path, k_true, seed, *, slip=0.0, trim=None, kinds=("white",), window="3s", truth="gt.csv",
         epoch=0.0):
    """fit-noise of a robot file's k on a simulated log; ``slip``: with probability 0.005 a step
    also slips one wheel by that much [m] (a heavy tail no Gaussian model holds); ``epoch``
    [s] added to the log's and the truth's times (a Unix clock)."""
    from odomkit.workflows.fit_noise import fit_noise_files

    log, gt, robot = _simulate(make, tmp_path, k_true=k_true, k_model=0.005, seed=seed)
    for path, header in ((log, "t,L,R"), (tmp_path / truth, None)):
        if epoch:
            with open(path) as f:
                header = f.readline().strip()
            data = np.loadtxt(path, delimiter=",", skiprows=1)
            data[:, 0] += epoch
            np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.17g")
    if slip:
        data = np.loadtxt(log, delimiter=",", skiprows=1)
        rng = np.random.default_rng(100 + seed)
        hit = rng.random(data.shape[0]) < 0.005
        data[hit, 1] += slip * rng.choice([-1.0, 1.0], hit.sum())
        np.savetxt(log, data, delimiter=",", header="t,L,R", comments="")
    held = TruthOptions(tmp_path / truth, sigma=0.0, heading_sigma=0.0, time_sigma=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_noise_files(robot, [log], [held], tmp_path / "fit.toml", window=window, kinds=kinds,
                               log_options=LogOptions(columns=SIM_COLUMNS), trim=trim, overwrite=True)


def _misfit(result):
    return [w for w in result["warnings"] if w.startswith("in-sample coverage misses")]


def test_fit_noise_of_the_right_family_is_not_warned_about(noisy_diff_log):
    """Gaussian wheel noise fitted with the wheel-noise model: in-sample coverage inside its
    range in most seeds (each misses with probability ~12 %)."""
    import tempfile
    from pathlib import Path

    warned = 0
    for seed in range(5):
        with tempfile.TemporaryDirectory() as d:
            result = _fit(noisy_diff_log, Path(d), 0.01, seed)
            assert result["windows"] == 100
            warned += bool(_misfit(result))
    assert warned <= 1


def test_fit_noise_says_when_its_model_family_misses_its_own_windows(noisy_diff_log, tmp_path):
    """Wheel slips of 10 cm in 0.5 % of the steps (about one 3 s window in seven; a window's own
    wheel noise is about 1 cm): a Gaussian k fitted
    to every window (--trim 1) is too large for the bulk and too small for the slipped ones,
    so its own in-sample coverage is outside its range, and the warning names the window
    ends of largest eᵀΣ⁻¹e by log and time; trimmed (the default 0.999), far more than 5 %
    of the ends are left out, which is no rare tail."""
    result = _fit(noisy_diff_log, tmp_path, 0.01, 0, slip=0.1, epoch=1248444187.0)
    said = _misfit(result)
    assert len(said) == 1 and "does not describe these logs" in said[0] and "WheelNoise" in said[0]
    assert "log.csv " in said[0] and " s (" in said[0]
    # On a Unix clock (MRCLAM, ROS bags) each window is named to the millisecond, not as
    # 1.24844e+09-1.24844e+09 s for every window of the day.
    named = said[0].split("log.csv ")[1].split(" s (")[0]
    start, end = (float(part) for part in named.split("-"))
    assert "e+09" not in said[0] and 1248444187.0 <= start < end <= 1248444187.0 + 300.0
    cov = result["coverage_in_sample"]
    lo, hi = coverage_range(result["windows"], 0.5)
    assert cov["0.5"] > hi or cov["0.99"] < coverage_range(result["windows"], 0.99)[0]
    trimmed = _fit(noisy_diff_log, tmp_path, 0.01, 0, slip=0.1, trim=0.999)
    assert trimmed["windows_trimmed"] > 0.05 * (trimmed["windows"] + trimmed["windows_trimmed"])
    note = [w for w in trimmed["warnings"] if "ellipse of the fit and were left out" in w]
    assert len(note) == 1 and "no rare tail" in note[0] and "does not describe these logs" in note[0]
    # Without slips nothing is trimmed past 5 %: no such note.
    clean = _fit(noisy_diff_log, tmp_path, 0.01, 0, trim=0.999)
    assert not any("no rare tail" in w for w in clean["warnings"])


@pytest.mark.parametrize(("kinds", "suggested"), [("white", False), ("white,bias", True)])
def test_an_undetermined_fit_suggests_fewer_kinds_only_where_both_were_asked(
        noisy_diff_log, tmp_path, run_cli, kinds, suggested):
    log, _, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.01, k_model=0.01, seconds=20.0)
    code, _, err = run_cli("fit-noise", "--robot", robot, "--log", log, "--columns", SIM_COLUMNS, "--truth",
                           tmp_path / "xy.csv", "--window", "10s", "--kinds", kinds,
                           "--out", tmp_path / "f.toml")
    assert code == 2 and "the fit is undetermined" in err
    assert ("--kinds white" in err) is suggested


def test_each_window_end_gives_the_sigma_of_its_start_heading(noisy_diff_log, tmp_path):
    """An end far outside its ellipse may come from its start heading (a Husky bag: a window
    starting slow and turning, its heading fitted to 0.8 m fixes off by 0.7 rad): each
    window_ends entry gives that heading's σ. With heading truth it is the truth's heading
    noise, exactly; fitted to positions alone it is that fit's, positive and finite."""
    log, gt, robot = _simulate(noisy_diff_log, tmp_path, k_true=0.002, k_model=0.002, seconds=120.0,
                               truth_noise=0.02)
    opts = LogOptions(columns=SIM_COLUMNS)
    headed = evaluate_logs([log], robot, [TruthOptions(gt, heading_sigma=0.01)], log_options=opts,
                           window="10s")
    ends = headed["per_log"][0]["window_ends"]
    assert ends and all(e["start_heading_sigma"] == pytest.approx(0.01, rel=1e-12) for e in ends)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fitted = evaluate_logs([log], robot, [TruthOptions(tmp_path / "xy.csv", sigma=0.02)],
                               log_options=opts, window="10s")
    sigmas = [e["start_heading_sigma"] for e in fitted["per_log"][0]["window_ends"]]
    assert sigmas and all(0 < s < 0.5 for s in sigmas)
