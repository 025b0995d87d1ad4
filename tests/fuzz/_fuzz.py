"""The fuzz suite's tools (issue 10, item 8): hostile inputs as hypothesis strategies, an
in-process CLI runner inside a throw-away folder, and the four properties every run must have.

The properties (:func:`check_case`):

1. the exit status is 0 or 2 (``odomkit check`` also 1: "a check failed", with its JSON), and
   no exception escapes ``odomkit.cli.main``;
2. exit 2 prints exactly one line ``odomkit: error: ...`` on stderr, after any number of
   ``odomkit: warning: ...`` lines, and nothing else (no traceback, no numpy RuntimeWarning);
   exit 0 prints only warning lines there; and no Python warning escapes the command (it
   would print as two lines naming a source file);
3. exit 0 with ``--json`` prints one JSON object with no NaN/Infinity and no ``null`` except
   where "no number" is the documented answer (:data:`NULL_KEYS`, :data:`NULL_SUBTREES`,
   :data:`NULL_IF_FEW_RUNS`, :data:`NULL_IF_WARNED`, :data:`NULL_IN_LISTS`), and
   every covariance (:data:`COVARIANCE_KEYS`) finite, symmetric and positive semi-definite
   (eigenvalues >= -1e-12 x its largest entry);
4. no input file changes (bytes and modification time), no pre-existing output changes
   unless the command was given ``--force``, and a failed command (exit 1 or 2) writes
   nothing at all: one up-front output-path check, nothing half-written.

Examples are derandomized (``derandomize=True``, no example database), so every run of the
suite tries the same inputs; ``ODOMKIT_FUZZ_SCALE=20`` multiplies every budget for a deeper
search (new seeds: ``ODOMKIT_FUZZ_SEED``).
"""

from __future__ import annotations

import contextlib
import gzip
import io
import json
import math
import os
import signal
import tempfile
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import hypothesis
import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "src" / "odomkit" / "data"
INPUTS = REPO / "tests" / "golden" / "inputs"

__all__ = [
    "Case", "check_case", "COVARIANCE_KEYS", "fuzz_settings", "NULL_KEYS", "run_in", "RunResult",
]

# ---------------------------------------------------------------------------------------------
# settings


def fuzz_settings(max_examples: int) -> Callable[[Callable[..., None]], Callable[..., None]]:
    """Deterministic, database-free settings with ``max_examples`` scaled by
    ``ODOMKIT_FUZZ_SCALE`` (default 1); ``ODOMKIT_FUZZ_SEED=N`` draws other examples (seed N)."""
    scale = float(os.environ.get("ODOMKIT_FUZZ_SCALE", "1"))
    seed = os.environ.get("ODOMKIT_FUZZ_SEED")
    chosen = settings(
        max_examples=max(1, int(max_examples * scale)),
        derandomize=seed is None,
        database=None,
        deadline=None,
        # Whole CLI runs are slow examples by hypothesis's standards, on purpose.
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                               HealthCheck.filter_too_much, HealthCheck.large_base_example],
        print_blob=False,
    )

    def apply(test: Callable[..., None]) -> Callable[..., None]:
        test = chosen(test)
        return hypothesis.seed(int(seed))(test) if seed is not None else test

    return apply


#: Seconds one CLI run may take before it counts as a hang.
TIME_LIMIT = 30.0

# ---------------------------------------------------------------------------------------------
# hostile values

#: Numbers (as a user types them) that broke commands in the outside campaign, and friends.
NASTY_FLOATS = ("0", "-0", "-1", "-1e-9", "nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e-320",
                "1e200", "1e-300", "1e400", "abc", "", " ", "1,5", "0x10", "1e9", "٣")
NASTY_INTS = ("0", "-1", "1", "2", "1000000000", "99999999999999999999999", "-9223372036854775809",
              "1.5", "nan", "abc", "", "1e3")
#: TOML values for a robot file's fields.
TOML_VALUES = ("0", "-1", "1", "0.2", "0.001", "1e-9", "1e308", "-1e308", "1e-320", "1e200", "nan",
               "inf", "-inf", "1e400", "99999999999999999999999", "-0.0", '"x"', "true", "[1, 2]",
               "{a = 1}", '"diff"', '"bias"', '"white"', '"rear"', '"front"', "1979-05-27", '""')


def floats_text(lo: float, hi: float) -> st.SearchStrategy[str]:
    """A valid number in [lo, hi], as text."""
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False).map(repr)


def _mostly(good: st.SearchStrategy[str], bad: st.SearchStrategy[str],
            odds: int = 6) -> st.SearchStrategy[str]:
    """``good`` ``odds`` times out of ``odds + 1``, else ``bad``: most examples should get far
    enough to compute something, so that the success properties are exercised too."""
    # Hypothesis starts from the simplest example (every choice 0): make that one good.
    return st.integers(0, odds).flatmap(lambda i: bad if i == odds else good)


def number(valid: st.SearchStrategy[str] | Sequence[str], odds: int = 8) -> st.SearchStrategy[str]:
    """A value for a float option: valid (``valid``) or, one time in ``odds + 1``, hostile
    (:data:`NASTY_FLOATS`)."""
    good = valid if isinstance(valid, st.SearchStrategy) else st.sampled_from(list(valid))
    return _mostly(good, st.sampled_from(NASTY_FLOATS), odds)


def integer(valid: Sequence[str]) -> st.SearchStrategy[str]:
    """A value for an int option: valid or hostile (:data:`NASTY_INTS`)."""
    return _mostly(st.sampled_from(list(valid)), st.sampled_from(NASTY_INTS))


def word(valid: Sequence[str]) -> st.SearchStrategy[str]:
    """A value for a word option: one of ``valid`` or any short text."""
    text = st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=8)
    return _mostly(st.sampled_from(list(valid)), text)


# ---------------------------------------------------------------------------------------------
# files: mutations of good inputs

def _lines(data: bytes) -> list[bytes]:
    return data.splitlines()


@st.composite
def mutated_table(draw: st.DrawFn, data: bytes, max_changes: int = 3) -> bytes:
    """``data`` (a text table) with up to ``max_changes`` hostile edits: a field replaced
    by a bad number or text, lines cut, swapped, repeated or added, a column scaled to the
    edge of the float range; and possibly re-encoded (gzip, Latin-1 bytes, a BOM, CRLF,
    cut mid-line)."""
    lines = _lines(data)
    for _ in range(draw(st.integers(0, max_changes))):
        if not lines:
            break
        op = draw(st.sampled_from(("field", "field", "keep", "swap", "repeat", "garbage", "scale",
                                   "drop_column")))
        i = draw(st.integers(0, len(lines) - 1))
        sep = b"," if b"," in lines[i] else None
        fields = lines[i].split(sep) if sep else lines[i].split()
        joiner = sep or b" "
        if op == "field" and fields:
            j = draw(st.integers(0, len(fields) - 1))
            fields[j] = draw(st.sampled_from(NASTY_FLOATS)).encode()
            lines[i] = joiner.join(fields)
        elif op == "keep":
            lines = lines[: draw(st.sampled_from((0, 1, 2, 3, 5, 20)))]
        elif op == "swap":
            k = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[k] = lines[k], lines[i]
        elif op == "repeat":
            lines.insert(i, lines[i])
        elif op == "garbage":
            lines.insert(i, draw(st.binary(max_size=12)).replace(b"\n", b"").replace(b"\r", b""))
        elif op == "scale" and fields:
            j = draw(st.integers(0, len(fields) - 1))
            factor = draw(st.sampled_from((1e200, 1e-300, -1.0, 0.0, 1e300)))
            out = []
            for line in lines:
                parts = line.split(sep) if sep else line.split()
                if j < len(parts):
                    with contextlib.suppress(ValueError, OverflowError):
                        parts[j] = repr(float(parts[j]) * factor).encode()
                out.append(joiner.join(parts))
            lines = out
        elif op == "drop_column" and fields:
            j = draw(st.integers(0, len(fields) - 1))
            out = []
            for line in lines:
                parts = line.split(sep) if sep else line.split()
                out.append(joiner.join(parts[:j] + parts[j + 1:]))
            lines = out
    return draw(encoded(b"\n".join(lines) + (b"\n" if lines else b"")))


@st.composite
def encoded(draw: st.DrawFn, data: bytes) -> bytes:
    """``data`` as is (mostly), or gzip, non-UTF-8, BOM, CRLF, cut or random bytes."""
    how = draw(st.sampled_from(("plain",) * 16 + ("gzip", "latin1", "bom", "crlf", "cut", "random",
                                                  "gzip_cut", "nul")))
    if how == "gzip":
        return gzip.compress(data, mtime=0)
    if how == "gzip_cut":
        packed = gzip.compress(data, mtime=0)
        return packed[: draw(st.integers(0, max(0, len(packed) - 1)))]
    if how == "latin1":
        at = draw(st.integers(0, len(data)))
        return data[:at] + b"\xe9\xff" + data[at:]
    if how == "bom":
        return b"\xef\xbb\xbf" + data
    if how == "crlf":
        return data.replace(b"\n", b"\r\n")
    if how == "cut":
        return data[: draw(st.integers(0, len(data)))]
    if how == "nul":
        at = draw(st.integers(0, len(data)))
        return data[:at] + b"\x00" + data[at:]
    if how == "random":
        return draw(st.binary(max_size=64))
    return data


# ---------------------------------------------------------------------------------------------
# good inputs

RUNS = [DATA / f"230620202042_run-0{i}.csv" for i in range(1, 7)]


def _head(path: Path, n: int | None = None, step: int = 1) -> bytes:
    lines = path.read_bytes().splitlines()
    return b"\n".join(lines[:n][::step]) + b"\n"


def _diff_csv() -> bytes:
    """Run 1 as a text log with a header: t, truth, ticks (every 4th row)."""
    rows = np.loadtxt(RUNS[0], delimiter=",")[::4]
    out = io.StringIO()
    out.write("t,gt_x,gt_y,gt_theta,R,L\n")
    np.savetxt(out, rows, delimiter=",", fmt="%.10g")
    return out.getvalue().encode()


def _tum(step: int = 4) -> bytes:
    rows = np.loadtxt(RUNS[0], delimiter=",")[::step]
    t, x, y, th = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    table = np.column_stack([t, x, y, 0 * t, 0 * t, 0 * t, np.sin(th / 2), np.cos(th / 2)])
    out = io.StringIO()
    np.savetxt(out, table, fmt="%.10g")
    return out.getvalue().encode()


def _truth_csv(step: int = 4) -> bytes:
    rows = np.loadtxt(RUNS[0], delimiter=",")[::step]
    out = io.StringIO()
    out.write("t,x,y,theta\n")
    np.savetxt(out, rows[:, :4], delimiter=",", fmt="%.10g")
    return out.getvalue().encode()


DIFF_COLUMNS = "t=t,ticks_left=L,ticks_right=R,gt_x=gt_x,gt_y=gt_y,gt_theta=gt_theta"

#: name -> (log bytes, robot TOML tables, --columns or None): logs and robots that go together.
LOGS: dict[str, tuple[bytes, dict[str, dict[str, str]], str | None]] = {}
ROBOTS: dict[str, dict[str, dict[str, str]]] = {
    "diff": {"robot": {"type": '"diff"', "wheel_base": "0.2", "wheel_diameter": "0.084",
                       "encoder_resolution": "64", "gear_ratio": "43.7"},
             "noise": {"k_left": "0.001", "k_right": "0.001"}},
    "gyro": {"robot": {"type": '"gyro"'},
             "noise": {"alpha_ss": "0.0001", "psd_gyro": "0.00001"},
             "noise.parameters": {"sigma_scale_left": "0.01"}},
    "compass": {"robot": {"type": '"compass"'}, "noise": {"alpha_ss": "0.0001", "psd_compass": "0.00001"}},
    "tricycle": {"robot": {"type": '"tricycle"', "wheel_to_axle": "0.68"},
                 "noise": {"sigma_speed": "0.005", "sigma_steer": "0.01", "sigma_dt": "0.0001"},
                 "noise.parameters": {"sigma_wheel_base": "0.01"}},
    "unicycle": {"robot": {"type": '"unicycle"'}, "noise": {"alpha_ss": "0.0001"}},
    "car": {"robot": {"type": '"car"', "wheel_base": "2.7", "encoder_offset": "0.3"},
            "noise": {"sigma_speed": "0.005", "sigma_steer": "0.01"}},
}


def logs() -> dict[str, tuple[bytes, dict[str, dict[str, str]], str | None]]:
    """The good logs, read once."""
    if not LOGS:
        gyro = (INPUTS / "gyro.csv").read_bytes()
        speed_steer = (INPUTS / "tricycle_speed.csv").read_bytes()
        LOGS.update({
            "run": (_head(RUNS[0]), ROBOTS["diff"], None),
            "run_short": (_head(RUNS[0], 200), ROBOTS["diff"], None),
            "diff_csv": (_diff_csv(), ROBOTS["diff"], DIFF_COLUMNS),
            "gyro": (gyro, ROBOTS["gyro"], "t=t,speed=speed,yaw_rate=yaw_rate"),
            "compass": ((INPUTS / "compass.csv").read_bytes(), ROBOTS["compass"],
                        "t=t,speed=speed,heading=heading"),
            "tricycle": (speed_steer, ROBOTS["tricycle"], "t=t,speed=speed,steer=steer"),
            "unicycle": (gyro, ROBOTS["unicycle"], "t,speed,yaw_rate"),
            "car": (speed_steer, ROBOTS["car"], "t=t,speed=speed,steer=steer"),
        })
    return LOGS


#: Every key a robot file may hold (and one it may not).
ROBOT_KEYS = ("type", "name", "wheel_base", "wheel_diameter", "wheel_diameter_left", "wheel_diameter_right",
              "wheel_radius", "wheel_radius_front", "m_per_tick", "m_per_tick_left", "m_per_tick_right",
              "encoder_resolution", "gear_ratio", "c_left", "c_right", "c_wheel_base", "wheel_to_axle",
              "steering_offset", "c_scale", "gyro_bias", "gyro_scale", "heading_offset",
              "yaw_rate_bias", "yaw_rate_scale", "encoder_offset", "encoder_at", "bogus")


def noise_keys() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The ``[noise]`` keys and the ``[noise.parameters]`` keys of the registered models."""
    from dataclasses import fields

    from odomkit.noise import NOISE_MODELS

    plain, sub = [], []
    for cls in NOISE_MODELS.values():
        names = [f.name for f in fields(cls)]
        (plain if cls.toml_table == "noise" else sub).extend(names)
    return tuple(sorted(set(plain))) + ("bogus",), tuple(sorted(set(sub))) + ("bogus",)


def toml_text(tables: Mapping[str, Mapping[str, str]]) -> bytes:
    """TOML from tables of raw literals (so that ``nan`` or ``1e400`` stay as typed)."""
    out = []
    for name, table in tables.items():
        out.append(f"[{name}]")
        out.extend(f"{key} = {value}" for key, value in table.items())
        out.append("")
    return "\n".join(out).encode()


@st.composite
def robot_file(draw: st.DrawFn, base: Mapping[str, Mapping[str, str]]) -> bytes:
    """A robot file: ``base`` with up to three hostile edits (a field set to any TOML value,
    removed or added; random ``[noise]`` and ``[noise.parameters]`` keys; another robot
    type; an unknown table), possibly re-encoded."""
    tables = {name: dict(table) for name, table in base.items()}
    plain_keys, sub_keys = noise_keys()
    value = st.one_of(st.sampled_from(TOML_VALUES), floats_text(-10, 10), floats_text(0, 1e-3))
    for _ in range(draw(st.sampled_from((0, 0, 0, 0, 1, 1, 2, 3)))):
        op = draw(st.sampled_from(("robot_key", "noise_key", "noise_key", "parameters_key",
                                   "delete", "type", "no_noise", "extra_table")))
        if op == "robot_key":
            tables.setdefault("robot", {})[draw(st.sampled_from(ROBOT_KEYS))] = draw(value)
        elif op == "noise_key":
            tables.setdefault("noise", {})[draw(st.sampled_from(plain_keys))] = draw(value)
        elif op == "parameters_key":
            key = draw(st.sampled_from(sub_keys))
            tables.setdefault("noise.parameters", {})[key] = draw(value)
        elif op == "delete":
            name = draw(st.sampled_from(sorted(tables)))
            if tables[name]:
                del tables[name][draw(st.sampled_from(sorted(tables[name])))]
        elif op == "type":
            kind = draw(st.sampled_from(("diff", "tricycle", "gyro", "compass", "unicycle", "car", "x")))
            tables.setdefault("robot", {})["type"] = f'"{kind}"'
        elif op == "no_noise":
            tables.pop("noise", None)
            tables.pop("noise.parameters", None)
        else:
            tables[draw(st.sampled_from(("extra", "robot.sub", "noise.extra")))] = {"a": draw(value)}
    if "noise.parameters" in tables and "noise" not in tables:
        tables = {"noise": {}, **tables}  # a sub-table before its parent is fine TOML, but keep order
    return draw(encoded(toml_text(tables)))


def errors_csv() -> bytes:
    return (INPUTS / "errors.csv").read_bytes()


@st.composite
def umbmark_errors(draw: st.DrawFn) -> bytes:
    """An UMBmark errors CSV: the golden one edited, or random rows of direction,x,y."""
    if draw(st.booleans()):
        return draw(mutated_table(errors_csv()))
    direction = st.sampled_from(("cw", "ccw", "CW", " ccw ", "x", ""))
    value = st.one_of(floats_text(-1, 1), st.sampled_from(NASTY_FLOATS))
    rows = draw(st.lists(st.tuples(direction, value, value), max_size=12))
    text = "direction,x,y\n" + "".join(f"{d},{x},{y}\n" for d, x, y in rows)
    return draw(encoded(text.encode()))


# ---------------------------------------------------------------------------------------------
# a case: files + argv


@dataclass
class Case:
    """One fuzz example: files to create (relative path -> bytes, or None for a folder), the
    argv (with paths relative to the case's folder) and which argv paths are outputs."""

    argv: list[str] = field(default_factory=list)
    files: dict[str, bytes | None] = field(default_factory=dict)
    output_flags: tuple[str, ...] = ()
    #: extra outputs a flag implies, e.g. KITTI's NAME.times.txt
    derived: Callable[[str, str], list[str]] | None = None

    def add(self, *tokens: str) -> Case:
        self.argv.extend(tokens)
        return self

    def file(self, name: str, data: bytes | None) -> str:
        self.files[name] = data
        return name


PRECIOUS = b"precious: the user's own file\n"


@st.composite
def output_path(draw: st.DrawFn, case: Case, suffix: str, inputs: Sequence[str] = (),
                outputs: Sequence[str] = ()) -> str:
    """An output path: new (mostly), an existing file, inside a missing folder, a folder, a
    file used as a folder, empty, one of the inputs, or one of the other ``outputs``."""
    kind = draw(st.sampled_from(("new",) * 6 + ("existing", "existing", "missing_folder", "folder",
                                                 "under_file", "empty", "input", "other_output")))
    if kind == "other_output" and outputs:
        return draw(st.sampled_from(list(outputs)))
    n = len(case.files)
    if kind == "existing":
        return case.file(f"old{n}{suffix}", PRECIOUS)
    if kind == "missing_folder":
        return f"nodir{n}/out{suffix}"
    if kind == "folder":
        return case.file(f"adir{n}", None)
    if kind == "under_file":
        return case.file(f"plain{n}.txt", PRECIOUS) + f"/out{suffix}"
    if kind == "empty":
        return ""
    if kind == "input" and inputs:
        return draw(st.sampled_from(list(inputs)))
    return f"out{n}{suffix}"


@st.composite
def options(draw: st.DrawFn, menu: Sequence[tuple[str, st.SearchStrategy[list[str]] | None]],
            most: int = 3) -> list[str]:
    """Up to ``most`` distinct options from ``menu`` ((flag, strategy of values) or (flag,
    None) for a switch)."""
    chosen = draw(st.lists(st.sampled_from(range(len(menu))), max_size=most, unique=True))
    argv: list[str] = []
    for i in chosen:
        flag, values = menu[i]
        argv.append(flag)
        if values is not None:
            argv.extend(draw(values))
    return argv


def one(strategy: st.SearchStrategy[str]) -> st.SearchStrategy[list[str]]:
    return strategy.map(lambda v: [v])


#: The log options (log_options.py), hostile and valid values alike.
LOG_OPTION_MENU: list[tuple[str, st.SearchStrategy[list[str]] | None]] = [
    ("--format", one(word(("auto", "csv", "khepera", "snowhite", "optiodom", "bag")))),
    ("--columns", one(word(("t,ticks_left,ticks_right", "t=t,speed=speed", "t,_,x", "=", ",")))),
    ("--cumulative", None),
    ("--wrap-bits", one(integer(("8", "16", "32", "64")))),
    ("--period", one(number(("0.05", "1")))),
    ("--time-unit", one(word(("s", "ms", "us", "ns", "1e-4", "0", "-1", "nan", "inf", "1e308", "1e-320")))),
    ("--time-scale", one(word(("1", "-1", "0", "1e-320", "1e308")))),
    ("--decimate", one(integer(("1", "2", "3", "100000")))),
    ("--topic", one(word(("/odom", "/joint_states", "")))),
    ("--joints", one(word(("l,r", "a,a", ",")))),
    ("--bag-time", None),
    ("--truth-topic", one(word(("/gt",)))),
]

TRUTH_OPTION_MENU: list[tuple[str, st.SearchStrategy[list[str]] | None]] = [
    ("--truth-format", one(word(("auto", "tum", "kitti", "csv")))),
    ("--truth-columns", one(word(("t,x,y,theta", "t,x,y", "t=t,x=x,y=y", "t,x,y,theta_deg")))),
    ("--truth-time-unit", one(word(("s", "ms", "us", "ns", "0", "-1")))),
    ("--truth-sigma", one(number(("0", "0.001", "0.01")))),
    ("--max-gap", one(number(("0", "0.5", "2")))),
]


@st.composite
def truth_file(draw: st.DrawFn) -> bytes:
    """A truth file for run 1: TUM or t,x,y,theta, possibly edited."""
    base = draw(st.sampled_from(("tum", "csv")))
    data = _tum() if base == "tum" else _truth_csv()
    return draw(mutated_table(data, max_changes=2))


# ---------------------------------------------------------------------------------------------
# running


@dataclass
class RunResult:
    argv: list[str]
    code: int | None
    out: str
    err: str
    exception: BaseException | None
    #: warnings that escaped ``main`` (Python would print them as they are)
    escaped: list[str] = field(default_factory=list)


class _Hang(Exception):
    pass


@contextlib.contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    def alarm(signum: int, frame: Any) -> None:
        raise _Hang(f"no answer after {seconds:g} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def run_in(folder: Path, argv: Sequence[str]) -> RunResult:
    """``odomkit.cli.main(argv)`` with ``folder`` as the working directory, stdout and stderr
    captured; an exception that escapes ``main`` is returned, not raised."""
    from odomkit.cli import main

    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    os.chdir(folder)
    code: int | None = None
    exception: BaseException | None = None
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), _time_limit(TIME_LIMIT), \
                warnings.catch_warnings(record=True) as escaped:
            # What a command does not turn into "odomkit: warning:" lines itself escapes here;
            # outside the tests Python would print it as two lines naming a source file.
            warnings.simplefilter("always")
            code = main(list(argv))
    except BaseException as exc:  # noqa: BLE001  (any escape is a finding)
        exception = exc
    finally:
        os.chdir(here)
    shown = [w for w in escaped if not issubclass(w.category, _HIDDEN_WARNINGS)]
    return RunResult(list(argv), code, out.getvalue(), err.getvalue(), exception,
                     [f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})" for w in shown])


#: Warnings Python does not show by default (outside ``__main__``): not a user's concern.
_HIDDEN_WARNINGS = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


# ---------------------------------------------------------------------------------------------
# the properties

#: Keys whose value is a covariance (or a correlation) matrix: finite, symmetric, PSD. Under
#: ``se`` (standard errors of a covariance) and ``z`` (z-scores) simulate's ``cov`` is not one.
COVARIANCE_KEYS = frozenset({"cov", "cov_fitted", "cov_empirical", "cov0", "initial_cov", "corr",
                             "start_cov", "covariance"})
NOT_COVARIANCE_PARENTS = frozenset({"se", "z"})

#: Keys whose value may be ``null`` on success, and why (the contract, not a failure):
NULL_KEYS: dict[str, str] = {
    # track: no covariance propagated (--no-covariance, or a robot file without [noise])
    "cov": "track: no covariance propagated",
    "ros_pose_covariance": "track: no covariance propagated",
    # odomkit check: a finding without advice or without a measured value
    "advice": "check: a finding that needs no advice",
    "value": "check: a finding with no single measured value",
    "truth": "check: no truth file given",
    # fit-noise / evaluate: --window not given (one window per log)
    "window": "fit-noise/evaluate: no --window, one window per log",
    # evaluate: no verdict without --window (one end per log is no test), and no note where
    # the NEES and the coverage agree
    "coverage_bounds": "evaluate: no --window, no verdict",
    "coverage_verdict": "evaluate: no --window, no verdict",
    "coverage_overall": "evaluate: no --window, no verdict",
    "nees_verdict": "evaluate: no --window, no verdict",
    "verdict_note": "evaluate: NEES and coverage agree",
    # evaluate: a log's caution where it has too few window ends to judge (none from 20 on,
    # or without --window, where no verdict is given at all)
    "few_ends": "evaluate: enough window ends for a verdict, or no --window",
    # evaluate: the heading's NEES and coverage need truth with heading (position-only truth
    # has none) and a covariance; its verdicts need --window too, as the position's
    "nees_heading_mean": "evaluate: truth without heading, or no covariance",
    "nees_heading_median": "evaluate: truth without heading, or no covariance",
    "nees_heading_bounds": "evaluate: truth without heading, or no covariance",
    "coverage_heading": "evaluate: truth without heading, or no covariance",
    "coverage_heading_bounds": "evaluate: no --window or truth without heading, no verdict",
    "coverage_heading_verdict": "evaluate: no --window or truth without heading, no verdict",
    "coverage_heading_overall": "evaluate: no --window or truth without heading, no verdict",
    "nees_heading_verdict": "evaluate: no --window or truth without heading, no verdict",
    "verdict_heading_note": "evaluate: the heading's NEES and coverage agree, or no heading verdict",
    # evaluate: a window end's heading error and NEES, where the truth has no heading (or the
    # predicted heading variance is zero)
    "heading_error": "evaluate: a window end without truth heading",
    "nees_heading": "evaluate: a window end without truth heading or heading variance",
    # evaluate: the whole run's start is one log's (null for a track file, or several logs)
    "start_time": "evaluate: a track file or several logs",
    "start_heading": "evaluate: a track file or several logs",
    "start_heading_sigma": "evaluate: a track file or several logs",
    "start_heading_fitted": "evaluate: a track file or several logs",
    # umbmark: an infinite turning radius (no Type-A curvature), and the 3·SEM verdict
    # needs two runs per direction
    "radius": "umbmark: infinite radius",
    "second_compensation_advised": "umbmark: fewer than 2 runs, no verdict",
    # predict: correlation coefficients of a zero variance are undefined
    "xy": "predict: correlation of a zero variance", "xtheta": "predict: correlation of a zero variance",
    "ytheta": "predict: correlation of a zero variance",
}
#: Keys under which any value may be null: correlations (``corr.xy``, ``z.corr.xy``...) of a
#: zero variance.
NULL_SUBTREES = frozenset({"corr"})
#: simulate's z-scores (``z.mean``, ``z.std``, ``z.cov``) may be null only with a warning that
#: names them: they are ±inf where a predicted variance is zero, which JSON cannot spell.
Z_SCORES = "z"

#: umbmark: the spread of the return errors (``sigma``, ``sem``) needs two runs per direction;
#: with fewer they are null, as ``second_compensation_advised`` is ("unknown (< 2 runs)"),
#: and a warning says so.
NULL_IF_FEW_RUNS = frozenset({"sigma", "sem"})

#: Keys of a figure that may be undefined (``null``) when the JSON's ``warnings`` say why (or,
#: for track, its ``cov`` is null: no covariance, no NEES):
#: evaluate's RPE over a distance the truth never travels (or without a truth heading), NEES
#: and coverage of a track without covariance, drift of a truth that does not move. Children
#: of these keys (``rpe.1``, ``coverage.0.95``) count too.
NULL_IF_WARNED = frozenset({"rpe", "nees_position_mean", "nees_position_median", "nees_bounds",
                            "coverage", "inside_95_fraction", "drift_percent"})
#: List positions that may be null: an open interval bound (a profile-likelihood interval has
#: no upper end when the likelihood never drops far enough: fit-amcl's and fit-noise's
#: ``interval95``, calibrate-noise's ``ci_left``/``ci_right``, each with a warning), keyed by
#: the list's key or its parent's.
NULL_IN_LISTS = frozenset({"interval", "ci_left", "ci_right"})


def _reject_constant(name: str) -> float:
    raise ValueError(f"JSON holds {name}, which is not JSON")


def _walk(value: object, path: tuple[str, ...]) -> Iterator[tuple[tuple[str, ...], object]]:
    yield path, value
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _walk(item, (*path, str(key)))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from _walk(item, (*path, f"[{i}]"))


def _null_allowed(path: tuple[str, ...], warned: bool, few_runs: bool = False) -> bool:
    keys = [p for p in path if not p.startswith("[")]
    if not keys:
        return False
    if keys[0] == Z_SCORES and len(keys) > 1 and keys[1] != "corr":
        return warned
    if path[-1].startswith("[") and any(k.startswith(tuple(NULL_IN_LISTS)) for k in keys[-2:]):
        return True
    if warned and any(k in NULL_IF_WARNED for k in keys[-2:]):
        return True
    if any(k in NULL_SUBTREES for k in keys):
        return True
    if few_runs and warned and any(k in NULL_IF_FEW_RUNS for k in keys):
        return True
    return not path[-1].startswith("[") and keys[-1] in NULL_KEYS


def _is_matrix(value: object) -> bool:
    return (isinstance(value, list) and len(value) > 0
            and all(isinstance(r, list) and len(r) == len(value) for r in value))


def check_covariance(name: str, value: object) -> None:
    """A finite, symmetric, PSD matrix (or a list of them)."""
    if isinstance(value, list) and value and _is_matrix(value[0]):
        for i, item in enumerate(value):
            check_covariance(f"{name}[{i}]", item)
        return
    assert _is_matrix(value), f"{name} is not a square matrix: {value!r}"
    assert all(isinstance(x, int | float) and not isinstance(x, bool)
               for row in value for x in row), f"{name} holds a non-number: {value!r}"
    m = np.array(value, dtype=float)
    assert np.all(np.isfinite(m)), f"{name} is not finite: {value!r}"
    scale = float(np.max(np.abs(m))) if m.size else 0.0
    assert np.max(np.abs(m - m.T)) <= 1e-12 * scale, f"{name} is not symmetric: {value!r}"
    if scale > 0:
        low = float(np.min(np.linalg.eigvalsh(0.5 * (m + m.T))))
        assert low >= -1e-12 * scale, f"{name} is not PSD (eigenvalue {low:.3g}): {value!r}"


def check_json(text: str) -> dict[str, Any]:
    """Property 3 on a command's ``--json`` output."""
    try:
        doc = json.loads(text, parse_constant=_reject_constant)
    except ValueError as exc:
        raise AssertionError(f"stdout is not one JSON object ({exc}): {text[:300]!r}") from None
    assert isinstance(doc, dict), f"JSON is not an object: {text[:200]!r}"
    # Explained: a warning says why, or the track has no covariance at all (track's own
    # ground_truth.nees_position_mean needs one).
    warned = bool(doc.get("warnings")) or ("cov" in doc and doc["cov"] is None)
    few_runs = "second_compensation_advised" in doc and doc["second_compensation_advised"] is None
    for path, value in _walk(doc, ()):
        where = ".".join(path)
        if value is None:
            assert _null_allowed(path, warned, few_runs), (
                f"null where a number is expected: {where} (warnings: {doc.get('warnings')})")
        if isinstance(value, float):
            assert math.isfinite(value), where
        if path and path[-1] == "ros_pose_covariance" and isinstance(value, list):
            assert len(value) == 36, f"{where} is not 6x6: {value!r}"
            check_covariance(where, [value[i:i + 6] for i in range(0, 36, 6)])
        if path and path[-1] in COVARIANCE_KEYS and not (
                len(path) > 1 and path[-2] in NOT_COVARIANCE_PARENTS) and isinstance(value, list):
            check_covariance(where, value)
    return doc


_WARNING = "odomkit: warning: "
_ERROR = "odomkit: error: "


def check_streams(result: RunResult, allowed_codes: frozenset[int]) -> None:
    """Properties 1 and 2."""
    described = f"odomkit {' '.join(map(repr, result.argv))}"
    if result.exception is not None:
        exc = result.exception
        raise AssertionError(f"{described} raised {type(exc).__name__}: {exc}") from exc
    assert result.code in allowed_codes, f"{described}: exit {result.code}\n{result.err}"
    assert not result.escaped, f"{described}: warnings escaped as Python warnings: {result.escaped}"
    lines = result.err.splitlines()
    others = [ln for ln in lines if not ln.startswith(_WARNING)]
    if result.code == 2:
        assert len(others) == 1 and others[0].startswith(_ERROR) and lines[-1] == others[0], (
            f"{described}: exit 2 must end with one 'odomkit: error:' line; stderr:\n{result.err}")
        assert len(others[0]) > len(_ERROR), described
    else:
        assert not others, f"{described}: exit {result.code} printed on stderr:\n{result.err}"


def _snapshot(folder: Path) -> dict[str, tuple[bytes, int] | None]:
    """Every file (bytes, mtime) and folder (None) under ``folder``."""
    seen: dict[str, tuple[bytes, int] | None] = {}
    for path in folder.rglob("*"):
        rel = path.relative_to(folder).as_posix()
        if path.is_dir():
            seen[rel] = None
        elif path.is_file():
            seen[rel] = (path.read_bytes(), path.stat().st_mtime_ns)
    return seen


def _output_paths(case: Case) -> set[str]:
    named = set()
    for i, token in enumerate(case.argv[:-1]):
        if token in case.output_flags:
            value = case.argv[i + 1]
            named.add(os.path.normpath(value) if value else value)
            if case.derived:
                named.update(os.path.normpath(p) for p in case.derived(token, value))
    return named


def check_case(case: Case, *, allowed_codes: frozenset[int] = frozenset({0, 2})) -> RunResult:
    """Create the case's files in a fresh folder, run it, check the four properties."""
    with tempfile.TemporaryDirectory(prefix="odomkit-fuzz-") as tmp:
        folder = Path(tmp)
        for name, data in case.files.items():
            target = folder / name
            if data is None:
                target.mkdir(parents=True, exist_ok=True)
            else:
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
                os.utime(target, ns=(1_000_000_000_000_000_000, 1_000_000_000_000_000_000))
        before = _snapshot(folder)
        result = run_in(folder, case.argv)
        check_streams(result, allowed_codes)
        if result.code == 0 and "--json" in case.argv:
            check_json(result.out)
        after = _snapshot(folder)
        described = f"odomkit {' '.join(map(repr, case.argv))}"
        force = "--force" in case.argv
        outputs = _output_paths(case)
        inputs = {os.path.normpath(t) for i, t in enumerate(case.argv)
                  if t and (i == 0 or case.argv[i - 1] not in case.output_flags)}
        for rel, state in before.items():
            if state is None:
                assert rel in after, f"{described} removed the folder {rel}"
                continue
            replaceable = (force and result.code == 0 and rel not in inputs
                           and any(rel == o or rel.startswith(o.rstrip("/") + "/") for o in outputs if o))
            if not replaceable:
                assert after.get(rel) == state, f"{described} changed {rel} (exit {result.code})"
        if result.code != 0:
            new = sorted(set(after) - set(before))
            assert not new, f"{described} failed (exit {result.code}) but wrote {new}"
    return result
