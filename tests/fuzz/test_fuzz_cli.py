"""Fuzz every command in-process (issue 10, item 8): hostile flags, files and output paths.

Each test draws a :class:`Case` (files in a fresh folder, an argv) for one command, runs it
with ``odomkit.cli.main`` and checks the four properties of :func:`_fuzz.check_case`:
exit 0 or 2, one ``odomkit: error:`` line on exit 2, finite symmetric PSD covariances and
no stray null in ``--json``, and no user file changed. Budgets are small (the whole folder
runs in well under a minute); ``ODOMKIT_FUZZ_SCALE=20`` searches deeper.
"""

from __future__ import annotations

import importlib.util
import sys
import tempfile
from functools import cache
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

_spec = importlib.util.spec_from_file_location("odomkit_fuzz", Path(__file__).with_name("_fuzz.py"))
assert _spec is not None and _spec.loader is not None
fz = sys.modules.setdefault("odomkit_fuzz", importlib.util.module_from_spec(_spec))
if not hasattr(fz, "check_case"):
    _spec.loader.exec_module(fz)

Case = fz.Case
one, number, integer, word, floats_text = fz.one, fz.number, fz.integer, fz.word, fz.floats_text

RUN_NAMES = [f"exp_run-0{i}.csv" for i in range(1, 7)]


def _json(draw) -> list[str]:
    """``--json`` mostly; sometimes the text report (its printing is fuzzed too)."""
    return ["--json"] if draw(st.integers(0, 5)) < 5 else []


def _kitti_times(flag: str, value: str) -> list[str]:
    if flag == "--kitti" and value:
        from odomkit.io.trackio import kitti_times_path

        return [str(kitti_times_path(value))]
    return []


@cache
def _track_csv(covariance: bool = True, rows: int | None = None) -> bytes:
    """Run 1 dead-reckoned by ``odomkit track --out`` (the input of evaluate and fit-amcl)."""
    with tempfile.TemporaryDirectory() as tmp:
        args = ["track", str(fz.RUNS[0]), "--robot", str(fz.DATA / "optiodom_diff.toml"),
                "--out", "t.csv"] + ([] if covariance else ["--no-covariance"])
        result = fz.run_in(Path(tmp), args)
        assert result.code == 0, result.err
        return fz._head(Path(tmp) / "t.csv", None if rows is None else rows + 1)


def _log(draw, case: Case, names=None) -> tuple[str, str | None, dict]:
    """A log (possibly edited) and the robot tables that go with it: (file name, --columns, robot)."""
    logs = fz.logs()
    name = draw(st.sampled_from(names or sorted(logs)))
    data, robot, columns = logs[name]
    if draw(st.integers(0, 3)) == 3:
        data = draw(fz.mutated_table(data))
    file = case.file("exp_run-01.csv" if name.startswith("run") else f"{name}.csv", data)
    return file, columns, robot


def _robot(draw, case: Case, tables: dict) -> str:
    return case.file("robot.toml", draw(fz.robot_file(tables)))


def _runs(draw, case: Case) -> list[str]:
    """The six OptiOdom runs, one of them possibly edited, sometimes fewer of them."""
    names = []
    bad = draw(st.sampled_from([None, None, *range(6)]))
    for i, (src, name) in enumerate(zip(fz.RUNS, RUN_NAMES, strict=True)):
        data = src.read_bytes()
        if i == bad:
            data = draw(fz.mutated_table(data))
        names.append(case.file(name, data))
    keep = draw(st.sampled_from((6, 6, 6, 2, 1)))
    return names[:keep] if keep == 6 else draw(st.permutations(names))[:keep]


def _outputs(draw, case: Case, flags: dict[str, str], inputs: list[str], p: int = 3) -> None:
    """Each output flag with chance 1/p, at a drawn path; ``--force`` sometimes."""
    chosen: list[str] = []
    for flag, suffix in flags.items():
        if draw(st.integers(0, p - 1)) == p - 1:
            chosen.append(draw(fz.output_path(case, suffix, inputs, chosen)))
            case.add(flag, chosen[-1])
    if draw(st.integers(0, 2)) == 2:
        case.add("--force")


def _log_options(draw, most: int = 1) -> list[str]:
    return draw(fz.options(fz.LOG_OPTION_MENU, most=most)) if draw(st.integers(0, 4)) == 4 else []


def _truth(draw, case: Case, flag_each: int = 1) -> list[str]:
    argv = []
    if draw(st.integers(0, 2)) == 2:
        for i in range(flag_each):
            argv += ["--truth", case.file(f"truth{i}.txt", draw(fz.truth_file()))]
    if draw(st.integers(0, 3)) == 3:
        argv += draw(fz.options(fz.TRUTH_OPTION_MENU, most=2))
    return argv


# --------------------------------------------------------------------------------------- track

TRACK_MENU = [
    ("--method", one(word(("exact", "midpoint", "euler")))),
    ("--initial-pose", one(word(("0,0,0", "1,2,0.5", "nan,0,0", "1e308,1e308,3", "1,2", "1e-320,0,1e300")))),
    ("--theta0-deg", None),
    ("--initial-cov", one(word(("0,0,0", "1e-4,1e-4,1e-3", "-1,0,0", "1,2,3,4,5,6,7,8,9", "nan,0,0",
                                "1e308,1e308,1e308", "1,0,0,0,-1,0,0,0,1", "1e-320,0,0")))),
    ("--no-covariance", None),
    ("--engine", one(word(("recursion", "transition")))),
    ("--bag-format", one(word(("ros1", "db3", "mcap")))),
    ("--frame-id", one(word(("odom", "")))),
    ("--child-frame-id", one(word(("base_link", "")))),
]


@st.composite
def track_cases(draw) -> Case:
    case = Case(output_flags=("--out", "--tum", "--kitti", "--bag-out"), derived=_kitti_times)
    log, columns, robot = _log(draw, case)
    robot_path = _robot(draw, case, robot)
    case.add("track", log, "--robot", robot_path)
    if columns:
        case.add("--columns", columns)
    case.argv += draw(fz.options(TRACK_MENU, most=2)) + _log_options(draw) + _truth(draw, case)
    _outputs(draw, case, {"--out": ".csv", "--tum": ".tum", "--kitti": ".txt", "--bag-out": ".bag"},
             [log, robot_path], p=4)
    case.argv += _json(draw)
    return case


@fz.fuzz_settings(60)
@given(case=track_cases())
def test_fuzz_track(case):
    fz.check_case(case)


# ---------------------------------------------------------------------------- predict, simulate

MODELS = {
    "wheel": (["--model", "diff", "--noise", "wheel"],
              [("--wheel-base", ("0.4", "0.2")), ("--k-left", ("0.001", "0")),
               ("--k-right", ("0.001", "0.01"))]),
    "classical": (["--model", "diff", "--noise", "classical"],
                  [("--wheel-base", ("0.4",)), ("--sigma-distance", ("0.01", "0")),
                   ("--sigma-angle", ("0.01",))]),
    "gyro": (["--model", "gyro"], [("--speed-noise", ("1e-4", "0")), ("--gyro-noise", ("1e-5", "0"))]),
    "compass": (["--model", "compass"], [("--speed-noise", ("1e-4",)), ("--heading-noise", ("1e-5", "0"))]),
}
STRAY = ["--wheel-base", "--k-left", "--sigma-angle", "--gyro-noise", "--heading-noise", "--compass-period"]


@st.composite
def _segments(draw, model: str) -> list[str]:
    small = number(floats_text(-3, 3), odds=40)
    positive = number(("1", "2", "10", "0.5"), odds=40)
    argv = []
    for _ in range(draw(st.sampled_from((1, 1, 1, 2, 2, 3, 3, 3, 3, 0)))):
        if model in ("wheel", "classical"):
            kind = draw(st.sampled_from(("arc", "straight", "spin") * 4 + ("bogus",)))
            values = {"arc": 2, "straight": 1, "spin": 1, "bogus": 1}[kind]
        else:
            kind = draw(st.sampled_from(("arc", "straight") * 5 + ("spin",)))
            values = {"arc": 3, "straight": 2, "spin": 1}[kind]
        nums = [draw(small) for _ in range(values - 1)] + [draw(positive if model in ("gyro", "compass")
                                                                 else small)]
        if draw(st.integers(0, 19)) == 19:
            nums = nums[:-1]
        argv += ["--segment", f"{kind}:{','.join(nums)}"]
    return argv


def _model_args(draw) -> tuple[str, list[str]]:
    model = draw(st.sampled_from(sorted(MODELS)))
    head, flags = MODELS[model]
    argv = list(head)
    for flag, valid in flags:
        if draw(st.integers(0, 19)) < 19:  # mostly given
            argv += [flag, draw(number(valid))]
    if model == "compass" and draw(st.booleans()):
        argv += ["--compass-period", draw(number(("0.1", "0.05", "1")))]
    if draw(st.integers(0, 7)) == 7:
        argv += [draw(st.sampled_from(STRAY)), "0.1"]
    return model, argv


INITIAL_MENU = [
    ("--initial-pose", one(word(("0,0,0", "1,2,0.5", "nan,0,0", "1e308,0,0", "1,2")))),
    ("--initial-cov", one(word(("1e-4,1e-4,1e-3", "-1,0,0", "1e308,1e308,1e308", "0,0,0")))),
    ("--initial-cov-matrix", one(word(("1,0,0;0,1,0;0,0,1", "1,2,0;2,1,0;0,0,1", "1,0;0,1",
                                       "1,1e308,0;1e308,1,0;0,0,1", "1,0.5,0;0.4,1,0;0,0,1")))),
]


@st.composite
def predict_cases(draw) -> Case:
    model, argv = _model_args(draw)
    case = Case().add("predict", *argv, *draw(_segments(model)))
    menu = INITIAL_MENU + [
        ("--engine", one(word(("closed", "recursion", "transition")))),
        ("--partitions", one(integer(("1", "10", "200")))),
    ]
    case.argv += draw(fz.options(menu, most=3)) + _json(draw)
    return case


@fz.fuzz_settings(80)
@given(case=predict_cases())
def test_fuzz_predict(case):
    fz.check_case(case)


@st.composite
def simulate_cases(draw) -> Case:
    model, argv = _model_args(draw)
    case = Case().add("simulate", *argv, *draw(_segments(model)))
    # Small runs, and a work limit that refuses a huge --runs/--partitions at once.
    base = {"--runs": "64", "--partitions": "8", "--workers": "1", "--max-work": "2e5"}
    menu = INITIAL_MENU + [
        ("--runs", one(integer(("1", "2", "64")))),
        ("--partitions", one(integer(("1", "3", "8")))),
        ("--seed", one(integer(("0", "7")))),
        ("--workers", one(st.sampled_from(("1", "0", "-1", "abc")))),
        ("--chunk-runs", one(integer(("1", "256")))),
        ("--scheduler", one(st.sampled_from(("", " ", "tcp://", "::", "a b", "host:", ":1")))),
        ("--systematic", one(word(("1.002,1.01,1.0", "1,1,1", "0,1,1", "-1,1,1", "1,nan,1", "1,1")))),
        ("--alpha", one(number(("0.01", "0.5")))),
        ("--max-work", one(st.sampled_from(("0", "-1", "nan", "abc", "1e-320", "5e4")))),
    ]
    chosen = draw(fz.options(menu, most=3))
    for flag, value in base.items():
        if flag not in chosen:
            case.add(flag, value)
    case.argv += chosen + _json(draw)
    return case


@fz.fuzz_settings(60)
@given(case=simulate_cases())
def test_fuzz_simulate(case):
    fz.check_case(case)


# ------------------------------------------------------------------------------------- umbmark

@st.composite
def umbmark_cases(draw) -> Case:
    case = Case()
    side = ["--side", draw(number(("4", "0.75")))] if draw(st.integers(0, 7)) < 7 else []
    if draw(st.booleans()):
        errors = case.file("errors.csv", draw(fz.umbmark_errors()))
        case.add("umbmark", errors, *side)
        if draw(st.integers(0, 3)) < 3:
            case.add("--wheel-base", draw(number(("0.34", "0.2"))))
        else:
            case.add("--robot", _robot(draw, case, fz.ROBOTS["diff"]))
        if draw(st.integers(0, 5)) == 5:
            case.argv += _log_options(draw)
    else:
        case.add("umbmark", "--runs", *_runs(draw, case), *side)
        if draw(st.integers(0, 7)) < 7:
            case.add("--robot", _robot(draw, case, fz.ROBOTS["diff"]))
        if draw(st.integers(0, 7)) == 7:
            case.add("--wheel-base", "0.2")
        case.argv += _log_options(draw)
    case.argv += _json(draw)
    return case


@fz.fuzz_settings(60)
@given(case=umbmark_cases())
def test_fuzz_umbmark(case):
    fz.check_case(case)


# ----------------------------------------------------------------------- calibrate, -noise

CALIBRATE_MENU = [
    ("--method", one(word(("exact", "umbmark")))),
    ("--from", one(word(("endpoints", "trajectory")))),
    ("--side", one(number(("0.75", "4")))),
    ("--heading-weight", one(number(("0", "0.1", "1")))),
    ("--wheel-radius", one(number(("0.042",)))),
    ("--twist-speed", one(number(("0.2", "1")))),
    ("--controller-period", one(number(("0.02", "0.1")))),
    ("--velocity-window", one(integer(("1", "10")))),
]


@st.composite
def calibrate_cases(draw) -> Case:
    case = Case(output_flags=("--out-robot", "--ros-yaml"))
    runs = _runs(draw, case)
    robot = _robot(draw, case, fz.ROBOTS["diff"])
    case.add("calibrate", *runs, "--robot", robot)
    case.argv += draw(fz.options(CALIBRATE_MENU, most=3)) + _log_options(draw)
    _outputs(draw, case, {"--out-robot": ".toml", "--ros-yaml": ".yaml"}, [*runs, robot])
    case.argv += _json(draw)
    return case


@fz.fuzz_settings(60)
@given(case=calibrate_cases())
def test_fuzz_calibrate(case):
    fz.check_case(case)


@st.composite
def calibrate_noise_cases(draw) -> Case:
    case = Case(output_flags=("--plot",))
    runs = _runs(draw, case)
    robot = _robot(draw, case, fz.ROBOTS["diff"])
    case.add("calibrate-noise", *runs, "--robot", robot)
    menu = [
        ("--components", one(word(("x,y,theta", "x,theta", "theta", "x,x", "y")))),
        ("--known-mean", None),
        ("--level", one(number(("0.95", "0.5", "0.999999")))),
    ]
    case.argv += draw(fz.options(menu, most=2)) + _log_options(draw)
    _outputs(draw, case, {"--plot": ".png"}, [*runs, robot], p=8)
    case.argv += _json(draw)
    return case


@fz.fuzz_settings(40)
@given(case=calibrate_noise_cases())
def test_fuzz_calibrate_noise(case):
    fz.check_case(case)


# ------------------------------------------------------------------------------------ evaluate

WINDOWS = ("10s", "5m", "0s", "-1s", "1e308s", "nan s", "abc", "1e-320m", "30")
EVALUATE_MENU = [
    ("--min-travel", one(number(("0.05", "0", "1")))),
    ("--align", one(word(("none", "start", "se2")))),
    ("--rpe", one(word(("1", "0.5,1", "0", "-1", "nan", "1e308", "", "1e-320")))),
]


@st.composite
def evaluate_cases(draw) -> Case:
    case = Case()
    if draw(st.booleans()):
        tracks = [case.file(f"track{i}.csv", draw(fz.mutated_table(_track_csv(bool(i % 2 == 0)),
                                                                    max_changes=2)))
                  for i in range(draw(st.integers(1, 2)))]
        case.add("evaluate", *tracks)
        case.argv += _truth(draw, case, flag_each=draw(st.sampled_from((1, 1, len(tracks)))))
    else:
        log, columns, robot = _log(draw, case, ["run", "run_short", "diff_csv"])
        case.add("evaluate", log, "--robot", _robot(draw, case, robot))
        if columns:
            case.add("--columns", columns)
        if draw(st.booleans()):
            case.add("--window", draw(st.sampled_from(WINDOWS)))
        case.argv += _truth(draw, case) + _log_options(draw)
        if draw(st.integers(0, 3)) == 3:
            case.add("--method", draw(word(("exact", "midpoint", "euler"))))
    case.argv += draw(fz.options(EVALUATE_MENU, most=2)) + _json(draw)
    return case


@fz.fuzz_settings(60)
@given(case=evaluate_cases())
def test_fuzz_evaluate(case):
    fz.check_case(case)


# ----------------------------------------------------------------------------------- fit-noise

@st.composite
def fit_noise_cases(draw) -> Case:
    case = Case(output_flags=("--out",))
    robot_tables = {**fz.ROBOTS["diff"]}
    if draw(st.booleans()):
        robot_tables["noise.parameters"] = {"sigma_wheel_base": "0.001", "sigma_scale_left": "0.001"}
    robot = _robot(draw, case, robot_tables)
    logs = []
    for i in range(draw(st.integers(1, 3))):
        data = fz.RUNS[i].read_bytes()
        if draw(st.integers(0, 3)) == 3:
            data = draw(fz.mutated_table(data))
        logs.append(case.file(RUN_NAMES[i], data))
    case.add("fit-noise", "--robot", robot, *[a for log in logs for a in ("--log", log)])
    out = draw(fz.output_path(case, ".toml", [robot, *logs]))
    case.add("--out", out)
    menu = [
        ("--window", one(st.sampled_from(WINDOWS))),
        ("--kinds", one(word(("white", "bias", "white,bias", "white,white")))),
        ("--fix", one(word(("k_left", "sigma_wheel_base", "bogus", "k_left,k_right")))),
        ("--min-travel", one(number(("0.05", "0")))),
        ("--cross-validate", None),
        ("--level", one(number(("0.95", "0.5")))),
        ("--method", one(word(("exact", "midpoint", "euler")))),
        ("--workers", one(st.sampled_from(("1", "0", "-1", "abc")))),
        ("--scheduler", one(st.sampled_from(("", "tcp://", "a b")))),
    ]
    case.argv += draw(fz.options(menu, most=3)) + _truth(draw, case, flag_each=len(logs))
    case.argv += _log_options(draw)
    if draw(st.integers(0, 2)) == 2:
        case.add("--force")
    case.argv += _json(draw)
    return case


@fz.fuzz_settings(40)
@given(case=fit_noise_cases())
def test_fuzz_fit_noise(case):
    fz.check_case(case)


# ------------------------------------------------------------------------------------ fit-amcl

@st.composite
def fit_amcl_cases(draw) -> Case:
    case = Case(output_flags=("--yaml-out",))
    if draw(st.booleans()):
        odom = [case.file("track.csv", draw(fz.mutated_table(_track_csv(rows=600), max_changes=2)))]
        case.add("fit-amcl", *odom)
    else:
        log, columns, robot = _log(draw, case, ["run_short", "diff_csv"])
        odom = [log]
        case.add("fit-amcl", log, "--robot", _robot(draw, case, robot))
        if columns:
            case.add("--columns", columns)
        case.argv += _log_options(draw)
    menu = [
        ("--model", one(word(("diff", "omni")))),
        ("--update-min-d", one(number(("0.25", "0.1", "1")))),
        ("--update-min-a", one(number(("0.2", "0.5")))),
        ("--level", one(number(("0.95", "0.5")))),
        ("--method", one(word(("exact", "midpoint", "euler")))),
    ]
    case.argv += draw(fz.options(menu, most=2)) + _truth(draw, case)
    _outputs(draw, case, {"--yaml-out": ".yaml"}, odom)
    case.argv += _json(draw)
    return case


@fz.fuzz_settings(12)
@given(case=fit_amcl_cases())
def test_fuzz_fit_amcl(case):
    fz.check_case(case)


# --------------------------------------------------------------------------------------- check

@st.composite
def check_cases(draw) -> Case:
    case = Case()
    log, columns, robot = _log(draw, case)
    case.add("check", log, "--robot", _robot(draw, case, robot))
    if columns:
        case.add("--columns", columns)
    if draw(st.integers(0, 4)) == 4:
        case.add("--spin", draw(word(("ccw", "cw"))))
    case.argv += _truth(draw, case) + _log_options(draw) + _json(draw)
    return case


@fz.fuzz_settings(40)
@given(case=check_cases())
def test_fuzz_check(case):
    # Exit 1 is check's documented "a check failed" (with its report).
    fz.check_case(case, allowed_codes=frozenset({0, 1, 2}))


# ---------------------------------------------------------------------------------------- demo

@st.composite
def demo_cases(draw) -> Case:
    case = Case(output_flags=("--out",))
    case.add("demo")
    kind = draw(st.sampled_from(("default", "new", "existing_file", "existing_folder", "under_file",
                                 "empty")))
    if kind == "new":
        case.add("--out", "results/demo")
    elif kind == "existing_file":
        case.add("--out", case.file("results.txt", fz.PRECIOUS))
    elif kind == "existing_folder":
        case.file("results/keep.txt", fz.PRECIOUS)
        case.file("results/run-01_track.csv", fz.PRECIOUS)
        case.add("--out", "results")
    elif kind == "under_file":
        case.add("--out", case.file("plain.txt", fz.PRECIOUS) + "/demo")
    elif kind == "empty":
        case.add("--out", "")
    if draw(st.booleans()):
        case.add("--force")
    return case


@fz.fuzz_settings(4)
@given(case=demo_cases())
def test_fuzz_demo(case):
    result = fz.check_case(case)
    assert result.code == 2 or "outputs in" in result.out


# ------------------------------------------------------------------------ any command, any tokens

COMMANDS = ("track", "predict", "simulate", "umbmark", "calibrate", "calibrate-noise", "evaluate",
            "fit-noise", "fit-amcl", "check", "demo", "report")


@st.composite
def token_soup(draw) -> Case:
    """A command followed by tokens from every command's flags and hostile values: what
    click makes of nonsense (usage errors, missing arguments) must be one line too."""
    from odomkit.cli import commands  # noqa: F401  (registers the commands)
    from odomkit.cli.application import app

    flags = sorted({opt for cmd in app.registered_commands if cmd.callback
                    for opt in _flags_of(cmd.callback)})
    values = st.sampled_from(fz.NASTY_FLOATS + fz.NASTY_INTS + ("-", "--", "--help=x", "-x", "nofile.csv"))
    tokens = draw(st.lists(st.one_of(st.sampled_from(flags), values), max_size=6))
    # Never --help (exit 0 and the help text: fine, and not what this test is about) and never
    # a real network address for --scheduler.
    tokens = [t for t in tokens if t != "--help"]
    command = draw(st.sampled_from(COMMANDS + ("", "bogus", "--json")))
    return Case().add(*([command] if command else []), *tokens)


def _flags_of(callback) -> list[str]:
    import inspect

    names = []
    for param in inspect.signature(callback, eval_str=True).parameters.values():
        for meta in getattr(param.annotation, "__metadata__", ()):
            decls = getattr(meta, "param_decls", None) or ()
            default = getattr(meta, "default", None)
            names += [d.split("/")[0] for d in decls if d.startswith("--")]
            if isinstance(default, str) and default.startswith("--"):
                names.append(default.split("/")[0])
        names.append("--" + param.name.replace("_", "-"))
    return names


@fz.fuzz_settings(60)
@given(case=token_soup())
def test_fuzz_token_soup(case):
    # A bare `odomkit` prints the help on stdout (exit 0); anything else wrong is one line.
    fz.check_case(case)
