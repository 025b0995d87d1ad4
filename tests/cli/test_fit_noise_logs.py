"""``odomkit fit-noise`` takes its logs as arguments, as ``calibrate`` and ``evaluate`` do, or
each with ``--log`` (user study, issue 11: ``fit-noise --robot R run1.csv run2.csv`` said only
"missing option '--log'"). The i-th ``--truth`` and ``--group`` belong to the i-th log either
way; the two forms together would leave that order unknown, so they are refused.
"""

from __future__ import annotations

import json

import numpy as np

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in (1, 2)]
FIT = ("--window", "20s", "--kinds", "white")


def _truth_file(run, path):
    """The run's own OptiTrack truth (columns t, x, y, θ of an OptiOdom run) as a file."""
    data = np.loadtxt(run, delimiter=",")
    np.savetxt(path, data[:, :4], delimiter=",", header="t,x,y,theta", comments="", fmt="%.17g")
    return path


def _fit(run_cli, tmp_path, name, *args):
    code, out, err = run_cli("fit-noise", "--robot", ROBOT, *args, *FIT, "--out", tmp_path / name, "--json")
    assert code == 0, err
    return json.loads(out)


def test_logs_given_as_arguments_fit_as_with_log(run_cli, tmp_path):
    truths = [_truth_file(run, tmp_path / f"gt{i}.csv") for i, run in enumerate(RUNS)]
    flagged = _fit(run_cli, tmp_path, "a.toml", "--log", RUNS[0], "--truth", truths[0],
                   "--log", RUNS[1], "--truth", truths[1])
    given = _fit(run_cli, tmp_path, "b.toml", *RUNS, "--truth", truths[0], "--truth", truths[1])
    assert given["parameters"] == flagged["parameters"]
    assert given["log_likelihood"] == flagged["log_likelihood"] and given["windows"] == flagged["windows"]
    assert (tmp_path / "b.toml").read_text() == (tmp_path / "a.toml").read_text()
    # The i-th --truth is the i-th argument's: swapped, each log meets the other run's truth.
    swapped = _fit(run_cli, tmp_path, "c.toml", *RUNS, "--truth", truths[1], "--truth", truths[0])
    assert swapped["log_likelihood"] != given["log_likelihood"]


def _one_error_line(run_cli, *args) -> str:
    code, out, err = run_cli("fit-noise", *args)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    return lines[0]


def test_both_forms_together_or_no_log_at_all_is_one_line_exit_2(run_cli, tmp_path):
    line = _one_error_line(run_cli, "--robot", ROBOT, "--log", RUNS[0], RUNS[1], *FIT,
                           "--out", tmp_path / "x.toml")
    assert "--log" in line and "argument" in line and "not both" in line
    line = _one_error_line(run_cli, "--robot", ROBOT, *FIT, "--out", tmp_path / "x.toml")
    assert "--log" in line and "argument" in line
    assert not (tmp_path / "x.toml").exists()
