"""``odomkit evaluate`` and ``odomkit track --truth/--initial-cov`` end to end; bad input exits 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")
RUN2 = builtin_data_path("230620202042_run-02.csv")


def _gt(tmp_path, shift=(0.0, 0.0, 0.0), dt=0.0, heading=True, name="gt.csv"):
    """The run's own OptiTrack truth as a separate file, moved rigidly by ``shift`` and
    on a clock ``dt`` seconds ahead."""
    data = np.loadtxt(RUN, delimiter=",")
    c, s = np.cos(shift[2]), np.sin(shift[2])
    x = c * data[:, 1] - s * data[:, 2] + shift[0]
    y = s * data[:, 1] + c * data[:, 2] + shift[1]
    cols = [data[:, 0] + dt, x, y] + ([data[:, 3] + shift[2]] if heading else [])
    path = tmp_path / name
    np.savetxt(path, np.column_stack(cols), delimiter=",",
               header="t,x,y,theta" if heading else "t,x,y", comments="")
    return path


def test_text_reports_say_what_a_single_run_means(run_cli, tmp_path):
    code, _, _ = run_cli("track", RUN, "--robot", ROBOT, "--out", tmp_path / "t.csv")
    assert code == 0
    # The truth's own noise given: without it the first rows (standing, zero covariance) warn
    # that they make the NEES mean (tests/workflows/test_run_start.py).
    code, out, err = run_cli("evaluate", tmp_path / "t.csv", "--truth-sigma", "0.001")
    assert code == 0 and not err
    note = [line for line in out.splitlines() if line.startswith("note:")]
    assert len(note) == 1 and "one sample, not a statistic" in note[0] and "correlated" in note[0]
    code, out, _ = run_cli("evaluate", RUN, "--robot", ROBOT, "--window", "20s")
    assert code == 0 and "this is the test to trust" in out and "share its bias draw" in out
    # A log dead-reckoned from the truth without --window is one window: one sample, and the
    # report says so instead of calling it the test to trust.
    code, out, _ = run_cli("evaluate", RUN, "--robot", ROBOT, "--truth-sigma", "0.001")
    note = [line for line in out.splitlines() if line.startswith("note:")]
    assert code == 0 and len(note) == 1 and "one sample per log" in note[0] and "test to trust" in note[0]
    assert "this is the test to trust" not in out


def _per_log_lines(run_cli, window="10s"):
    """``evaluate`` of two built-in runs in 10 s windows (9 ends each; 2 s: 28): each log's
    JSON figures (per_log) and the text line the text report gives that log."""
    import json

    args = ("evaluate", RUN, RUN2, "--robot", ROBOT, "--window", window)
    code, out, _ = run_cli(*args)
    _, js, _ = run_cli(*args, "--json")
    assert code == 0
    return [(one, next(x for x in out.splitlines() if x.startswith(f"  {one['log']}: ")))
            for one in json.loads(js)["per_log"]]


def test_windowed_text_lists_each_logs_ends_when_there_are_several(run_cli):
    """Windows of one log share its bias draw, so coverage comes in lumps: with several logs
    the text lists each log's ends, coverage and NEES, the per_log figures of the JSON."""
    for one, line in _per_log_lines(run_cli):
        assert f"{one['windows']} ends" in line and f"NEES mean {one['nees_position_mean']:.3g}" in line
        assert f"{one['coverage']['0.95']:.2f} / {one['coverage']['0.5']:.2f}" in line
    code, out, _ = run_cli("evaluate", RUN, "--robot", ROBOT, "--window", "10s")
    assert code == 0 and not any(x.startswith(f"  {RUN}: ") for x in out.splitlines())


def test_each_logs_line_gives_its_heading_where_the_truth_has_one(run_cli, tmp_path):
    """The per-log lines of several logs give the heading's coverage, NEES mean and verdict
    beside the position's (the per_log figures of the JSON; a verdict from 20 ends or more:
    tests/cli/test_evaluate_per_log_few_ends.py), and nothing of a heading where the truth has
    positions only."""
    for one, line in _per_log_lines(run_cli, "2s"):
        assert one["windows"] >= 20 and one["few_ends"] is None
        c = one["coverage_heading"]
        assert (f"heading inside 95 % / 50 %: {c['0.95']:.2f} / {c['0.5']:.2f}, NEES mean "
                f"{one['nees_heading_mean']:.3g}, coverage {one['coverage_heading_overall']}") in line, line
        assert line.index(f"NEES mean {one['nees_position_mean']:.3g}") < line.index("heading")
    data = np.loadtxt(RUN2, delimiter=",")
    gt2 = tmp_path / "gt2.csv"
    np.savetxt(gt2, data[:, :3], delimiter=",", header="t,x,y", comments="")
    position_only = ("evaluate", RUN, RUN2, "--robot", ROBOT, "--window", "10s",
                     "--truth", _gt(tmp_path, heading=False), "--truth", gt2)
    code, out, _ = run_cli(*position_only)
    lines = [x for x in out.splitlines() if x.startswith("  ")]
    assert code == 0 and len(lines) == 2
    assert all("ends, inside 95 %" in x and "heading" not in x for x in lines), lines


def test_evaluate_json_keys(run_cli, tmp_path):
    code, out, _ = run_cli("evaluate", RUN, builtin_data_path("230620202042_run-02.csv"), "--robot", ROBOT,
                           "--window", "10s", "--rpe", "0.5,1", "--json")
    assert code == 0
    got = json.loads(out)
    keys = {"rows_evaluated", "rows_skipped", "final_position_error", "max_position_error", "ate_rmse", "rpe",
            "drift_percent", "windows", "nees_position_mean", "nees_position_median", "nees_bounds",
            "coverage", "inside_95_fraction"}
    # Added beside the DESIGN.md keys (none renamed): the honesty verdicts and the whole run's start.
    keys |= {"coverage_bounds", "coverage_verdict", "coverage_overall", "nees_verdict", "verdict_note",
             "start_time", "start_heading", "start_heading_sigma", "start_heading_fitted"}
    # And the heading's, where the truth has heading (OptiOdom runs have).
    keys |= {"nees_heading_mean", "nees_heading_median", "nees_heading_bounds", "coverage_heading",
             "coverage_heading_bounds", "coverage_heading_verdict", "coverage_heading_overall",
             "nees_heading_verdict", "verdict_heading_note"}
    assert set(got) == keys | {"window", "per_log", "warnings"} and got["window"] == "10 s"
    assert set(got["coverage"]) == {"0.5", "0.9", "0.95", "0.99"} and set(got["rpe"]) == {"0.5", "1"}
    assert set(got["coverage_bounds"]) == set(got["coverage_verdict"]) == set(got["coverage"])
    assert got["start_heading"] is None and not got["start_heading_fitted"]  # two logs: each in per_log
    assert [set(p) for p in got["per_log"]] == [keys | {"log", "window_ends", "few_ends", "warnings"}] * 2
    assert all(p["start_heading"] is not None and not p["start_heading_fitted"] for p in got["per_log"])
    assert [len(p["window_ends"]) for p in got["per_log"]] == [p["windows"] for p in got["per_log"]]
    assert set(got["per_log"][0]["window_ends"][0]) == {"start", "end", "error", "nees", "heading_error",
                                                         "nees_heading", "start_heading_sigma"}
    assert set(got["coverage_heading"]) == set(got["coverage_heading_verdict"]) == set(got["coverage"])
    assert got["nees_heading_mean"] is not None and got["coverage_heading_overall"] is not None
    assert got["windows"] == sum(p["windows"] for p in got["per_log"])


def test_track_truth_from_another_file_starts_there_and_is_carried(run_cli, tmp_path):
    gt = _gt(tmp_path, shift=(1.0, -2.0, 0.5), dt=0.0)
    code, out, _ = run_cli("track", RUN, "--robot", ROBOT, "--truth", gt, "--out", tmp_path / "a.csv",
                           "--json")
    assert code == 0
    a = json.loads(out)
    code, out, _ = run_cli("track", RUN, "--robot", ROBOT, "--initial-pose", "1,-2,0.5",
                           "--out", tmp_path / "b.csv", "--json")
    b = json.loads(out)
    assert a["pose"] == pytest.approx(b["pose"], abs=1e-12)
    table = np.genfromtxt(tmp_path / "a.csv", delimiter=",", names=True)
    data = np.loadtxt(gt, delimiter=",", skiprows=1)
    np.testing.assert_allclose(table["gt_x"], data[:, 1], atol=1e-15)
    err = np.hypot(table["x"] - table["gt_x"], table["y"] - table["gt_y"])
    assert a["final_position_error"] == pytest.approx(err[-1]) and a["max_position_error"] == pytest.approx(
        err.max())
    # the same figures through evaluate, from the carried gt_* columns
    code, out, _ = run_cli("evaluate", tmp_path / "a.csv", "--json")
    assert json.loads(out)["final_position_error"] == pytest.approx(err[-1])


def test_track_truth_on_a_later_clock_leaves_rows_out(run_cli, tmp_path):
    gt = _gt(tmp_path, dt=-2.0)  # truth ends 2 s before the log does
    code, out, _ = run_cli("track", RUN, "--robot", ROBOT, "--truth", gt, "--out", tmp_path / "a.csv",
                           "--json")
    assert code == 0
    table = np.genfromtxt(tmp_path / "a.csv", delimiter=",", names=True)
    assert np.isnan(table["gt_x"][-40:]).all() and np.isfinite(table["gt_x"][:-40]).all()
    inside = np.isfinite(table["gt_x"])
    err = np.hypot(table["x"] - table["gt_x"], table["y"] - table["gt_y"])[inside]
    assert json.loads(out)["final_position_error"] == pytest.approx(err[-1])


def test_track_initial_cov_three_or_nine_numbers(run_cli, tmp_path):
    for text, want in (("1e-4,2e-4,3e-4", np.diag([1e-4, 2e-4, 3e-4])),
                       ("1e-4,1e-5,0,1e-5,2e-4,0,0,0,3e-4",
                        [[1e-4, 1e-5, 0], [1e-5, 2e-4, 0], [0, 0, 3e-4]])):
        path = tmp_path / f"c{len(text)}.csv"
        code, _, _ = run_cli("track", RUN, "--robot", ROBOT, "--initial-cov", text, "--out", path)
        assert code == 0
        row = np.genfromtxt(path, delimiter=",", names=True)[0]
        got = [[row["cov_xx"], row["cov_xy"], row["cov_xtheta"]],
               [row["cov_xy"], row["cov_yy"], row["cov_ytheta"]],
               [row["cov_xtheta"], row["cov_ytheta"], row["cov_thetatheta"]]]
        np.testing.assert_allclose(got, want, rtol=1e-15)


def _standing(path, seconds):
    """The truth file at ``path`` with its robot held at its first position for ``seconds``."""
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    data[data[:, 0] - data[0, 0] < seconds, 1:3] = data[0, 1:3]
    np.savetxt(path, data, delimiter=",", header="t,x,y", comments="")
    return path


def test_track_position_only_truth_fits_the_start_heading(run_cli, tmp_path):
    """The robot stands still for its first second; the fixes over the next seconds (the
    heading fit widens its span until the heading is known to 0.05 rad) give the heading it
    stands at, within the variance the track starts with."""
    gt = _gt(tmp_path, shift=(0.0, 0.0, 1.0), heading=False)
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--truth", gt, "--out", tmp_path / "a.csv")
    assert code == 0, err
    first = np.genfromtxt(tmp_path / "a.csv", delimiter=",", names=True)[0]
    true = np.loadtxt(RUN, delimiter=",")[0, 3] + 1.0  # the run's own heading, turned as the fixes
    assert abs(first["theta"] - true) < 3 * np.sqrt(first["cov_thetatheta"]) + 1e-3
    assert abs(first["theta"] - true) < 0.05
    # Fixes that stand for 6 s support no heading within the widest span there: the track
    # starts where they first give one (tests/workflows/test_run_start.py); fixes that never
    # move give none anywhere, and the user must say.
    code, out, err = run_cli("track", RUN, "--robot", ROBOT, "--truth", _standing(gt, 6.0), "--json")
    assert code == 0 and any("the track starts at" in w for w in json.loads(out)["warnings"])
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--truth", _standing(gt, 1e9), "--json")
    assert code == 2 and "give --initial-pose" in err and len(err.strip().splitlines()) == 1


def test_position_only_truth_in_the_log_form_starts_once_the_fixes_give_a_heading(run_cli, tmp_path):
    gt = _gt(tmp_path, heading=False)
    code, out, err = run_cli("evaluate", RUN, "--robot", ROBOT, "--truth", gt, "--window", "10s",
                             "--truth-sigma", "0.001", "--json")
    assert code == 0, err
    got = json.loads(out)
    assert got["rpe"]["1"] is None and got["windows"] > 0
    # standing for its first second, the robot still gets its heading from the fixes after it
    assert got["rows_skipped"] == 0 and not any("starts at" in w for w in got["warnings"])
    code, out, err = run_cli("evaluate", RUN, "--robot", ROBOT, "--truth", _standing(gt, 6.0), "--window",
                             "10s", "--truth-sigma", "0.001", "--json")
    assert code == 0, err
    late = json.loads(out)
    assert any("starts at" in w for w in late["warnings"]) and late["rows_skipped"] > 20
    assert "odomkit: warning:" in err  # the same warnings on stderr
    # the truth's own file, with heading, skips nothing
    full = json.loads(run_cli("evaluate", RUN, "--robot", ROBOT, "--truth", _gt(tmp_path, name="h.csv"),
                              "--json")[1])
    assert full["rows_skipped"] == 0


@pytest.mark.parametrize(("args", "message"), [
    (["evaluate", "{track}", "--truth", "{late}"], "do not overlap in time"),
    (["evaluate", str(RUN), "--robot", str(ROBOT), "--truth", "{late}"], "do not overlap in time"),
    (["evaluate", str(RUN), "--robot", str(ROBOT), "--window", "10min"], "longer than the log"),
    (["evaluate", str(RUN), "--robot", str(ROBOT), "--window", "50m"], "longer than the log"),
    (["evaluate", "{still}", "--robot", str(ROBOT), "--window", "10s"], "no motion"),
    (["evaluate", "{track}", "--truth", "{nan}"], "line 3: column 2 is nan"),
    (["evaluate", "{track}", "--window", "10s"], "needs --robot"),
    (["evaluate", "{track}", "--align", "sim3"], "--align must be one of"),
    (["evaluate", "{track}", "--rpe", "-1"], "--rpe expects positive"),
    (["evaluate", "{track}", "--truth", "{late}", "--truth", "{late}"], "one --truth per log"),
    (["evaluate", str(RUN), "--robot", str(ROBOT), "--window", "ten"], "--window must be"),
    (["track", str(RUN), "--robot", str(ROBOT), "--truth", "{late}"], "do not overlap in time"),
    (["track", str(RUN), "--robot", str(ROBOT), "--initial-cov", "1,2"], "3 variances"),
    (["track", str(RUN), "--robot", str(ROBOT), "--initial-cov", "1,2,3,4,5,6,7,8,9"], "symmetric"),
    (["track", str(RUN), "--robot", str(ROBOT), "--truth-sigma", "-1"], "--truth-sigma"),
])
def test_bad_input_is_one_line_and_exit_2(run_cli, tmp_path, args, message):
    code, _, _ = run_cli("track", RUN, "--robot", ROBOT, "--out", tmp_path / "track.csv")
    assert code == 0
    _gt(tmp_path, dt=500.0, name="late.csv")
    (tmp_path / "nan.csv").write_text("t,x,y\n0,0,0\n0.05,nan,0\n0.1,0,0\n")
    data = np.loadtxt(RUN, delimiter=",")
    data[:, 4:] = 0.0
    still = tmp_path / "still_run-01.csv"  # an OptiOdom run name: read as OptiOdom
    np.savetxt(still, data, delimiter=",")
    argv = [a.format(track=tmp_path / "track.csv", late=tmp_path / "late.csv", nan=tmp_path / "nan.csv",
                     still=still) for a in args]
    code, out, err = run_cli(*argv)
    assert code == 2, (out, err)
    assert err.startswith("odomkit: error: ") and len(err.strip().splitlines()) == 1, err
    assert message in err and "Traceback" not in err


def test_every_command_says_the_same_about_a_truth_that_misses_the_log(run_cli, tmp_path):
    """One message, from odomkit.truth.no_overlap, naming both spans: track, evaluate (a
    track file, a log whole and in windows) and fit-noise, for a truth 500 s late; and a
    truth whose span covers the log but whose fixes leave only gaps there names --max-gap."""
    code, _, _ = run_cli("track", RUN, "--robot", ROBOT, "--out", tmp_path / "track.csv")
    assert code == 0
    late = _gt(tmp_path, dt=500.0, name="late.csv")
    said = set()
    for args in (["track", RUN, "--robot", ROBOT, "--truth", late],
                 ["evaluate", tmp_path / "track.csv", "--truth", late],
                 ["evaluate", RUN, "--robot", ROBOT, "--truth", late],
                 ["evaluate", RUN, "--robot", ROBOT, "--truth", late, "--window", "10s"],
                 ["fit-noise", "--robot", ROBOT, "--log", RUN, "--truth", late, "--window", "10s",
                  "--out", tmp_path / "fit.toml"]):
        code, _, err = run_cli(*args)
        assert code == 2 and len(err.strip().splitlines()) == 1, err
        said.add(err.split(": ", 3)[-1].strip())  # without the file the error names
    assert len(said) == 1, said
    (text,) = said
    t = np.loadtxt(RUN, delimiter=",")[:, 0]
    assert f"the log ({t[0]:.6g}..{t[-1]:.6g} s)" in text and "--truth-time-offset" in text
    sparse = tmp_path / "sparse.csv"  # 10 Hz fixes for 2 s before the log and 2 s after it
    times = np.concatenate((t[0] - 2 + 0.1 * np.arange(20), t[-1] + 0.1 + 0.1 * np.arange(20)))
    sparse.write_text("t,x,y,theta\n" + "".join(f"{x:.17g},0,0,0\n" for x in times))
    code, _, err = run_cli("evaluate", tmp_path / "track.csv", "--truth", sparse, "--max-gap", "1")
    assert code == 2 and "overlap, but" in err and "--max-gap" in err


def test_the_windowed_text_gives_the_nees_verdict_its_bounds_imply(run_cli):
    """Below, inside or above the χ² bounds, in words, on the line of numbers it judges
    (the report said so; the command line did not)."""
    import re

    code, text, _ = run_cli("evaluate", RUN, "--robot", ROBOT, "--window", "10s")
    assert code == 0
    line = next(x for x in text.splitlines() if x.startswith("position NEES over"))
    found = re.search(r"mean ([\d.e+]+) \(95 % bounds ([\d.e+]+)\.\.([\d.e+]+)", line)
    assert found is not None
    mean, lo, hi = map(float, found.groups())
    want = ("above its bounds" if mean > hi else "below its bounds" if mean < lo else "inside its bounds")
    assert line.endswith(want) or want + "," in line
    code, text, _ = run_cli("evaluate", RUN, "--robot", ROBOT)  # track rows: no verdict
    line = next(x for x in text.splitlines() if x.startswith("position NEES over"))
    assert "bounds," not in line and "its bounds" not in line
