"""``odomkit evaluate --window A --window B`` scores each length, and says which it scored;
the NEES line never prints a mean outside its bounds equal to a bound (user study, issue 11).

The facts checked: OptiOdom's built-in runs have truth over their whole time and move
throughout, so a log of duration D splits into floor(D / L) windows of L seconds; a length
scored among several gives what it gives alone; a printed mean and its bounds, read back,
stand in the order the verdict names.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 4)]
FIGURES = ("windows", "nees_position_mean", "nees_position_median", "nees_bounds", "coverage",
           "inside_95_fraction")


def _windows_of(length: float) -> int:
    """Windows of ``length`` seconds the runs hold: floor(duration / length) each."""
    total = 0
    for run in RUNS:
        t = np.loadtxt(run, delimiter=",", usecols=0)
        total += math.floor((t[-1] - t[0]) / length)
    return total


def _json(run_cli, *args):
    code, out, err = run_cli("evaluate", *RUNS, "--robot", ROBOT, *args, "--json")
    assert code == 0, err
    return json.loads(out)


def test_each_window_length_is_scored_and_named_in_the_json(run_cli):
    alone = {w: _json(run_cli, "--window", w) for w in ("10s", "30s")}
    assert alone["10s"]["window"] == "10 s" and alone["30s"]["window"] == "30 s"
    assert alone["10s"]["windows"] == _windows_of(10.0) and alone["30s"]["windows"] == _windows_of(30.0)
    both = _json(run_cli, "--window", "10s", "--window", "30s")
    # The top level is the first length's, as a single-window consumer reads it, and says so.
    assert both["window"] == "10 s"
    for key in FIGURES:
        assert both[key] == alone["10s"][key], key
    assert set(both["by_window"]) == {"10 s", "30 s"}
    for text, key in (("10s", "10 s"), ("30s", "30 s")):
        got = both["by_window"][key]
        assert got["window"] == key
        for figure in FIGURES:
            assert got[figure] == alone[text][figure], (key, figure)
        assert [p["windows"] for p in got["per_log"]] == [p["windows"] for p in alone[text]["per_log"]]
    # The whole-run figures do not depend on the window.
    assert both["ate_rmse"] == alone["30s"]["ate_rmse"] and both["rpe"] == alone["30s"]["rpe"]
    # Without --window the key is there too: one window per log.
    assert _json(run_cli)["window"] is None


def test_with_several_lengths_each_warning_says_which_length_it_is_about(run_cli):
    """The whole runs' warnings (no RPE over 100 m: the runs travel ~3 m) once, as they are;
    a length's own (fewer than 20 ends) after that length, with its own count."""
    args = ("evaluate", *RUNS, "--robot", ROBOT, "--window", "10s", "--window", "30s", "--rpe", "100")
    code, out, err = run_cli(*args, "--json")
    assert code == 0
    got = json.loads(out)
    said = [x.removeprefix("odomkit: warning: ") for x in err.splitlines()]
    assert said == got["warnings"]
    rpe = [w for w in said if "no RPE over 100 m" in w]
    assert len(rpe) == 1 and rpe[0].startswith(f"{len(RUNS)} logs (")
    ends = _windows_of(30.0)
    assert ends < 20 <= _windows_of(10.0)
    few = [w for w in said if "window end(s)" in w]
    assert len(few) == 1 and few[0].startswith(f"30 s windows: only {ends} window end(s)")
    assert any(w.startswith(f"only {ends} window end(s)") for w in got["by_window"]["30 s"]["warnings"])


def test_the_text_scores_each_length_in_a_block_that_names_it(run_cli):
    both = _json(run_cli, "--window", "30s", "--window", "10s")
    code, text, _ = run_cli("evaluate", *RUNS, "--robot", ROBOT, "--window", "30s", "--window", "10s")
    assert code == 0
    lines = text.splitlines()
    nees = [i for i, x in enumerate(lines) if x.startswith("position NEES over")]
    assert len(nees) == 2
    for at, key in zip(nees, ("30 s", "10 s"), strict=True):
        got = both["by_window"][key]
        assert f"over {got['windows']} window ends" in lines[at]
        # The block's header, the line before its numbers, names the length scored.
        assert key in lines[at - 1] and "window" in lines[at - 1]
        cover = lines[at + 1]
        assert cover.startswith("inside the predicted") and cover.endswith(f"{got['coverage']['0.99']:.3f}")
    # One length alone: its header names it as well.
    code, text, _ = run_cli("evaluate", *RUNS, "--robot", ROBOT, "--window", "30s")
    lines = text.splitlines()
    at = next(i for i, x in enumerate(lines) if x.startswith("position NEES over"))
    assert "30 s" in lines[at - 1]


def _printed(mean: float, lo: float, hi: float, capsys, per_log: bool = False) -> str:
    from odomkit.cli.evaluate import print_report
    from odomkit.evaluate import nees_verdict

    figures = {"rows_evaluated": 10, "rows_skipped": 0, "final_position_error": 0.1,
               "max_position_error": 0.2, "ate_rmse": 0.1, "rpe": {"1": 0.1}, "drift_percent": 1.0,
               "windows": 73, "nees_position_mean": mean, "nees_position_median": 1.0,
               "nees_bounds": [lo, hi], "coverage": {"0.5": 0.5, "0.9": 0.9, "0.95": 0.95, "0.99": 0.99},
               "inside_95_fraction": 0.95,
               # the verdict evaluate gives beside them, which the text says
               "nees_verdict": nees_verdict(mean, [lo, hi])}
    logs = [{"log": "a.csv", **figures}, {"log": "b.csv", **figures}] if per_log else [{"log": "a.csv"}]
    print_report({**figures, "window": "30 s", "per_log": logs}, windowed=True)
    return capsys.readouterr().out


def _read_back(line: str) -> tuple[float, float, float]:
    found = re.search(r"mean ([-\d.e+]+) \(95 % bounds ([-\d.e+]+)\.\.([-\d.e+]+)", line)
    assert found is not None, line
    mean, lo, hi = map(float, found.groups())
    return mean, lo, hi


def test_a_mean_outside_its_bounds_never_prints_equal_to_a_bound(capsys):
    """The study's case: mean 1.5659, lower bound 1.5677 (JSON), both '1.57' at 3 digits
    beside the verdict 'below its bounds'."""
    cases = [(1.5658883747724095, 1.5676807376027166, 2.4841666861550125, "below its bounds"),
             (2.4842, 1.5676807376027166, 2.4841666861550125, "above its bounds"),
             (1.5677, 1.5676807376027166, 2.4841666861550125, "inside its bounds"),
             (1.0000000001, 1.0000000002, 3.0, "below its bounds")]
    for mean, lo, hi, verdict in cases:
        line = next(x for x in _printed(mean, lo, hi, capsys).splitlines() if x.startswith("position NEES"))
        shown = _read_back(line)
        assert verdict in line
        if verdict.startswith("below"):
            assert shown[0] < shown[1], line
        elif verdict.startswith("above"):
            assert shown[0] > shown[2], line
        else:
            assert shown[1] <= shown[0] <= shown[2], line


def test_the_per_log_lines_do_not_round_a_mean_onto_its_bound(capsys):
    text = _printed(1.5658883747724095, 1.5676807376027166, 2.4841666861550125, capsys, per_log=True)
    per_log = [x for x in text.splitlines() if x.startswith("  a.csv: ")]
    assert len(per_log) == 1
    mean = float(re.search(r"NEES mean ([-\d.e+]+)", per_log[0]).group(1))  # type: ignore[union-attr]
    # The log's own bounds are not printed, but its mean read back keeps its side of them.
    assert mean < 1.5676807376027166 and abs(mean - 1.5658883747724095) < 5e-4
