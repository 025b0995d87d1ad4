"""Fuzz every reader directly (issue 10, item 8): hostile bytes in, and out comes a value or an
:class:`~odomkit.errors.OdomkitError`, never another exception (nor a numpy RuntimeWarning,
which the CLI would print before its one-line error)."""

from __future__ import annotations

import contextlib
import importlib.util
import math
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterator
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from odomkit.errors import OdomkitError

_spec = importlib.util.spec_from_file_location("odomkit_fuzz", Path(__file__).with_name("_fuzz.py"))
assert _spec is not None and _spec.loader is not None
fz = sys.modules.setdefault("odomkit_fuzz", importlib.util.module_from_spec(_spec))
if not hasattr(fz, "check_case"):
    _spec.loader.exec_module(fz)

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")


@contextlib.contextmanager
def _file(name: str, data: bytes | None) -> Iterator[Path]:
    """``data`` written to ``name`` in a fresh folder (None: no file at all)."""
    with tempfile.TemporaryDirectory(prefix="odomkit-fuzz-") as tmp:
        path = Path(tmp) / name
        if data is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        yield path


def returns_or_refuses(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)``, or None when it raised an OdomkitError; anything else fails
    the test, naming the call."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # reader warnings are allowed
            warnings.simplefilter("error", RuntimeWarning)
            return fn(*args, **kwargs)
    except OdomkitError as exc:
        assert str(exc).strip() and "\n" not in str(exc).strip(), f"{fn.__name__}: message {exc!r}"
        return None
    except Exception as exc:  # noqa: BLE001
        raise AssertionError(f"{fn.__module__}.{fn.__name__}{_show(args, kwargs)} raised "
                             f"{type(exc).__name__}: {exc}") from exc


def _show(args: tuple[Any, ...], kwargs: dict[str, Any]) -> str:
    parts = [repr(a) if not isinstance(a, Path) else repr(a.name) for a in args]
    parts += [f"{k}={v!r}" for k, v in kwargs.items()]
    return f"({', '.join(parts)})"


TOKENS = ("0", "1", "-1", "0.5", "1e9", "nan", "inf", "-inf", "1e308", "1e-320", "1e400", "", " ",
          "abc", "t", "x", "ticks_left", "#", "#c", "1_000", "٣", "0x10", "9" * 25, "1.5e", "é")


@st.composite
def table_text(draw: st.DrawFn) -> bytes:
    """Any small text table: random tokens in random columns, delimiters, header, comments."""
    delimiter = draw(st.sampled_from((",", ";", "\t", " ", "  ", ", ")))
    ncols = draw(st.integers(1, 9))
    number = st.one_of(fz.floats_text(-1e3, 1e3), st.integers(-10**6, 10**6).map(str),
                       st.sampled_from(TOKENS))
    lines = []
    if draw(st.booleans()):
        names = ("t", "x", "y", "theta", "ticks_left", "ticks_right", "speed", "direction", "gt_x", "L")
        lines.append(delimiter.join(draw(st.lists(st.sampled_from(names), min_size=1, max_size=ncols))))
    for _ in range(draw(st.integers(0, 8))):
        width = ncols if draw(st.integers(0, 5)) < 5 else draw(st.integers(0, 10))
        lines.append(delimiter.join(draw(number) for _ in range(width)))
        if draw(st.integers(0, 9)) == 9:
            lines.append("# a comment")
    return draw(fz.encoded("\n".join(lines).encode()))


def any_table(good: bytes) -> st.SearchStrategy[bytes]:
    """A good table edited, or any table, or any bytes."""
    return st.one_of(fz.mutated_table(good), table_text(), st.binary(max_size=80))


# ------------------------------------------------------------------------------------- text io

@fz.fuzz_settings(100)
@given(data=st.one_of(table_text(), st.binary(max_size=100)), compressed=st.booleans(),
       strict=st.booleans())
def test_fuzz_read_text(data, compressed, strict):
    from odomkit.io.text import read_text, sniff_layout

    with _file("x.txt", data) as path:
        text = returns_or_refuses(read_text, path, compressed=compressed, strict_utf8=strict)
    if text is not None:
        returns_or_refuses(sniff_layout, text, "x.txt")


@fz.fuzz_settings(60)
@given(unit=st.one_of(st.text(max_size=6), st.sampled_from(("s", "ms", "us", "µs", "ns", "1e-4", "0", "-1",
                                                            "nan", "inf", "1e308", "1e-320", "1e400"))))
def test_fuzz_time_units(unit):
    from odomkit.io.text import seconds_per_unit

    value = returns_or_refuses(seconds_per_unit, unit)
    if value is not None:
        assert math.isfinite(value) and value > 0, (unit, value)


# ------------------------------------------------------------------------------------ log readers

COLUMNS = ("t,ticks_left,ticks_right", "t=t,ticks_left=L,ticks_right=R", "t,_,x", "t,speed,yaw_rate",
           "t=t", "t,ticks_left,ticks_right,gt_x,gt_y,gt_theta", "t,t", "=", "t=", "t,bogus")


@fz.fuzz_settings(100)
@given(data=st.one_of(any_table(fz._diff_csv()), any_table((fz.INPUTS / "gyro.csv").read_bytes())),
       columns=st.one_of(st.sampled_from(COLUMNS), st.just(fz.DIFF_COLUMNS), st.text(max_size=12)),
       time_unit=st.sampled_from(("s", "ms", "1e-4", "ns")), cumulative=st.booleans(),
       wrap_bits=st.sampled_from((None, None, 8, 16, 32, 64)))
def test_fuzz_csv_log(data, columns, time_unit, cumulative, wrap_bits):
    from odomkit.io.csvlog import parse_columns, read_csv_log

    parsed = returns_or_refuses(parse_columns, columns)
    if parsed is None:
        return
    with _file("log.csv", data) as path:
        log = returns_or_refuses(read_csv_log, path, parsed, time_unit=time_unit, cumulative=cumulative,
                                 wrap_bits=wrap_bits)
    if log is not None:
        assert np.all(np.isfinite(log.t)), "a log's time must be finite"
        assert np.all(np.diff(log.t) >= 0), "a log's time must not go back"


@fz.fuzz_settings(60)
@given(data=any_table(fz._head(fz.RUNS[0], 60)), platform=st.sampled_from(("diff", "tricyc")))
def test_fuzz_optiodom_run(data, platform):
    from odomkit.io.optiodom import read_run

    with _file("exp_run-01.csv", data) as path:
        returns_or_refuses(read_run, path, platform)


@fz.fuzz_settings(40)
@given(data=any_table((fz.DATA / "230620202042_metadata.csv").read_bytes()))
def test_fuzz_optiodom_metadata(data):
    from odomkit.io.optiodom import read_experiment, read_metadata

    with tempfile.TemporaryDirectory(prefix="odomkit-fuzz-") as tmp:
        folder = Path(tmp)
        (folder / "230620202042_metadata.csv").write_bytes(data)
        (folder / "230620202042_run-01.csv").write_bytes(fz._head(fz.RUNS[0], 50))
        returns_or_refuses(read_metadata, folder / "230620202042_metadata.csv")
        returns_or_refuses(read_experiment, folder)


KHEPERA = b"".join(f"{i * 10} {i * 12}\n".encode() for i in range(30))
SNOWHITE = b"".join(f"{0.5 + 0.01 * i} {0.01 * i}\n".encode() for i in range(30))


@fz.fuzz_settings(60)
@given(data=st.one_of(any_table(KHEPERA), any_table(SNOWHITE)),
       period=st.sampled_from((1.0, 0.05, 1e-320, 1e308)), wrap_bits=st.sampled_from((None, 8, 16, 64)))
def test_fuzz_halmstad(data, period, wrap_bits):
    from odomkit.io.halmstad import read_khepera, read_snowhite

    with _file("khepera.txt", data) as path:
        returns_or_refuses(read_khepera, path, period=period, wrap_bits=wrap_bits)
        returns_or_refuses(read_snowhite, path, period=period)


# --------------------------------------------------------------------------------- other readers

@fz.fuzz_settings(120)
@given(data=st.one_of(*(fz.robot_file(tables) for tables in fz.ROBOTS.values()), st.binary(max_size=60)))
def test_fuzz_robot_file(data):
    from odomkit.io.robotfile import read_robot

    with _file("robot.toml", data) as path:
        found = returns_or_refuses(read_robot, path)
    if found is not None:
        robot, noise = found
        for model in noise:  # what was read is usable: a model checks itself against the robot
            returns_or_refuses(model.check_robot, robot)


@fz.fuzz_settings(80)
@given(data=st.one_of(any_table(fz._tum()), any_table(fz._truth_csv())),
       fmt=st.sampled_from(("auto", "tum", "kitti", "csv")),
       columns=st.sampled_from((None, None, "t,x,y,theta", "t,x,y", "t=t,x=x,y=y", "t,x,y,theta_deg", "x,y")),
       time_unit=st.sampled_from(("s", "ms", "ns")), sigma=st.sampled_from((0.0, 0.01, 1e308)))
def test_fuzz_truth(data, fmt, columns, time_unit, sigma):
    from odomkit.io.truth import read_truth

    with _file("truth.txt", data) as path:
        truth = returns_or_refuses(read_truth, path, fmt, columns, time_unit, sigma)
    if truth is not None:
        assert np.all(np.isfinite(truth.t)) and np.all(np.isfinite(truth.xy)), "truth must be finite"
        assert np.all(np.diff(truth.t) > 0), "truth times must increase"


@fz.fuzz_settings(60)
@given(data=fz.umbmark_errors())
def test_fuzz_umbmark_errors(data):
    from odomkit.io.umbmark_errors import read_errors_csv

    with _file("errors.csv", data) as path:
        found = returns_or_refuses(read_errors_csv, path)
    if found is not None:
        assert all(np.all(np.isfinite(e)) for e in found)


@cache
def _track_csv() -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        result = fz.run_in(Path(tmp), ["track", str(fz.RUNS[0]), "--robot",
                                       str(fz.DATA / "optiodom_diff.toml"), "--out", "t.csv"])
        assert result.code == 0, result.err
        return fz._head(Path(tmp) / "t.csv", 80)


@fz.fuzz_settings(60)
@given(data=st.deferred(lambda: any_table(_track_csv())))
def test_fuzz_track_csv(data):
    from odomkit.io.trackio import read_track_csv

    with _file("track.csv", data) as path:
        returns_or_refuses(read_track_csv, path)


@fz.fuzz_settings(80)
@given(data=st.one_of(any_table(fz._diff_csv()), any_table(fz._head(fz.RUNS[0], 60)), st.binary(max_size=40)),
       name=st.sampled_from(("log.csv", "exp_run-01.csv", "khepera.txt", "snowhite.txt", "log.csv.gz")),
       fmt=st.sampled_from(("auto", "csv", "optiodom", "khepera", "snowhite")),
       decimate=st.sampled_from((1, 2, 10**6)))
def test_fuzz_load_log(data, name, fmt, decimate):
    from odomkit.robot import DiffDrive
    from odomkit.workflows.logs import LogOptions, load_log

    options = returns_or_refuses(LogOptions, fmt, fz.DIFF_COLUMNS if fmt in ("auto", "csv") else None,
                                 decimate=decimate)
    if options is None:
        return
    with _file(name, data) as path:
        returns_or_refuses(load_log, path, DiffDrive(0.2, 1e-4, 1e-4), options)


# ------------------------------------------------------------------------------------------ bags

@cache
def _bags() -> dict[str, dict[str, bytes]]:
    """Small good bags (ROS 1 and a ROS 2 MCAP folder), as {relative path: bytes}."""
    conftest = fz.REPO / "tests" / "io" / "conftest.py"
    spec = importlib.util.spec_from_file_location("odomkit_io_conftest", conftest)
    assert spec is not None and spec.loader is not None
    helpers = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(helpers)
    messages = [("/joint_states", "sensor_msgs/msg/JointState", 10**9 + i * 50_000_000,
                 {"header": helpers.header(10**9 + i * 50_000_000), "name": ["left", "right"],
                  "position": [0.1 * i, 0.12 * i]}) for i in range(12)]
    out: dict[str, dict[str, bytes]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in ("ros1", "mcap"):
            path = helpers.write_bag(Path(tmp) / f"b_{fmt}", fmt, messages)
            files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
            out[fmt] = {p.relative_to(tmp).as_posix(): p.read_bytes() for p in files}
    return out


@st.composite
def bag_files(draw: st.DrawFn) -> tuple[str, dict[str, bytes]]:
    """A bag with one file edited (bytes flipped, cut, replaced), and the path to open."""
    fmt = draw(st.sampled_from(("ros1", "mcap")))
    files = dict(_bags()[fmt])
    target = draw(st.sampled_from(sorted(files)))
    data = bytearray(files[target])
    op = draw(st.sampled_from(("flip", "flip", "cut", "random", "none", "yaml")))
    if op == "flip" and data:
        for _ in range(draw(st.integers(1, 4))):
            data[draw(st.integers(0, len(data) - 1))] ^= draw(st.integers(1, 255))
    elif op == "cut":
        data = data[: draw(st.integers(0, len(data)))]
    elif op == "random":
        data = bytearray(draw(st.binary(max_size=64)))
    elif op == "yaml":
        target = next((f for f in files if f.endswith("metadata.yaml")), target)
        data = bytearray(draw(st.sampled_from((b"", b"rosbag2_bagfile_information: 3\n", b"{", b"- 1\n",
                                               b"rosbag2_bagfile_information:\n  version: 99\n"))))
    files[target] = bytes(data)
    opened = "b_ros1.bag" if fmt == "ros1" else "b_mcap"
    return opened, files


@fz.fuzz_settings(40)
@given(bag=bag_files(), topic=st.sampled_from(((), ("/joint_states",), ("/nope",))))
def test_fuzz_bags(bag, topic):
    pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
    from odomkit.io.bag import bag_topics, read_bag, read_bag_odometry

    opened, files = bag
    with tempfile.TemporaryDirectory(prefix="odomkit-fuzz-") as tmp:
        for rel, data in files.items():
            (Path(tmp) / rel).parent.mkdir(parents=True, exist_ok=True)
            (Path(tmp) / rel).write_bytes(data)
        path = Path(tmp) / opened
        returns_or_refuses(bag_topics, path)
        returns_or_refuses(read_bag, path, topic)
        returns_or_refuses(read_bag_odometry, path)


@fz.fuzz_settings(30)
@given(data=st.binary(max_size=80), name=st.sampled_from(("x.bag", "x.db3", "x.mcap", "folder")))
def test_fuzz_bag_from_any_bytes(data, name):
    pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
    from odomkit.io.bag import read_bag

    target = f"{name}/metadata.yaml" if name == "folder" else name
    with _file(target, data) as path:
        returns_or_refuses(read_bag, path.parent if name == "folder" else path)
