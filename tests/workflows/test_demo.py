"""``odomkit demo``: its honesty table is what ``odomkit evaluate`` and ``odomkit fit-noise``
give on the same built-in files (independent paths through the code: the demo scores
window bases, evaluate dead-reckons every window again from the robot files the demo
wrote, fit-noise reads the logs through the log options), and the table is printed."""

from __future__ import annotations

import contextlib
import io
import json
import warnings

import numpy as np
import pytest

from odomkit.cli import main
from odomkit.data import OPTIODOM_EXPERIMENTS, builtin_experiment_path
from odomkit.io.robotfile import read_robot
from odomkit.plot import have_matplotlib
from odomkit.workflows.demo import FIT, FIT_WINDOW, HELD_OUT, SCORE_WINDOWS
from odomkit.workflows.evaluate import evaluate_logs
from odomkit.workflows.fit_noise import fit_noise_files
from odomkit.workflows.truth import TruthOptions

pytestmark = pytest.mark.slow

LEVELS = ("0.5", "0.9", "0.95", "0.99")


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """Run ``odomkit demo`` once: (output folder, stdout, summary.json)."""
    out = tmp_path_factory.mktemp("demo")
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        code = main(["demo", "--out", str(out), "--force"])
    assert code == 0
    return out, stdout.getvalue(), json.loads((out / "summary.json").read_text())


def _runs(experiments):
    return [p for e in experiments for p in sorted(builtin_experiment_path(e).glob("*_run-*.csv"))]


def test_fit_and_held_out_experiments_are_disjoint_and_cover_each_kind():
    assert not set(FIT) & set(HELD_OUT)
    assert set(FIT) | set(HELD_OUT) == set(OPTIODOM_EXPERIMENTS)
    kinds = {e: OPTIODOM_EXPERIMENTS[e][0] for e in OPTIODOM_EXPERIMENTS}
    each = ["circular", "free", "square"]
    assert sorted(kinds[e] for e in FIT) == sorted(kinds[e] for e in HELD_OUT) == each
    for e in OPTIODOM_EXPERIMENTS:  # every built-in experiment is there, metadata and runs
        folder = builtin_experiment_path(e)
        assert (folder / f"{e}_metadata.csv").is_file() and len(list(folder.glob(f"{e}_run-*.csv"))) >= 2


@pytest.mark.parametrize("window", SCORE_WINDOWS)
@pytest.mark.parametrize(("model", "robot_file"), [("guessed", "calibrated_robot.toml"),
                                                    ("white+bias", "fitted_robot.toml")])
def test_held_out_scores_equal_odomkit_evaluate(demo, model, robot_file, window):
    out, _, summary = demo
    runs = _runs(HELD_OUT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = evaluate_logs(runs, out / robot_file, [TruthOptions()] * len(runs), window=window)
    score = summary["noise_honesty"]["models"][model][window]
    assert got["windows"] == score["windows"] > 0
    for level in LEVELS:
        assert got["coverage"][level] == pytest.approx(score["coverage"][level], abs=1e-12)
    assert got["nees_position_mean"] == pytest.approx(score["nees_position_mean"], rel=1e-9)
    assert got["nees_bounds"] == pytest.approx(score["nees_bounds"], rel=1e-12)


def test_fitted_noise_is_fit_noise_on_the_fit_half_only(demo, tmp_path):
    out, _, summary = demo
    runs = _runs(FIT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # The demo holds the truth's own noise at zero (see FIT_WINDOW).
        result = fit_noise_files(out / "calibrated_robot.toml", runs,
                                 [TruthOptions(sigma=0.0, heading_sigma=0.0, time_sigma=0.0)] * len(runs),
                                 tmp_path / "refit.toml", window=FIT_WINDOW, kinds=("white", "bias"),
                                 trim=None)
    fitted = summary["noise_honesty"]["models"]["white+bias"]["parameters"]
    assert result["parameters"].keys() == fitted.keys()
    for key, value in fitted.items():
        assert result["parameters"][key] == pytest.approx(value, rel=1e-6, abs=1e-9)
    # and the robot file the demo wrote holds them
    _, models = read_robot(out / "fitted_robot.toml")
    written = {k: v for m in models for k, v in vars(m).items() if k in fitted}
    assert written == pytest.approx(fitted, rel=1e-12, abs=1e-15)


def test_the_guess_is_far_too_optimistic_and_the_fit_is_not(demo):
    """The demo's claims in the docs (getting-started.md, results/honesty.md), as measured
    (held out, 10 s windows)."""
    _, _, summary = demo
    rows = summary["noise_honesty"]["models"]
    guess, fit = rows["guessed"]["10s"], rows["white+bias"]["10s"]
    assert guess["coverage"]["0.95"] < 0.2 and guess["nees_position_mean"] > 50
    assert 0.88 <= fit["coverage"]["0.95"] <= 0.99
    assert 0.40 <= fit["coverage"]["0.5"] <= 0.80


def test_the_table_is_printed_with_where_the_outputs_went(demo):
    out, stdout, summary = demo
    rows = summary["noise_honesty"]["models"]
    for label, key in (("guessed (robot file)", "guessed"), ("fitted white + bias", "white+bias")):
        for window in SCORE_WINDOWS:
            c = rows[key][window]["coverage"]
            line = [ln for ln in stdout.splitlines() if ln.strip().startswith(label)
                    and f" {window[:-1]} s " in ln]
            assert len(line) == 1
            assert " / ".join(f"{c[k]:.2f}" for k in LEVELS) in line[0]
    assert f"outputs in {out.resolve()}" in stdout and "fitted_robot.toml" in stdout
    assert f"report: {(out / 'report.html').resolve()}" in stdout
    assert len(stdout.splitlines()) <= 12  # short: headline numbers, and where the report is
    for name in ("fitted_robot.toml", "calibrated_robot.toml", "summary.json", "report.html"):
        assert (out / name).is_file()


def _page(out):
    from tests.workflows.test_report import Page

    return Page((out / "report.html").read_text(encoding="utf-8"))


def test_the_report_shows_the_whole_product_offline(demo):
    from tests.workflows.test_report import network_references

    out, _, summary = demo
    page = _page(out)
    assert [h[0] for h in page.headings] == ["summary", "dead-reckoning", "prediction", "virtual-umbmark",
                                             "calibration", "honesty", "ros", "files"]
    assert network_references(page) == []
    assert summary["report"] == str(out / "report.html")
    if have_matplotlib():  # two runs, covariance elements, methods, Monte Carlo, two UMBmarks, honesty
        assert len(page.images) == 7
        assert all(i["src"].startswith("data:image/svg+xml;base64,") for i in page.images)


def test_the_report_numbers_are_the_summarys(demo):
    """Every number the page shows for the held-out test and the calibration is summary.json's."""
    out, _, summary = demo
    cells = _page(out).cells
    models = summary["noise_honesty"]["models"]
    compared = 0
    for key, rows in models.items():
        for window in SCORE_WINDOWS:
            for level in LEVELS:
                assert cells[f"{key}.{window}.coverage.{level}"][0] == rows[window]["coverage"][level]
                compared += 1
            assert cells[f"{key}.{window}.nees_position_mean"][0] == rows[window]["nees_position_mean"]
    cal = summary["calibration"]
    assert cells["calibration.exact.e_max_syst_before"][0] == cal["e_max_syst_before"]
    assert cells["calibration.exact.e_max_syst_after"][0] == cal["exact"]["e_max_syst_after"]
    assert cells["calibration.umbmark.e_max_syst_after"][0] == cal["umbmark"]["e_max_syst_after"]
    assert compared == 3 * 2 * 4


def test_the_prediction_is_checked_by_monte_carlo(demo):
    """The square's predicted σ is Chong–Kleeman's closed form, and the simulated runs agree."""
    _, _, summary = demo
    mc = summary["monte_carlo_one_square"]
    assert mc["verdict"] == "consistent" and mc["runs"] >= 1000
    se = 1 / np.sqrt(2 * (mc["runs"] - 1))  # relative standard error of a standard deviation
    for predicted, simulated in zip(mc["predicted_std"], mc["simulated_std"], strict=True):
        assert simulated == pytest.approx(predicted, rel=4 * se)
    assert np.array(mc["predicted_std"]) == pytest.approx(
        np.sqrt(np.diag(summary["prediction_one_square"]["cov"])), rel=1e-12)


def test_the_virtual_umbmark_finds_the_true_errors(demo):
    _, _, summary = demo
    v = summary["virtual_umbmark"]
    for k in ("E_d", "E_b"):  # first order, from 5 noisy runs each way: within a quarter of the error
        assert v["estimated"][k] == pytest.approx(v["true"][k], abs=0.25 * abs(v["true"][k] - 1))
    assert v["e_max_syst_after"] < v["e_max_syst_before"] / 5
