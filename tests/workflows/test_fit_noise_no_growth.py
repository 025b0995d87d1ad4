"""``odomkit fit-noise`` where the window ends' errors are the truth's noise alone (a user
study's RAV4 against a u-blox GPS, --truth-sigma 0.09): every noise parameter of the robot
fitted to zero, a written [noise] that predicts no growth of the odometry's error, and
nothing said but "too few windows". The fit must say so, in its warnings (text and JSON
alike), and where the given truth σ is well above the fixes' own scatter, that it may be too
large; its in-sample warning, pessimistic there, must point at that σ, not at the model family.

The logs are simulated (tests/conftest.py's ``noisy_diff_log``): a diff drive whose odometry
is exact (k = 0) against fixes with 0.01 m of white noise per axis, so that every window end's
error is the fixes' noise at its two ends; and the same drive with real wheel noise.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

ROBOT_TEXT = '[robot]\ntype = "diff"\nwheel_base = 0.4\nm_per_tick = 1\n'
COLUMNS = "t=t,dist_left=L,dist_right=R"
FIX_NOISE = 0.01  # the fixes' own white noise [m per axis]
NO_GROWTH = "every noise parameter of the robot's own models is fitted to zero"


def _fit(run_cli, folder, noisy_diff_log, k_true, *flags, seed=5):
    log, _, _ = noisy_diff_log(folder, k_true=k_true, k_model=k_true, seconds=200.0, seed=seed,
                               truth_noise=FIX_NOISE)
    robot = folder / "bare.toml"
    robot.write_text(ROBOT_TEXT)  # no [noise]: the diff drive's default white and bias models
    code, out, err = run_cli("fit-noise", "--robot", robot, "--log", log, "--truth", folder / "xy.csv",
                             "--columns", COLUMNS, "--window", "10s", *flags, "--out", folder / "fit.toml",
                             "--json")
    assert code == 0, err
    return json.loads(out), err, folder / "xy.csv"


def _robot_parameters(result):
    return {k: v for k, v in result["variances"].items() if result["kinds"][k] in ("white", "bias")}


def test_window_errors_within_a_given_truth_sigma_fit_the_robot_to_zero_and_are_warned_of(
        run_cli, tmp_path, noisy_diff_log):
    result, err, xy = _fit(run_cli, tmp_path, noisy_diff_log, 0.0, "--truth-sigma", "0.05")
    assert all(v == 0.0 for v in _robot_parameters(result).values()), result["variances"]
    said = [w for w in result["warnings"] if w.startswith(NO_GROWTH)]
    assert len(said) == 1, result["warnings"]
    note = said[0]
    assert "truth_sigma 0.05 m, given" in note and "predicts no growth" in note
    assert "longer windows" in note and "more logs" in note and "smaller --truth-sigma" in note
    # The window ends' errors it names: each is the fixes' noise at a window's two ends (its
    # start pose and heading are fitted to the fixes around it), about √2·0.01 m per axis.
    rms = float(note.split("RMS ")[1].split(" m")[0])
    assert 0.8 * np.sqrt(2) * FIX_NOISE < rms < 2.0 * np.sqrt(2) * FIX_NOISE, note
    # The fixes scatter about 0.01 m about a smooth path (odomkit.truth.scatter_sigma, by hand
    # here from the file): 0.05 m is five times that, and the σ given may be too large.
    from odomkit.truth import Truth, scatter_sigma

    fixes = np.loadtxt(xy, delimiter=",", skiprows=1)
    scatter = scatter_sigma(Truth(fixes[:, 0], fixes[:, 1:3]))
    assert scatter == pytest.approx(FIX_NOISE, rel=0.15)
    assert result["truth_scatter_sigma"] == pytest.approx(scatter, rel=1e-12)
    assert f"{scatter:.3g} m" in note and "may be too large" in note
    # The text output says it too (the warnings on stderr).
    assert NO_GROWTH in err
    # The in-sample coverage is pessimistic (every window end inside the 50 % ellipse): with
    # the robot's noise at zero what is left is the given σ, which the warning names.
    misfit = [w for w in result["warnings"] if w.startswith("in-sample coverage")]
    assert misfit and result["coverage_in_sample"]["0.5"] == 1.0, result["warnings"]
    assert "does not describe these logs" not in misfit[0]
    assert "truth_sigma 0.05 m, given" in misfit[0] and "too large" in misfit[0]


def test_a_given_truth_sigma_near_the_fixes_scatter_is_not_called_too_large(run_cli, tmp_path,
                                                                            noisy_diff_log):
    """The same exact odometry with a σ 1.5 times the fixes' given (under twice their scatter,
    odomkit.calibrate.fit_noise.GIVEN_ABOVE_SCATTER), white noise alone fitted: the robot's
    noise is still zero (every error is the fixes'), and said so, but the σ is not called too
    large. (At the fixes' own σ the fit puts a little of their noise in the wheels: k ≈ 0.003.)"""
    from odomkit.calibrate.fit_noise import GIVEN_ABOVE_SCATTER

    given = 1.5 * FIX_NOISE
    result, _, _ = _fit(run_cli, tmp_path, noisy_diff_log, 0.0, "--truth-sigma", str(given),
                        "--kinds", "white")
    assert given < GIVEN_ABOVE_SCATTER * result["truth_scatter_sigma"]
    assert all(v == 0.0 for v in _robot_parameters(result).values()), result["variances"]
    said = [w for w in result["warnings"] if w.startswith(NO_GROWTH)]
    assert len(said) == 1 and "may be too large" not in said[0], result["warnings"]


def test_real_odometry_noise_is_fitted_and_not_warned_of(run_cli, tmp_path, noisy_diff_log):
    """Wheel noise of k = 0.01 m^½ under the same fixes, their σ given: the wheels' k is fitted
    (within a factor of two of the truth) and nothing is said of a fit at zero."""
    result, err, _ = _fit(run_cli, tmp_path, noisy_diff_log, 0.01, "--truth-sigma", str(FIX_NOISE))
    k = np.sqrt([result["variances"]["k_left"], result["variances"]["k_right"]])
    assert np.sqrt(np.mean(k**2)) == pytest.approx(0.01, rel=0.5), result["variances"]
    assert not any(w.startswith(NO_GROWTH) for w in result["warnings"]), result["warnings"]
    assert NO_GROWTH not in err


def test_an_undetermined_fit_names_the_window_length_that_had_no_window(run_cli, tmp_path, noisy_diff_log):
    """A 25 s log fitted with --window 10s --window 30s: the 30 s length has no window, the 10 s
    ones are too few for the default models, and the fit is undetermined. A user study's half
    log was told only "2 window(s) give 4 numbers for 7 free noise parameter(s)"; the error now
    says the 30 s length had none."""
    log, _, _ = noisy_diff_log(tmp_path, k_true=0.01, k_model=0.01, seconds=25.0, truth_noise=FIX_NOISE)
    robot = tmp_path / "bare.toml"
    robot.write_text(ROBOT_TEXT)
    code, out, err = run_cli("fit-noise", "--robot", robot, "--log", log, "--truth", tmp_path / "xy.csv",
                             "--columns", COLUMNS, "--window", "10s", "--window", "30s",
                             "--out", tmp_path / "fit.toml")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "numbers for" in err and "free noise parameter" in err
    assert "--window 30 s: no log has a window of that length" in err


def test_cross_validation_gives_each_window_length_apart_and_names_groups(run_cli, tmp_path, noisy_diff_log):
    """--cross-validate pooled every --window length into one figure, which hid a length that
    failed (a user study's tricycle: 0.886 pooled, its 2 m windows 0.758 held out); with
    --group its text said "of 18 log(s)" and "leave-one-log-out" for 32 logs in 18 groups.
    Each length's figure is its own windows' share inside, and the pooled one their
    window-weighted mean."""
    logs, truths = [], []
    for seed in (1, 2, 3, 4):
        folder = tmp_path / f"run{seed}"
        folder.mkdir()
        log, _, _ = noisy_diff_log(folder, k_true=0.01, k_model=0.01, seconds=120.0, seed=seed,
                                   truth_noise=FIX_NOISE)
        logs += ["--log", log]
        truths += ["--truth", folder / "xy.csv"]
    robot = tmp_path / "bare.toml"
    robot.write_text(ROBOT_TEXT)
    common = ["fit-noise", "--robot", robot, *logs, *truths, "--columns", COLUMNS, "--window", "10s",
              "--window", "30s", "--cross-validate", "--kinds", "white", "--out", tmp_path / "fit.toml"]
    code, out, err = run_cli(*common, "--json")
    assert code == 0, err
    cv = json.loads(out)["cross_validation"]
    by = cv["by_length"]
    assert set(by) == {"10 s", "30 s"} and sum(x["windows"] for x in by.values()) == cv["windows"]
    for level in ("0.5", "0.95"):
        pooled = sum(x["coverage"][level] * x["windows"] for x in by.values()) / cv["windows"]
        assert cv["coverage"][level] == pytest.approx(pooled)
    code, out, err = run_cli(*common, "--group", "a", "--group", "a", "--group", "b", "--group", "b",
                             "--force")
    assert code == 0, err
    assert "of 4 log(s) in 2 group(s)" in out and "leave-one-group-out coverage (2 folds" in out
    assert "  10 s windows (" in out and "  30 s windows (" in out
