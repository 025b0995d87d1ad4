"""Warnings that differ only in the log they name are one line, on stderr and in the JSON
(user study, issue 11: 25 lines of "no RPE over 1 m" scrolled the results away).

Facts checked: the one line names how many logs say it (counted from the command's own
input), at most three of them and how many more; a pooled count of windows left out equals
the windows scored without the limit minus those scored with it.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]


def _warning_lines(err: str) -> list[str]:
    return [x for x in err.splitlines() if x.startswith("odomkit: warning: ")]


def test_a_warning_every_log_gives_is_one_line_naming_three_and_how_many_more(run_cli):
    args = ("evaluate", *RUNS, "--robot", ROBOT, "--window", "10s", "--rpe", "100")
    code, out, err = run_cli(*args)
    assert code == 0
    rpe = [x for x in _warning_lines(err) if "no RPE over 100 m" in x]
    assert len(rpe) == 1, err
    line = rpe[0]
    assert f"{len(RUNS)} logs (" in line and f"and {len(RUNS) - 3} more" in line
    assert sum(Path(r).name in line for r in RUNS) == 3
    assert "the truth travels less than the distance" in line
    # The JSON says it the same way, and each log's own entry keeps its own line.
    code, js, _ = run_cli(*args, "--json")
    got = json.loads(js)
    said = line.removeprefix("odomkit: warning: ")
    assert [w for w in got["warnings"] if "no RPE over 100 m" in w] == [said]
    for one in got["per_log"]:
        assert any(w.startswith(f"{one['log']}: no RPE over 100 m") for w in one["warnings"])


def test_windows_left_out_for_too_little_travel_are_counted_once(run_cli):
    def run(*extra):
        code, out, err = run_cli("evaluate", *RUNS, "--robot", ROBOT, "--window", "10s", *extra, "--json")
        assert code == 0
        return json.loads(out), _warning_lines(err)

    every, said = run("--min-travel", "0")
    assert not [x for x in said if "travelled less" in x]
    fewer, said = run("--min-travel", "0.2")
    left_out = every["windows"] - fewer["windows"]
    assert left_out > 0
    travel = [x for x in said if "travelled less than 0.2 m" in x]
    assert len(travel) == 1, said
    pairs = zip(every["per_log"], fewer["per_log"], strict=True)
    moving = sum(1 for a, b in pairs if a["windows"] > b["windows"])
    assert f"{left_out} window(s)" in travel[0] and (moving == 1 or f"of {moving} logs" in travel[0])


def test_the_shared_printer_groups_by_the_text_after_the_path(capsys):
    from odomkit.cli.log_options import reported_warnings, with_warnings

    same = [f"/data/{d}/odom.csv" for d in ("a", "b")]  # one name in two folders: full paths
    with reported_warnings() as warned:
        for path in same:
            warnings.warn(f"{path}: the robot stands still", stacklevel=1)
        warnings.warn("/data/c/run.csv: the truth lags", stacklevel=1)
        warnings.warn("/data/d/run2.csv: the truth lags by 3 s", stacklevel=1)  # not the same text
        warnings.warn("a warning about no log", stacklevel=1)
    err = capsys.readouterr().err
    lines = _warning_lines(err)
    assert lines == ["odomkit: warning: 2 logs (/data/a/odom.csv, /data/b/odom.csv): the robot stands still",
                     "odomkit: warning: /data/c/run.csv: the truth lags",
                     "odomkit: warning: /data/d/run2.csv: the truth lags by 3 s",
                     "odomkit: warning: a warning about no log"]
    # The JSON list: the command's own list and the raised ones, grouped alike, once each.
    out = with_warnings({"warnings": ["/data/e/x.csv: the robot stands still"]}, warned)
    assert out["warnings"][0] == ("3 logs (/data/e/x.csv, /data/a/odom.csv, /data/b/odom.csv): the robot "
                                  "stands still")
    assert len(out["warnings"]) == 4
