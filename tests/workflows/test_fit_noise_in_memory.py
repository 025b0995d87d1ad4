"""The noise fit and the honesty test for logs already in memory (user study s24, H3 and M1):
:func:`fit_noise_in_memory` and :func:`evaluate_in_memory` give what ``odomkit fit-noise``
and ``odomkit evaluate`` give for the same data in files, with the command's defaults
(trimmed, the truth's noise fitted), checked against the CLI's JSON to 1e-12; the core's
building blocks with their own defaults give another model, and say so in their docstrings.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive
from odomkit.truth import Truth
from odomkit.workflows.evaluate import evaluate_in_memory
from odomkit.workflows.fit_noise import FittedNoise, fit_noise_in_memory

COLUMNS = "t=t,dist_left=L,dist_right=R"
ROBOT_TEXT = '[robot]\ntype = "diff"\nwheel_base = 0.4\nm_per_tick = 1\n'
WINDOWS = ("10s", "30s")


def _same(cli, ours, path="result"):
    """``ours`` (a Python result) equals ``cli`` (the command's JSON) key by key: the same
    keys and strings, numbers to 1e-12 relative (inf in Python is null in JSON)."""
    if isinstance(cli, dict):
        assert isinstance(ours, dict) and list(cli) == list(ours), (path, sorted(set(cli) ^ set(ours)))
        for key in cli:
            _same(cli[key], ours[key], f"{path}.{key}")
    elif isinstance(cli, list):
        assert isinstance(ours, list | tuple) and len(cli) == len(ours), path
        for i, (a, b) in enumerate(zip(cli, ours, strict=True)):
            _same(a, b, f"{path}[{i}]")
    elif cli is None:
        assert ours is None or (isinstance(ours, float) and math.isinf(ours)), (path, ours)
    elif isinstance(cli, bool) or isinstance(cli, str):
        assert cli == ours, (path, cli, ours)
    else:
        assert ours == pytest.approx(cli, rel=1e-12, abs=1e-300), (path, cli, ours)


def _quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


@pytest.fixture()
def three_logs(tmp_path, noisy_diff_log):
    """Three simulated diff-drive logs of known wheel noise in files, and the same numbers as
    arrays: (log paths, truth paths, OdometryLogs, Truths)."""
    paths, gts, logs, truths = [], [], [], []
    for seed in (1, 2, 3):
        folder = tmp_path / f"run{seed}"
        folder.mkdir()
        log_path, gt_path, _ = noisy_diff_log(folder, k_true=0.01, k_model=0.01, seconds=300.0, seed=seed)
        rows = np.loadtxt(log_path, delimiter=",", skiprows=1)  # written with 18 digits: exact
        gt = np.loadtxt(gt_path, delimiter=",", skiprows=1)
        paths.append(log_path)
        gts.append(gt_path)
        logs.append(OdometryLog(rows[:, 0], {"dist_left": rows[:, 1], "dist_right": rows[:, 2]},
                                source=str(log_path)))
        truths.append(Truth(gt[:, 0], gt[:, 1:3], gt[:, 3], source=str(gt_path)))
    return paths, gts, logs, truths


def _truth_args(gts):
    return [a for gt in gts for a in ("--truth", gt)]


def test_the_fit_and_the_honesty_test_in_memory_equal_the_commands(three_logs, tmp_path, run_cli):
    paths, gts, logs, truths = three_logs
    robot_file = tmp_path / "robot.toml"
    robot_file.write_text(ROBOT_TEXT)  # no [noise]: the defaults for a diff drive are fitted
    windows = [a for w in WINDOWS for a in ("--window", w)]
    code, out, err = run_cli("fit-noise", "--robot", robot_file, *paths, *_truth_args(gts),
                             "--columns", COLUMNS, *windows, "--out", tmp_path / "cli.toml", "--json")
    assert code == 0, err
    cli = json.loads(out)
    fitted = _quiet(fit_noise_in_memory, logs, DiffDrive(0.4), truths=truths, window=list(WINDOWS))
    assert isinstance(fitted, FittedNoise)
    _same({k: v for k, v in cli.items() if k not in ("outputs", "seconds")}, fitted.summary)
    # The command's defaults, not the building blocks': trimmed at 0.999, the truth's noise fitted.
    assert fitted.summary["trim"] == 0.999
    assert {"truth_sigma", "truth_heading_sigma", "truth_time_sigma"} <= set(fitted.summary["parameters"])
    # The fitted robot file is the command's, byte for byte.
    written = fitted.write(tmp_path / "py.toml")
    assert written.read_text() == (tmp_path / "cli.toml").read_text()

    code, out, err = run_cli("evaluate", *paths, "--robot", tmp_path / "cli.toml", *_truth_args(gts),
                             "--columns", COLUMNS, *windows, "--json")
    assert code == 0, err
    scored = _quiet(evaluate_in_memory, logs, fitted.robot, fitted.noise, truths, truth_noise=fitted.truth,
                    window=list(WINDOWS))
    _same(json.loads(out), scored)
    assert set(scored["by_window"]) == {"10 s", "30 s"}


def test_the_building_blocks_with_their_own_defaults_give_another_model(three_logs):
    """What the user study chained by hand: log_window_basis and fit_noise with their own
    defaults (no truth columns, no trimming) fit a different model than the command; with
    the command's settings given they fit the same one."""
    from odomkit.calibrate.fit_noise import DEFAULT_FIXED, DEFAULT_TRIM, fit_noise, models_to_fit
    from odomkit.window_errors import log_window_basis
    from odomkit.windows import parse_windows

    _, _, logs, truths = three_logs
    robot = DiffDrive(0.4)
    fitted = _quiet(fit_noise_in_memory, logs, robot, truths=truths, window=list(WINDOWS))
    models, fixed = models_to_fit(robot, (), ("white", "bias"))
    specs = parse_windows(list(WINDOWS))

    def by_hand(columns, **kwargs):
        bases = [log_window_basis(log, robot, models, truth, specs, truth_columns=columns)[0]
                 for log, truth in zip(logs, truths, strict=True)]
        return _quiet(fit_noise, bases, models, robot, kinds=("white", "bias"), fixed=fixed | DEFAULT_FIXED,
                      log_names=[log.source for log in logs], **kwargs)

    same = by_hand(True, trim=DEFAULT_TRIM)
    assert same.parameters == pytest.approx(fitted.fit.parameters, rel=1e-12)
    other = by_hand(False)
    assert "truth_sigma" not in other.parameters and other.trim is None


def test_the_core_docstrings_say_they_are_building_blocks():
    from odomkit.calibrate.fit_noise import fit_noise
    from odomkit.window_errors import log_window_basis

    for fn in (fit_noise, log_window_basis):
        doc = " ".join((fn.__doc__ or "").split())
        assert "building block" in doc and "fit_noise_in_memory" in doc, fn.__name__
    assert "no trimming" in " ".join((fit_noise.__doc__ or "").split())
    assert "no truth-noise columns" in " ".join((log_window_basis.__doc__ or "").split())


def test_on_optiodom_runs_the_in_memory_fit_equals_the_command(data_dir, tmp_path, run_cli):
    """Three runs of one OptiOdom square experiment read by odomkit.io's reader: the fit in
    memory equals ``odomkit fit-noise`` on the files, and the honesty test on two held-out
    runs equals ``odomkit evaluate``."""
    from odomkit.data import builtin_data_path
    from odomkit.io.optiodom import read_run
    from odomkit.io.robotfile import read_robot

    folder = data_dir / "optiodom" / "diff" / "square"
    fit_runs = sorted((folder / "231220200029").glob("*_run-0[123].csv"))
    held = sorted((folder / "231220200040").glob("*_run-0[12].csv"))
    if len(fit_runs) < 3 or len(held) < 2:
        pytest.skip("the OptiOdom square runs 231220200029 and 231220200040 are not in the data folder")
    text = builtin_data_path("optiodom_diff.toml").read_text()
    robot_file = tmp_path / "robot.toml"
    robot_file.write_text(text.split("[noise]")[0])  # the defaults fitted, as the study's CLI run did
    robot = read_robot(robot_file)[0]
    code, out, err = run_cli("fit-noise", "--robot", robot_file, *fit_runs, "--window", "10s",
                             "--out", tmp_path / "cli.toml", "--json")
    assert code == 0, err
    fitted = _quiet(fit_noise_in_memory, [read_run(p) for p in fit_runs], robot, window="10s")
    _same({k: v for k, v in json.loads(out).items() if k not in ("outputs", "seconds")}, fitted.summary)
    code, out, err = run_cli("evaluate", *held, "--robot", tmp_path / "cli.toml", "--window", "10s", "--json")
    assert code == 0, err
    scored = _quiet(evaluate_in_memory, [read_run(p) for p in held], fitted.robot, fitted.noise,
                    truth_noise=fitted.truth, window="10s")
    _same(json.loads(out), scored)


def test_in_memory_input_mistakes_are_one_line(three_logs):
    paths, _, logs, truths = three_logs
    robot = DiffDrive(0.4)
    with pytest.raises(InputError, match="for log files use odomkit.workflows.evaluate.evaluate_logs"):
        evaluate_in_memory(paths, robot, ())
    with pytest.raises(InputError, match=r"give one Truth per log: 3 log\(s\), 1 truth"):
        evaluate_in_memory(logs, robot, (), [truths[0]])
    with pytest.raises(InputError, match="no truth: the log has no ground truth"):
        fit_noise_in_memory(logs[0], robot)
    with pytest.raises(InputError, match="no noise model given"):
        evaluate_in_memory(logs, robot, None, truths, window="10s")
    with pytest.raises(InputError, match="time_offset"):
        evaluate_in_memory(logs, robot, (), truths, truth_noise={"sigma": 0.0, "time_offset": 0.2})


def test_a_noise_naming_its_white_models_is_told_which_defaults_it_leaves_out(three_logs):
    from odomkit.noise import WheelNoise

    _, _, logs, truths = three_logs
    fitted = _quiet(fit_noise_in_memory, logs[:2], DiffDrive(0.4), WheelNoise(0.0, 0.0), truths[:2],
                    window="30s", kinds=("white",))
    [note] = [w for w in fitted.summary["warnings"] if "names its white models (WheelNoise)" in w]
    assert note.startswith("the noise given") and "SpeedNoise(alpha_ss=0)" in note
    assert "LateralSlipNoise(alpha_lateral=0)" in note


def test_the_in_memory_defaults_are_the_file_forms_and_the_commands():
    """Defaults no data above exercise (max_gap without gaps): each in-memory function's are
    those of its file form, and max_gap the truth options' (the CLI's --max-gap)."""
    import inspect

    from odomkit.workflows.evaluate import evaluate_logs
    from odomkit.workflows.fit_noise import fit_noise_files
    from odomkit.workflows.truth import TruthOptions

    for memory, files in ((fit_noise_in_memory, fit_noise_files), (evaluate_in_memory, evaluate_logs)):
        ours, theirs = (inspect.signature(f).parameters for f in (memory, files))
        shared = set(ours) & set(theirs) - {"logs", "truths", "truth"}
        assert shared and all(ours[k].default == theirs[k].default for k in shared), memory.__name__
        assert ours["max_gap"].default == TruthOptions().max_gap


def test_logs_in_memory_prepared_in_worker_processes_give_the_same_fit(three_logs):
    _, _, logs, truths = three_logs
    alone = _quiet(fit_noise_in_memory, logs, DiffDrive(0.4), truths=truths, window="30s", kinds=("white",),
                   workers=1)
    spread = _quiet(fit_noise_in_memory, logs, DiffDrive(0.4), truths=truths, window="30s", kinds=("white",),
                    workers=2)
    assert spread.summary == alone.summary


def test_position_only_truth_with_its_noise_held_equals_the_command(tmp_path, noisy_diff_log, run_cli):
    """A truth without heading whose noise is known: ``--truth-sigma`` holds it and weighs the
    fixes the start headings are fitted to; ``truth_held`` does the same in memory."""
    paths, xys, logs, truths = [], [], [], []
    for seed in (4, 5):
        folder = tmp_path / f"run{seed}"
        folder.mkdir()
        log_path, _, _ = noisy_diff_log(folder, k_true=0.01, k_model=0.01, seconds=200.0, seed=seed,
                                        truth_noise=0.01)
        rows = np.loadtxt(log_path, delimiter=",", skiprows=1)
        xy = np.loadtxt(folder / "xy.csv", delimiter=",", skiprows=1)
        paths.append(log_path)
        xys.append(folder / "xy.csv")
        logs.append(OdometryLog(rows[:, 0], {"dist_left": rows[:, 1], "dist_right": rows[:, 2]},
                                source=str(log_path)))
        truths.append(Truth(xy[:, 0], xy[:, 1:3], source=str(folder / "xy.csv")))
    robot_file = tmp_path / "robot.toml"
    robot_file.write_text(ROBOT_TEXT)
    code, out, err = run_cli("fit-noise", "--robot", robot_file, *paths, *_truth_args(xys),
                             "--columns", COLUMNS, "--window", "30s", "--truth-sigma", "0.01",
                             "--out", tmp_path / "cli.toml", "--json")
    assert code == 0, err
    fitted = _quiet(fit_noise_in_memory, logs, DiffDrive(0.4), truths=truths, window="30s",
                    truth_held={"truth_sigma": 0.01})
    _same({k: v for k, v in json.loads(out).items() if k not in ("outputs", "seconds")}, fitted.summary)
    assert "truth_sigma" not in fitted.summary["parameters"] and fitted.truth["sigma"] == 0.01


def test_a_truth_in_memory_is_asked_what_a_truth_file_is(three_logs):
    """A Truth handed over in memory gets the checks a truth file gets when a command reads it:
    its heading in degrees is named (it was fitted silently, the windows started from
    headings that were no robot's)."""
    from dataclasses import replace

    _, _, logs, truths = three_logs
    in_degrees = [replace(truth, theta=np.degrees(truth.theta)) for truth in truths]
    with pytest.warns(UserWarning, match="does not follow the direction its positions move in"):
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="^(?!.*does not follow)")
            try:
                fit_noise_in_memory(logs, DiffDrive(0.4), truths=in_degrees, window=WINDOWS)
            except InputError:
                pass  # the fit may refuse such windows; the warning came first
