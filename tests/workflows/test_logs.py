"""odomkit.workflows.logs: log options are checked when made, and an option the log's format
would ignore is refused instead of dropped (issue 10 items 5 and 8)."""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.errors import InputError
from odomkit.io.table import COUNTER_BITS
from odomkit.robot import DiffDrive
from odomkit.workflows import logs
from odomkit.workflows.logs import LogOptions, detect_format, load_log

RUN = builtin_data_path("230620202042_run-01.csv")


def test_the_counter_widths_agree_with_the_reader():
    assert logs._COUNTER_BITS == COUNTER_BITS


@pytest.mark.parametrize("kwargs, flag", [
    ({"period": 0.0}, "--period"), ({"period": -1.0}, "--period"), ({"period": math.nan}, "--period"),
    ({"time_unit": 0.0}, "--time-unit"), ({"time_unit": "-1"}, "--time-unit"),
    ({"time_unit": math.inf}, "--time-unit"), ({"time_unit": "min"}, "--time-unit"),
    ({"time_unit": True}, "--time-unit"), ({"wrap_bits": 12}, "--wrap-bits"),
    ({"decimate": 0}, "--decimate"), ({"decimate": 2.0}, "--decimate"), ({"format": "rosbag"}, "--format"),
])
def test_bad_values_are_refused_by_flag(kwargs, flag):
    with pytest.raises(InputError, match=f"^{flag} must be"):
        LogOptions(**kwargs)


def test_given_lists_the_flags_set():
    assert LogOptions().given() == []
    assert LogOptions(cumulative=True, wrap_bits=16, decimate=3).given() == [
        "--cumulative", "--wrap-bits", "--decimate"]


@pytest.mark.parametrize("name, fmt", [
    ("230620202042_run-01.csv.gz", "optiodom"), ("khepera3.txt.gz", "khepera"),
    ("snowhite.txt.gz", "snowhite"), ("log.csv.gz", "csv"), ("LOG_RUN-2.CSV", "optiodom"),
])
def test_detect_format_looks_through_gz(name, fmt):
    assert detect_format(Path(name)) == fmt


def test_decimate_is_a_log_option(tmp_path):
    robot = DiffDrive(0.2)
    full = load_log(RUN, robot)
    every3 = load_log(RUN, robot, LogOptions(decimate=3))
    assert np.array_equal(every3.t, full.t[::3])
    last = 3 * ((len(full) - 1) // 3)  # the last row kept
    # increments are summed over the dropped rows: the same total up to that row
    assert every3.channels["ticks_left"][1:].sum() == full.channels["ticks_left"][1:last + 1].sum()


def test_a_gzip_run_is_detected_and_read(tmp_path):
    packed = tmp_path / "230620202042_run-01.csv.gz"
    packed.write_bytes(gzip.compress(Path(RUN).read_bytes()))
    a, b = load_log(packed, DiffDrive(0.2)), load_log(RUN, DiffDrive(0.2))
    assert np.array_equal(a.t, b.t) and np.array_equal(a.ground_truth, b.ground_truth)


@pytest.mark.parametrize("options, message", [
    (LogOptions(cumulative=True), "--cumulative does not apply to a optiodom log"),
    (LogOptions(period=0.05), "--period does not apply to a optiodom log"),
    (LogOptions(format="csv", columns="t=t", period=0.05), "--period does not apply to a csv log"),
    (LogOptions(format="snowhite", wrap_bits=16), "--wrap-bits does not apply to a snowhite log"),
    (LogOptions(format="khepera", time_unit="ms"), "--time-unit does not apply to a khepera log"),
    (LogOptions(format="csv", columns="t=t", wrap_bits=16), "--wrap-bits unwraps cumulative counters"),
])
def test_an_option_the_format_ignores_is_an_error(options, message):
    with pytest.raises(InputError, match=message):
        load_log(RUN, DiffDrive(0.2), options)


def test_importing_the_options_loads_no_reader():
    import subprocess
    import sys

    code = ("import sys, odomkit.workflows.logs; "
            "print(sorted(m for m in sys.modules if m.startswith(('numpy', 'odomkit.io'))))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_a_folder_or_an_optiodom_metadata_file_is_refused_with_what_to_give(tmp_path):
    """A user study: an OptiOdom experiment folder was "no such file", and its metadata CSV,
    picked up by ``*.csv``, "a text log needs --columns". Each now says what to give."""
    folder = tmp_path / "140120211430"
    folder.mkdir()
    for name in ("140120211430_metadata.csv", "140120211430_run-01.csv", "140120211430_run-02.csv"):
        (folder / name).write_text("x\n")
    with pytest.raises(InputError, match=r"is a folder, not a log: give the logs in it \("
                       r"140120211430_run-01.csv, 140120211430_run-02.csv: e\.g\. .*/\*_run-\*\.csv\)"):
        load_log(folder, DiffDrive(0.2))
    with pytest.raises(InputError, match=r"is an OptiOdom experiment's metadata, not a run: give its runs "
                       r"\(140120211430_run-\*\.csv\)"):
        load_log(folder / "140120211430_metadata.csv", DiffDrive(0.2))
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="is a folder, not a log: it holds no log files"):
        load_log(empty, DiffDrive(0.2))
