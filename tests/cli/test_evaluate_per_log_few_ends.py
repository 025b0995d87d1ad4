"""Each log's line of ``evaluate --window`` with several logs gives no verdict from fewer ends
than the pooled figures' few-ends rule (user study 30: an F1TENTH's per-log lines read
"coverage consistent" from 1–3 ends, one with a NEES mean of 27.1, and "1 ends").

Independent truth: each log's window count is floor(duration / 10 s) of the simulated logs,
and the range the few-ends note quotes is scipy's binomial 2.5 and 97.5 % points.
"""

from __future__ import annotations

import json

from scipy import stats


def test_a_logs_verdict_from_fewer_ends_than_the_rule_is_not_judged(run_cli, tmp_path, noisy_diff_log):
    logs = {}
    for name, seconds in (("long", 250.0), ("one", 12.0), ("three", 35.0)):
        folder = tmp_path / name
        folder.mkdir()
        logs[name] = noisy_diff_log(folder, 0.01, 0.01, seconds, seed=len(logs) + 3)
    args = ["evaluate", *(log for log, _, _ in logs.values()), "--robot", logs["long"][2], "--window", "10s",
            "--columns", "t=t,dist_left=L,dist_right=R"]
    for _, gt, _ in logs.values():
        args += ["--truth", gt]
    code, out, err = run_cli(*args)
    assert code == 0, err
    _, js, _ = run_cli(*args, "--json")
    per_log = {p["log"]: p for p in json.loads(js)["per_log"]}
    ends = {name: per_log[str(log)]["windows"] for name, (log, _, _) in logs.items()}
    assert ends == {"long": 25, "one": 1, "three": 3}  # floor(duration / 10 s)
    lines = {name: next(x for x in out.splitlines() if x.startswith(f"  {log}: "))
             for name, (log, _, _) in logs.items()}
    long = per_log[str(logs["long"][0])]
    assert long["few_ends"] is None
    assert "25 ends, inside 95 %" in lines["long"]
    assert f", coverage {long['coverage_overall']};" in lines["long"]
    assert f"coverage {long['coverage_heading_overall']}" in lines["long"]
    for name, n in (("one", 1), ("three", 3)):
        line = lines[name]
        assert f": {n} {'end' if n == 1 else 'ends'}, inside 95 %" in line, line
        assert "not judged (under 20 ends)" in line and "coverage" not in line, line
        low = stats.binom.ppf(0.025, n, 0.95) / n
        assert f"falls anywhere in {low:.2f}..1.00" in per_log[str(logs[name][0])]["few_ends"]
    assert "1 ends" not in out and "1 ends" not in err
