"""``--plot FILE`` on every command (odomkit.workflows.figures): a readable file of the
format the suffix names, a PNG that is not blank, the path in the JSON; an existing file
refused without --force and a missing matplotlib named, each on one line with exit 2."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]
MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "svg": b"<?xml", "pdf": b"%PDF-"}
DIFF = ["--wheel-base", "0.4", "--k-left", "0.001", "--k-right", "0.001"]


def _errors_csv():
    return Path(__file__).resolve().parents[1] / "golden" / "inputs" / "errors.csv"


def _commands(tmp_path):
    """Each command with --plot: (name, argv before --plot, suffix, JSON path to the plot)."""
    track_csv = tmp_path / "track.csv"
    return {
        "track": (["track", RUNS[0], "--robot", ROBOT], "png", ("outputs", "plot")),
        "predict": (["predict", "--segment", "straight:1", "--segment", "arc:1,1.5", *DIFF], "svg",
                    ("outputs", "plot")),
        "simulate": (["simulate", "--segment", "arc:1,1.5", *DIFF, "--runs", "300", "--partitions", "20"],
                     "pdf", ("outputs", "plot")),
        "umbmark": (["umbmark", _errors_csv(), "--side", "4", "--wheel-base", "0.34"], "png",
                    ("outputs", "plot")),
        "umbmark --runs": (["umbmark", "--runs", *RUNS, "--robot", ROBOT, "--side", "0.75"], "png",
                           ("outputs", "plot")),
        "calibrate": (["calibrate", *RUNS, "--robot", ROBOT, "--side", "0.75"], "png", ("outputs", "plot")),
        "calibrate-noise": (["calibrate-noise", *RUNS[:3], "--robot", ROBOT], "svg", ("plot",)),
        "evaluate": (["evaluate", track_csv], "png", ("outputs", "plot")),
        "evaluate --window": (["evaluate", *RUNS[:2], "--robot", ROBOT, "--window", "10s"], "png",
                              ("outputs", "plot")),
        "fit-noise": (["fit-noise", "--robot", ROBOT, "--log", RUNS[0], "--log", RUNS[1], "--log", RUNS[2],
                       "--window", "10s", "--kinds", "white,bias", "--out", tmp_path / "fitted.toml"], "png",
                      ("outputs", "plot")),
        "fit-amcl": (["fit-amcl", *RUNS[:2], "--robot", ROBOT], "png", ("outputs", "plot")),
    }


NAMES = list(_commands(Path(".")))


def _one_line_error(code, err, message):
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    assert message in lines[0], err


@pytest.mark.parametrize("name", NAMES)
def test_plot_writes_a_readable_figure(run_cli, tmp_path, name, png_is_drawn):
    if name == "evaluate":
        assert run_cli("track", RUNS[0], "--robot", ROBOT, "--out", tmp_path / "track.csv")[0] == 0
    argv, suffix, where = _commands(tmp_path)[name]
    target = tmp_path / f"figure.{suffix}"
    code, out, err = run_cli(*argv, "--plot", target, "--json")
    assert code == 0, err
    data = json.loads(out)
    for key in where:
        data = data[key]
    assert data == str(target)
    assert target.read_bytes().startswith(MAGIC[suffix])
    if suffix == "png":
        assert png_is_drawn(target)
    elif suffix == "svg":
        assert b"<svg" in target.read_bytes()[:2000]


@pytest.mark.parametrize("name", NAMES)
def test_an_existing_plot_is_refused_up_front_without_force(run_cli, tmp_path, name):
    argv, suffix, _ = _commands(tmp_path)[name]
    if name == "evaluate":
        argv = ["evaluate", RUNS[0], "--truth", RUNS[0]]  # refused before the file is read
    target = tmp_path / f"mine.{suffix}"
    target.write_bytes(b"not yours")
    code, _, err = run_cli(*argv, "--plot", target)
    _one_line_error(code, err, "exists already; pass --force to replace it")
    assert target.read_bytes() == b"not yours"
    assert not (tmp_path / "fitted.toml").exists()  # nothing else was written either


@pytest.mark.parametrize("name", ["track", "predict", "umbmark", "calibrate"])
def test_a_missing_matplotlib_is_one_line_naming_the_extra(run_cli, tmp_path, monkeypatch, name):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    argv, suffix, _ = _commands(tmp_path)[name]
    code, _, err = run_cli(*argv, "--plot", tmp_path / f"f.{suffix}")
    _one_line_error(code, err, "--plot needs matplotlib: pip install 'odomkit[plot]'")
    assert not (tmp_path / f"f.{suffix}").exists()


def test_an_unknown_format_is_one_line(run_cli, tmp_path):
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--plot", tmp_path / "f.jpg")
    _one_line_error(code, err, "--plot writes .png, .svg or .pdf")


def test_the_simulate_figure_redraws_the_experiments_own_runs():
    """The figure simulates the first runs again with the experiment's seed: the same
    numbers, so its points are the experiment's (here all of them: the means agree)."""
    from odomkit.noise import WheelNoise
    from odomkit.path import Arc
    from odomkit.simulate import monte_carlo, simulate_runs

    path, noise = [Arc(1.0, 1.5)], WheelNoise(1e-3, 1e-3)
    result = monte_carlo(path, noise, 0.4, runs=700, partitions=20, seed=11)
    again = simulate_runs(path, noise, 0.4, runs=700, partitions=20, seed=result["seed"],
                          engine=result["engine"])
    assert np.allclose(again.final.mean(axis=0), result["simulation"]["mean"], rtol=0, atol=1e-12)
    first = simulate_runs(path, noise, 0.4, runs=300, partitions=20, seed=11, engine=result["engine"])
    assert np.array_equal(first.final[:256], again.final[:256])  # whole blocks of 256 runs


def _capture(monkeypatch, name):
    """Replace a figure of odomkit.workflows.figures by one that records what it is given."""
    import odomkit.workflows.figures as figures

    seen: dict = {}

    def record(path, *args, **kwargs):
        seen.update(kwargs)
        Path(path).write_bytes(b"")
        return Path(path)

    monkeypatch.setattr(figures, name, record)
    return seen


def _robot_file(path, bias):
    text = ROBOT.read_text().split("[noise]")[0]
    text += "[noise]\nk_left = 0.0045\nk_right = 0.006\n"
    if bias:
        text += "\n[noise.parameters]\nsigma_scale_left = 0.003\nsigma_scale_right = 0.002\nmode = \"bias\"\n"
    path.write_text(text)
    return path


def test_evaluate_shows_the_white_models_alone_beside_white_and_bias(monkeypatch, tmp_path):
    """The white-only series is what scoring a robot file with only the white models gives."""
    from odomkit.workflows.evaluate import evaluate_logs
    from odomkit.workflows.truth import TruthOptions

    seen = _capture(monkeypatch, "honesty_figure")
    truth = [TruthOptions()] * 3
    both = evaluate_logs(RUNS[:3], _robot_file(tmp_path / "both.toml", True), truth, window="10s",
                         plot=tmp_path / "f.png")
    white = evaluate_logs(RUNS[:3], _robot_file(tmp_path / "white.toml", False), truth, window="10s")
    # The heading's intervals too, where the truth has a heading (OptiOdom's does).
    assert seen["coverages"] == {"window ends (white + bias)": both["coverage"],
                                 "window ends (white only)": white["coverage"],
                                 "window ends (white + bias), heading": both["coverage_heading"]}
    assert both["windows"] == white["windows"]
    assert seen["n_scored"] == {"window ends (white + bias)": both["windows"],
                                "window ends (white only)": both["windows"],
                                "window ends (white + bias), heading": both["windows"]}
    assert both["coverage"] != white["coverage"]  # the bias widens the ellipses


def test_fit_noise_refits_white_only_beside_white_and_bias(monkeypatch, tmp_path):
    """The white-only coverage is that of ``fit-noise --kinds white`` on the same logs."""
    from odomkit.workflows.fit_noise import fit_noise_files
    from odomkit.workflows.truth import TruthOptions

    seen = _capture(monkeypatch, "profiles_figure")
    logs, truth = RUNS[:3], [TruthOptions()] * 3
    both = fit_noise_files(ROBOT, logs, truth, tmp_path / "b.toml", window="10s", kinds=("white", "bias"),
                           plot=tmp_path / "f.png")
    white = fit_noise_files(ROBOT, logs, truth, tmp_path / "w.toml", window="10s", kinds=("white",))
    assert seen["coverages"] == {"white + bias (this fit)": both["coverage_in_sample"],
                                 "white only (refitted, bias zero)": white["coverage_in_sample"]}
    assert seen["n_scored"] == both["windows"]


def test_evaluate_plots_no_heading_series_for_position_only_truth(monkeypatch, tmp_path):
    from odomkit.io.optiodom import read_run
    from odomkit.workflows.evaluate import evaluate_logs
    from odomkit.workflows.truth import TruthOptions

    log = read_run(RUNS[0])
    xy = tmp_path / "xy.csv"
    np.savetxt(xy, np.column_stack((log.t, log.ground_truth[:, :2])), delimiter=",", header="t,x,y",
               comments="")
    seen = _capture(monkeypatch, "honesty_figure")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = evaluate_logs(RUNS[:1], _robot_file(tmp_path / "white.toml", False), [TruthOptions(xy)],
                            window="10s", plot=tmp_path / "f.png")
    assert out["coverage_heading"] is None
    assert seen["coverages"] == {"window ends": out["coverage"]}
    assert seen["n_scored"] == {"window ends": out["windows"]}
