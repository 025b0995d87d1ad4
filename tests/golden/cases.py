"""The CLI calls whose ``--json`` output is frozen as golden files (issue 9).

Each case is ``(name, argv)``; ``{data}`` is the built-in data folder and ``{inputs}`` the
folder of small hand-written inputs beside this file. ``python tests/golden/cases.py``
rewrites every golden file from the current code: do that only in a commit that changes an
output on purpose, and say why in its message.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
DATA = HERE.parents[1] / "src" / "odomkit" / "data"
INPUTS = HERE / "inputs"
RUNS = [f"{{data}}/230620202042_run-0{i}.csv" for i in range(1, 7)]
ROBOT = "{data}/optiodom_diff.toml"

DIFF = ["--model", "diff", "--wheel-base", "0.4", "--k-left", "0.001", "--k-right", "0.001"]
GYRO = ["--model", "gyro", "--speed-noise", "1e-4", "--gyro-noise", "1e-5"]
COMPASS = ["--model", "compass", "--speed-noise", "1e-4", "--heading-noise", "1e-5"]
CLASSICAL = ["--model", "diff", "--noise", "classical", "--wheel-base", "0.4",
             "--sigma-distance", "0.01", "--sigma-angle", "0.01"]
SQUARE = ["--segment", "straight:2", "--segment", "spin:1.5707963267948966",
          "--segment", "straight:2"]
KELLY = ["--segment", "arc:0.5,0.2,10", "--segment", "arc:0.5,0,5"]
MC = ["--runs", "2000", "--partitions", "50", "--seed", "7"]

CASES: list[tuple[str, list[str]]] = [
    ("track_run1", ["track", RUNS[0], "--robot", ROBOT]),
    ("track_run3_transition", ["track", RUNS[2], "--robot", ROBOT, "--engine", "transition"]),
    ("track_run2_midpoint", ["track", RUNS[1], "--robot", ROBOT, "--method", "midpoint",
                             "--initial-pose", "1,2,0.5"]),
    ("track_tricycle_speed", ["track", "{inputs}/tricycle_speed.csv",
                              "--robot", "{inputs}/tricycle.toml",
                              "--columns", "t=t,speed=speed,steer=steer"]),
    ("track_gyro", ["track", "{inputs}/gyro.csv", "--robot", "{inputs}/gyro.toml",
                    "--columns", "t=t,speed=speed,yaw_rate=yaw_rate"]),
    ("track_compass", ["track", "{inputs}/compass.csv", "--robot", "{inputs}/compass.toml",
                       "--columns", "t=t,speed=speed,heading=heading"]),
    ("predict_diff_arc", ["predict", *DIFF, "--segment", "arc:3,1"]),
    ("predict_diff_square_cov0", ["predict", *DIFF, *SQUARE, "--initial-cov", "1e-4,1e-4,1e-3"]),
    ("predict_diff_recursion", ["predict", *DIFF, "--segment", "arc:3,1", "--engine", "recursion",
                                "--partitions", "200"]),
    ("predict_diff_transition", ["predict", *DIFF, "--segment", "arc:3,1", "--engine",
                                 "transition", "--partitions", "200"]),
    ("predict_classical", ["predict", *CLASSICAL, "--segment", "arc:3,1", "--partitions", "4"]),
    ("predict_gyro", ["predict", *GYRO, *KELLY]),
    ("predict_gyro_recursion", ["predict", *GYRO, *KELLY, "--engine", "recursion",
                                "--partitions", "100"]),
    ("predict_compass", ["predict", *COMPASS, *KELLY]),
    ("simulate_diff", ["simulate", *DIFF, "--segment", "arc:3,1", *MC]),
    ("simulate_diff_systematic", ["simulate", *DIFF, *SQUARE, *MC, "--systematic",
                                  "1.002,1.01,1.0"]),
    ("simulate_classical", ["simulate", *CLASSICAL, "--segment", "arc:3,1", *MC]),
    ("simulate_gyro", ["simulate", *GYRO, *KELLY, *MC]),
    ("simulate_compass", ["simulate", *COMPASS, *KELLY, *MC]),
    ("umbmark_errors", ["umbmark", "{inputs}/errors.csv", "--side", "4", "--wheel-base", "0.34"]),
    ("umbmark_runs", ["umbmark", "--runs", *RUNS, "--robot", ROBOT, "--side", "0.75"]),
    ("calibrate_exact", ["calibrate", *RUNS, "--robot", ROBOT, "--side", "0.75"]),
    ("calibrate_trajectories", ["calibrate", *RUNS, "--robot", ROBOT, "--from", "trajectory"]),
    ("calibrate_umbmark", ["calibrate", *RUNS, "--robot", ROBOT, "--method", "umbmark",
                           "--side", "0.75"]),
    ("calibrate_noise", ["calibrate-noise", *RUNS, "--robot", ROBOT]),
]

# Keys whose values are wall-clock measurements, not results.
VOLATILE = {"seconds"}


def expand(argv: list[str]) -> list[str]:
    return [a.replace("{data}", str(DATA)).replace("{inputs}", str(INPUTS)) for a in argv]


def scrub(obj: object) -> object:
    """The JSON object without its wall-clock keys, and with the input folders' paths (a
    run's name in ``calibrate``'s ``per_run``) as ``{data}`` and ``{inputs}``, so that the
    golden files hold no checkout's location."""
    if isinstance(obj, dict):
        return {k: scrub(v) for k, v in obj.items() if k not in VOLATILE}
    if isinstance(obj, list):
        return [scrub(v) for v in obj]
    if isinstance(obj, str):
        return obj.replace(str(DATA), "{data}").replace(str(INPUTS), "{inputs}")
    return obj


def run_case(argv: list[str]) -> str:
    """The scrubbed ``--json`` output of one CLI call, as canonical text."""
    import contextlib
    import io

    from odomkit.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main([*expand(argv), "--json"])
    if code != 0:
        raise RuntimeError(f"{argv}: exit {code}")
    return json.dumps(scrub(json.loads(out.getvalue())), indent=1, sort_keys=True) + "\n"


if __name__ == "__main__":
    names = set(sys.argv[1:])
    for name, argv in CASES:
        if names and name not in names:
            continue
        (HERE / f"{name}.json").write_text(run_case(argv))
        print("wrote", name)
