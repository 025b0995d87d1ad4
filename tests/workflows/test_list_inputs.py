"""The workflow functions that take lists of logs take them as a Python user gives them
(user study s24, M7): one path (``str`` or ``Path``) is a list of one, not a sequence of
characters ("/: is a folder"); ``truth`` None is each log's own truth; a list of truth
options of the wrong length, or a log that is not a path, is one :class:`InputError` line,
not "zip() argument 2 is shorter than argument 1".
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.errors import InputError
from odomkit.workflows.evaluate import evaluate_logs, evaluate_tracks, score_logs
from odomkit.workflows.fit_amcl import fit_amcl_files
from odomkit.workflows.fit_noise import fit_noise_files
from odomkit.workflows.results import paths_given, truths_per_log
from odomkit.workflows.truth import TruthOptions

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in (1, 2)]


def _one_line(exc: pytest.ExceptionInfo[InputError]) -> str:
    text = str(exc.value)
    assert "\n" not in text and "zip()" not in text
    return text


def test_a_single_path_is_a_list_of_one_and_truth_none_is_each_logs_own():
    as_list = evaluate_logs([RUN], ROBOT, [TruthOptions()], window="10s")
    for given in (str(RUN), RUN):
        alone = evaluate_logs(given, ROBOT, window="10s")
        assert alone["windows"] == as_list["windows"] > 0
        assert alone["nees_position_mean"] == as_list["nees_position_mean"]
        assert alone["per_log"][0]["log"] == as_list["per_log"][0]["log"]
    # One TruthOptions is every log's.
    both = evaluate_logs(RUNS, ROBOT, TruthOptions(), window="10s")
    assert both["windows"] == evaluate_logs(RUNS, ROBOT, [TruthOptions()] * 2, window="10s")["windows"]
    scored = score_logs(str(RUN), ROBOT, window="10s")
    assert len(scored) == 1 and scored[0].windows == as_list["windows"]


def test_fit_noise_files_takes_one_path_and_no_truth_options(tmp_path):
    listed = fit_noise_files(ROBOT, [RUN], [TruthOptions()], tmp_path / "a.toml", window="10s",
                             kinds=("white",))
    alone = fit_noise_files(ROBOT, str(RUN), None, tmp_path / "b.toml", window="10s", kinds=("white",))
    assert alone["parameters"] == listed["parameters"] and alone["windows"] == listed["windows"]


def test_evaluate_tracks_and_fit_amcl_take_one_path(tmp_path):
    track = tmp_path / "track.csv"
    t = np.arange(0.0, 10.0, 0.1)
    poses = np.column_stack((0.1 * t, np.zeros_like(t), np.zeros_like(t)))
    truth = poses + [0.01, 0.02, 0.0]
    rows = np.column_stack((t, poses, truth))
    track.write_text("t,x,y,theta,gt_x,gt_y,gt_theta\n"
                     + "\n".join(",".join(repr(float(v)) for v in row) for row in rows) + "\n")
    one = evaluate_tracks(str(track))
    assert one["rows_evaluated"] == t.size
    assert one["final_position_error"] == pytest.approx(np.hypot(0.01, 0.02), rel=1e-12)
    amcl = fit_amcl_files(str(RUN), robot_path=ROBOT)
    assert amcl["updates"] == fit_amcl_files([RUN], [TruthOptions()], robot_path=ROBOT)["updates"] > 0


def test_a_truth_list_of_the_wrong_length_is_one_line():
    with pytest.raises(InputError) as exc:
        evaluate_logs([RUN], ROBOT, [])
    line = _one_line(exc)
    assert "1 log(s)" in line and "0 TruthOptions" in line
    with pytest.raises(InputError) as exc:
        evaluate_tracks([RUN, RUN], [TruthOptions()] * 3)
    assert "2 track(s)" in _one_line(exc)
    with pytest.raises(InputError) as exc:
        fit_amcl_files([RUN], [TruthOptions()] * 2, robot_path=ROBOT)
    assert "1 file(s)" in _one_line(exc)


def test_a_log_that_is_not_a_path_is_one_line_naming_the_in_memory_function(tmp_path):
    from odomkit.io.optiodom import read_run

    log = read_run(RUN)
    with pytest.raises(InputError) as exc:
        evaluate_logs([log], ROBOT)
    line = _one_line(exc)
    assert "OdometryLog" in line and "evaluate_in_memory" in line
    with pytest.raises(InputError) as exc:
        fit_noise_files(ROBOT, log, None, tmp_path / "x.toml")
    assert "fit_noise_in_memory" in _one_line(exc)
    with pytest.raises(InputError) as exc:
        evaluate_logs([], ROBOT)
    assert "no log" in _one_line(exc)


def test_the_helpers_themselves():
    assert paths_given("a.csv") == ["a.csv"]
    assert paths_given(["a.csv", "b.csv"]) == ["a.csv", "b.csv"]
    assert paths_given(builtin_data_path("optiodom_diff.toml")) == [ROBOT]
    opts = TruthOptions(sigma=0.01)
    assert truths_per_log(None, 2) == [TruthOptions(), TruthOptions()]
    assert truths_per_log(opts, 3) == [opts] * 3
    assert truths_per_log([opts, TruthOptions()], 2) == [opts, TruthOptions()]
    with pytest.raises(InputError, match=r"^give one TruthOptions per log: 2 log\(s\), 1 TruthOptions"):
        truths_per_log([opts], 2)
    with pytest.raises(InputError, match="TruthOptions"):
        truths_per_log(["gt.csv"], 1)  # type: ignore[list-item]


def test_calibrate_and_umbmark_take_one_path_as_a_list_of_one():
    import warnings

    from odomkit.workflows.calibration import calibrate_files
    from odomkit.workflows.umbmark import umbmark_from_files

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        listed = calibrate_files([RUN], ROBOT, source="trajectory")
        alone = calibrate_files(str(RUN), ROBOT, source="trajectory")
    assert alone["robot"] == listed["robot"]
    # UMBmark needs both directions: one run is its error, not "/: is a folder".
    with pytest.raises(InputError) as first:
        umbmark_from_files([RUN], ROBOT, 0.75)
    with pytest.raises(InputError) as second:
        umbmark_from_files(str(RUN), ROBOT, 0.75)
    assert str(second.value) == str(first.value)
