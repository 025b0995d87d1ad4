"""One set of log options for every command that reads a log (issue 10 items 3, 5, 8).

The independent truth is the built-in OptiOdom runs read in their own format: written out
again as a CSV of cumulative counters (or gzip, or metres), they must give the same answers
through ``--columns ... --cumulative``, in every command.
"""

from __future__ import annotations

import gzip
import json

import numpy as np
import pytest
import typer.main

from odomkit.cli.application import app
from odomkit.data import builtin_data_path
from odomkit.io.optiodom import read_run

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]
LOG_FLAGS = {"--format", "--columns", "--cumulative", "--wrap-bits", "--period", "--time-unit",
             "--time-scale", "--decimate", "--topic", "--joints", "--bag-time", "--truth-topic",
             "--truth-frame", "--span", "--record"}
CUMULATIVE = "t=t,ticks_left=L,ticks_right=R,gt_x=gx,gt_y=gy,gt_theta=gth"
LOG_COMMANDS = ("track", "calibrate", "calibrate-noise", "umbmark")
#: Every command that reads a log (issue 12 item 1: "Every command that reads a log shares these options").
EVERY_LOG_COMMAND = (*LOG_COMMANDS, "fit-noise", "evaluate", "check", "fit-amcl", "report")


def _log_params(command: str) -> dict[str, tuple[str | None, object]]:
    from odomkit.cli import commands  # noqa: F401  (registers the commands)

    click_command = typer.main.get_command(app).commands[command]  # type: ignore[attr-defined]
    return {opt: (param.help, param.default) for param in click_command.params
            for opt in param.opts if opt in LOG_FLAGS}


def test_every_log_reading_command_takes_the_same_log_options():
    reference = _log_params("track")
    assert set(reference) == LOG_FLAGS
    for command in EVERY_LOG_COMMAND[1:]:
        assert _log_params(command) == reference, command


def test_no_other_command_takes_a_log_option():
    """A command added later that reads logs must join EVERY_LOG_COMMAND (and so take all
    of the options); one that does not must take none."""
    from odomkit.cli import commands  # noqa: F401  (registers the commands)

    names = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    with_options = {name for name in names if _log_params(name)}
    assert with_options == set(EVERY_LOG_COMMAND)


def cumulative_csv(run, path, offset=1000, compress=False):
    """The run as a CSV of cumulative tick counters starting at ``offset``, with its truth."""
    log = read_run(run)
    left = offset + np.cumsum(np.r_[0, log.channels["ticks_left"][1:]]).astype(np.int64)
    right = offset + np.cumsum(np.r_[0, log.channels["ticks_right"][1:]]).astype(np.int64)
    gt = log.ground_truth
    lines = ["t,L,R,gx,gy,gth"] + [
        f"{t!r},{a},{b},{x!r},{y!r},{th!r}"  # repr: every double exactly
        for t, a, b, x, y, th in zip(log.t.tolist(), left.tolist(), right.tolist(),
                                     *gt.T.tolist(), strict=True)]
    text = ("\n".join(lines) + "\n").encode()
    path.write_bytes(gzip.compress(text) if compress else text)
    return path


def run_json(run_cli, *args):
    code, out, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(out), err


def same_numbers(a, b, skip=("outputs", "warnings")):
    if isinstance(a, dict):
        assert a.keys() - set(skip) == b.keys() - set(skip)
        for key in a.keys() - set(skip):
            same_numbers(a[key], b[key])
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            same_numbers(x, y)
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=1e-12, abs=1e-15)
    else:
        assert a == b


@pytest.fixture(scope="module")
def cumulative_runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cumulative")
    return [cumulative_csv(run, folder / f"c{i}.csv") for i, run in enumerate(RUNS)]


@pytest.mark.parametrize("command, extra", [
    ("calibrate", ["--side", "0.75"]),
    ("calibrate-noise", []),
    ("umbmark", ["--side", "0.75"]),
])
def test_cumulative_counters_calibrate_like_the_increments_they_count(run_cli, cumulative_runs,
                                                                      command, extra):
    """calibrate and calibrate-noise had no --cumulative: the counters were read as
    increments without a word."""
    runs = ["--runs", *cumulative_runs] if command == "umbmark" else cumulative_runs
    plain = ["--runs", *RUNS] if command == "umbmark" else RUNS
    expected, _ = run_json(run_cli, command, *plain, "--robot", ROBOT, *extra)
    got, err = run_json(run_cli, command, *runs, "--robot", ROBOT, *extra,
                        "--columns", CUMULATIVE, "--cumulative")
    assert err == ""
    same_numbers(got, expected)


def test_counters_read_as_increments_are_warned_about_in_one_line_and_in_json(run_cli, cumulative_runs):
    """On the square runs one wheel turns back in every spin, so its counter falls: only
    run 2's left and run 6's right counter never decrease, and only they are flagged."""
    runs = [cumulative_runs[1], cumulative_runs[5]]
    out, err = run_json(run_cli, "calibrate", *runs, "--robot", ROBOT, "--columns", CUMULATIVE)
    lines = err.strip().splitlines()
    assert len(lines) == 2
    assert all(line.startswith("odomkit: warning: ") and "--cumulative" in line for line in lines)
    assert f"{runs[0]}: column 'L' (ticks_left) never decreases" in lines[0]
    assert f"{runs[1]}: column 'R' (ticks_right) never decreases" in lines[1]
    assert out["warnings"] == [line.removeprefix("odomkit: warning: ") for line in lines]


def test_track_warning_reaches_json_and_stderr(run_cli, cumulative_runs):
    out, err = run_json(run_cli, "track", cumulative_runs[1], "--robot", ROBOT, "--columns", CUMULATIVE,
                        "--no-covariance")
    assert len(out["warnings"]) == 1 and err.count("odomkit: warning:") == 1
    code, text, err = run_cli("track", cumulative_runs[1], "--robot", ROBOT, "--columns", CUMULATIVE)
    assert code == 0 and "never decreases" in err and "never decreases" not in text


def test_64_bit_counters_gzip_through_track(run_cli, tmp_path):
    """A 64-bit counter that wraps, in a gzip file: the same track as the increments."""
    path = cumulative_csv(RUNS[0], tmp_path / "wrap.csv.gz", offset=2**63 - 20_000, compress=True)
    expected, said = run_json(run_cli, "track", RUNS[0], "--robot", ROBOT)
    got, err = run_json(run_cli, "track", path, "--robot", ROBOT, "--columns", CUMULATIVE,
                        "--cumulative", "--wrap-bits", "64")
    assert err == said  # no warning of its own (the run's, on its start's NEES, alike)
    same_numbers(got, expected)


def test_a_log_in_metres_is_not_scaled_by_the_robots_encoder(run_cli, tmp_path):
    """optiodom_diff.toml has an encoder resolution; dist_* columns are metres all the same."""
    n = 101
    step = 0.004  # m per row and wheel: 0.4 m straight ahead
    rows = "\n".join(f"{0.05 * i:.2f},{step if i else 0},{step if i else 0}" for i in range(n))
    path = tmp_path / "metres.csv"
    path.write_text("t,dl,dr\n" + rows + "\n")
    out, _ = run_json(run_cli, "track", path, "--robot", ROBOT, "--columns", "t=t,dist_left=dl,dist_right=dr")
    assert out["path_length"] == pytest.approx(0.4, rel=1e-12)
    assert out["pose"][0] == pytest.approx(0.4, rel=1e-12)


@pytest.mark.parametrize("flags, message", [
    (["--time-scale", "-1"], "--time-unit must be one of s, ms, us, µs, ns or a positive number"),
    (["--time-scale", "0"], "--time-unit must be one of s, ms, us, µs, ns or a positive number"),
    (["--time-unit", "nan"], "--time-unit must be one of s, ms, us, µs, ns or a positive number"),
    (["--time-unit", "min"], "--time-unit must be one of s, ms, us, µs, ns or a positive number"),
    (["--period", "0"], "--period must be a positive number of seconds, got 0.0"),
    (["--period", "-0.05"], "--period must be a positive number"),
    (["--wrap-bits", "12"], "--wrap-bits must be one of 8, 16, 24, 32, 64, got 12"),
    (["--decimate", "0"], "--decimate must be a positive integer"),
    (["--format", "rosbag"], "--format must be one of"),
    (["--cumulative"], "--cumulative does not apply to a optiodom log"),
    (["--time-scale", "1e-3"], "--time-unit does not apply to a optiodom log"),
    (["--time-unit", "ms"], "--time-unit does not apply to a optiodom log"),
    (["--columns", "t=t"], "--columns does not apply to a optiodom log"),
])
@pytest.mark.parametrize("command", LOG_COMMANDS)
def test_bad_log_options_exit_2_with_one_line(run_cli, command, flags, message):
    args = {"track": [RUNS[0]], "calibrate": RUNS[:2], "calibrate-noise": RUNS[:2],
            "umbmark": ["--runs", *RUNS, "--side", "0.75"]}[command]
    code, _, err = run_cli(command, *args, "--robot", ROBOT, *flags)
    assert code == 2, err
    assert message in err and err.startswith("odomkit: error: ") and len(err.strip().splitlines()) == 1


def test_period_applies_to_logs_without_time(run_cli, tmp_path):
    khepera = tmp_path / "khepera1.txt"
    khepera.write_text("0 0\n10 12\n20 25\n")
    out, _ = run_json(run_cli, "track", khepera, "--robot", ROBOT, "--period", "0.25")
    assert out["duration"] == pytest.approx(0.5, rel=1e-15)
    code, _, err = run_cli("track", khepera, "--robot", ROBOT, "--period", "0")
    assert code == 2 and "--period must be a positive number" in err


def test_umbmark_log_options_need_runs(run_cli, tmp_path):
    errors = tmp_path / "errors.csv"
    errors.write_text("direction,x,y\ncw,0.1,0.1\ncw,0.1,0.1\nccw,0.1,0.1\nccw,0.1,0.1\n")
    code, _, err = run_cli("umbmark", errors, "--side", "4", "--wheel-base", "0.3", "--cumulative")
    assert code == 2 and "--cumulative applies to the logs of --runs" in err


def test_reported_warnings_one_line_each_also_before_an_error(capsys):
    import warnings

    from odomkit.cli.log_options import reported_warnings, with_warnings

    with pytest.raises(ValueError), reported_warnings() as warned:
        warnings.warn("a: first\n  continued", stacklevel=1)
        warnings.warn("a: first\n  continued", stacklevel=1)  # the same text once
        warnings.warn("b: second", stacklevel=1)
        raise ValueError
    assert capsys.readouterr().err == "odomkit: warning: a: first continued\nodomkit: warning: b: second\n"
    assert warned == ["a: first continued", "b: second"]
    merged = with_warnings({"warnings": ["b: second"]}, warned)
    assert merged == {"warnings": ["b: second", "a: first continued"]}
    assert with_warnings({}, []) == {}


# --- text logs as they are (issue 12 item 1) ----------------------------------------------

def public_style_log(run, path, *, delimiter=" ", unit_per_s=1, compress=False, header=False):
    """The run as a text log of another style: ``#`` comment lines, no header (or one), the
    given delimiter, time in another unit; the columns in a different order than OptiOdom's."""
    log = read_run(run)
    gt = log.ground_truth
    lines = ["# recorded on the test robot", "# columns: stamp right left gx gy gth"]
    if header:
        lines.append(delimiter.join(["stamp", "right", "left", "gx", "gy", "gth"]))
    lines += [delimiter.join(repr(v) for v in (t * unit_per_s, right, left, x, y, th))
              for t, right, left, x, y, th in zip(log.t.tolist(), log.channels["ticks_right"].tolist(),
                                            log.channels["ticks_left"].tolist(), *gt.T.tolist(), strict=True)]
    text = ("\n".join(lines) + "\n").encode()
    path.write_bytes(gzip.compress(text) if compress else text)
    return path


IN_ORDER = "t,ticks_right,ticks_left,gt_x,gt_y,gt_theta"


def test_a_whitespace_log_with_comments_and_no_header_reads_with_columns_in_order(run_cli, tmp_path):
    """A public-dataset style log (whitespace, # comments, no usable header, ns stamps, gzip)
    gives the track of the same run read in its own format."""
    path = public_style_log(RUNS[0], tmp_path / "run.txt.gz", unit_per_s=10**9, compress=True)
    expected, said = run_json(run_cli, "track", RUNS[0], "--robot", ROBOT)
    got, err = run_json(run_cli, "track", path, "--robot", ROBOT, "--columns", IN_ORDER, "--time-unit", "ns")
    assert err == said  # no warning of its own (the run's, on its start's NEES, alike)
    same_numbers(got, expected)


@pytest.mark.parametrize("command, extra", [
    ("calibrate", ["--side", "0.75"]),
    ("calibrate-noise", []),
    ("umbmark", ["--side", "0.75"]),
])
def test_every_command_reads_semicolon_logs_in_ms(run_cli, tmp_path, command, extra):
    runs = [public_style_log(run, tmp_path / f"r{i}.txt", delimiter=";", unit_per_s=1000, header=True)
            for i, run in enumerate(RUNS)]
    columns = "t=stamp,ticks_right=right,ticks_left=left,gt_x=gx,gt_y=gy,gt_theta=gth"
    expected, _ = run_json(run_cli, command, *(["--runs"] if command == "umbmark" else []), *RUNS,
                           "--robot", ROBOT, *extra)
    got, err = run_json(run_cli, command, *(["--runs"] if command == "umbmark" else []), *runs,
                        "--robot", ROBOT, *extra, "--columns", columns, "--time-unit", "ms")
    assert err == ""
    same_numbers(got, expected)


def test_time_scale_is_kept_as_the_old_name_of_time_unit(run_cli, tmp_path):
    path = public_style_log(RUNS[0], tmp_path / "run.csv", delimiter=",", unit_per_s=1000)
    by_unit, _ = run_json(run_cli, "track", path, "--robot", ROBOT, "--columns", IN_ORDER,
                          "--time-unit", "ms")
    by_scale, _ = run_json(run_cli, "track", path, "--robot", ROBOT, "--columns", IN_ORDER,
                           "--time-scale", "1e-3")
    by_number, _ = run_json(run_cli, "track", path, "--robot", ROBOT, "--columns", IN_ORDER,
                            "--time-unit", "0.001")
    assert by_unit == by_scale == by_number
    assert by_unit["duration"] == pytest.approx(read_run(RUNS[0]).t[-1], rel=1e-12)


@pytest.mark.parametrize("text, columns, message", [
    ("t;v;w\n0;1,5;0\n1;1,5;0,25\n", "t=t,speed=v,yaw_rate=w", "line 2: '1,5' has a decimal comma"),
    ("0,0,0\n1,1,1\n0.5,2,2\n", "t,ticks_left,ticks_right", "line 3: time 0.5 is earlier than 1.0 on line 2"),
    ("0,0,0\n1,1,1\n", "t=time,ticks_left=L,ticks_right=R", "--columns maps header names, but the file "
                                                           "has no header"),
])
def test_bad_text_logs_exit_2_with_one_line(run_cli, tmp_path, text, columns, message):
    path = tmp_path / "log.csv"
    path.write_text(text)
    code, _, err = run_cli("track", path, "--robot", ROBOT, "--columns", columns)
    assert code == 2, err
    assert message in err and err.startswith("odomkit: error: ") and len(err.strip().splitlines()) == 1


def test_a_span_of_a_log_is_that_part_of_it_and_halves_share_no_row(run_cli, tmp_path):
    """``--span :50%`` and ``--span 50%:`` cut a log into halves at half its duration
    (half-open: no row in both), and ``--span 2:6`` to the rows from 2 s to before 6 s after
    its first; each gives the track of a file holding only those rows, written out here
    (the independent truth), in every log-reading command alike."""
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows.logs import LogOptions, load_log

    robot, _ = read_robot(ROBOT)
    whole = read_run(RUNS[0])
    first = load_log(RUNS[0], robot, LogOptions(span=":50%"))
    rest = load_log(RUNS[0], robot, LogOptions(span="50%:"))
    middle = whole.t[0] + 0.5 * (whole.t[-1] - whole.t[0])
    assert first.t[-1] < middle <= rest.t[0]
    np.testing.assert_array_equal(np.concatenate([first.t, rest.t]), whole.t)
    for name, values in whole.channels.items():
        np.testing.assert_array_equal(np.concatenate([first.channels[name], rest.channels[name]]), values)
    seconds = load_log(RUNS[0], robot, LogOptions(span="2:6"))
    inside = (whole.t >= whole.t[0] + 2) & (whole.t < whole.t[0] + 6)
    np.testing.assert_array_equal(seconds.t, whole.t[inside])
    # Seconds may carry their unit, as --window's do.
    np.testing.assert_array_equal(load_log(RUNS[0], robot, LogOptions(span="2s:6s")).t, whole.t[inside])

    part = tmp_path / "part.csv"
    rows = np.flatnonzero(inside)
    gt = whole.ground_truth
    table = np.column_stack([whole.t, whole.channels["ticks_left"], whole.channels["ticks_right"], gt])
    np.savetxt(part, table[rows], delimiter=",", header="t,ticks_left,ticks_right,gt_x,gt_y,gt_theta",
               comments="")
    for command in ("track", "evaluate"):
        cut, _ = run_json(run_cli, command, RUNS[0], "--robot", ROBOT, "--span", "2:6")
        alone, _ = run_json(run_cli, command, part, "--robot", ROBOT)
        same_numbers(cut, alone, skip=("outputs", "warnings", "log", "per_log"))
        for a, b in zip(cut.get("per_log", []), alone.get("per_log", []), strict=True):
            same_numbers(a, b, skip=("log", "warnings"))


@pytest.mark.parametrize(("span", "message"), [
    ("1:2:3", "--span takes START:END"),
    ("50", "--span takes START:END"),
    ("x:", "'x' is neither"),
    ("5ss:", "'5ss' is neither"),
    ("5%s:", "'5%s' is neither"),
    ("-5:", "'-5' is neither"),
    (":150%", "'150%' is neither"),
    ("9:3", "--span 9:3: its end must come after its start"),
    ("500:", "--span 500: leaves 0 row(s) of the log, whose rows run over"),
])
def test_a_bad_span_is_one_line(run_cli, span, message):
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--span", span)
    assert code == 2, err
    assert message in err and err.startswith("odomkit: error: ") and len(err.strip().splitlines()) == 1


def test_a_counter_that_falls_read_as_increments_is_faster_than_any_vehicle(run_cli, tmp_path):
    """A raw counter read as increments where it also falls (run 1's wheels turn back in
    every spin), so "never decreases" cannot say it: a tricycle's drove 561 km in 113 s, exit
    0, without a word (user study). The speed it reads is no wheeled vehicle's: track warns
    once, naming --cumulative; check fails on it first and says it once, before any finding
    that a wrong reading would make meaningless; read with --cumulative, neither says it."""
    raw = cumulative_csv(RUNS[0], tmp_path / "raw.csv", offset=3_000_000_000)
    code, text, err = run_cli("track", raw, "--robot", ROBOT, "--columns", CUMULATIVE, "--no-covariance")
    assert code == 0 and err.count("odomkit: warning:") == 1
    assert "faster than any wheeled vehicle" in err and "--cumulative" in err and "never decreases" not in err
    code, text, err = run_cli("check", raw, "--robot", ROBOT, "--columns", CUMULATIVE)
    assert code == 1 and "faster than any wheeled vehicle" not in err
    assert text.count("faster than any wheeled vehicle") == 1
    findings = [line.split()[:2] for line in text.split("next:")[0].splitlines() if line.startswith("  ")]
    assert findings[-1] == ["FAIL", "speed"] and ["ok", "counters"] in findings
    assert "--cumulative" in text.split("next:")[1].splitlines()[1]
    for command in ("track", "check"):
        code, text, err = run_cli(command, raw, "--robot", ROBOT, "--columns", CUMULATIVE, "--cumulative")
        assert code == 0 and "faster than any" not in text + err
