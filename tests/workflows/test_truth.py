"""The shared truth options: a truth file, or the log's own ground truth, one per log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.log import OdometryLog
from odomkit.workflows.truth import TruthOptions, load_truth, truth_options_per_log


def test_a_file_wins_over_the_log_and_sigma_reaches_the_truth(tmp_path):
    path = tmp_path / "gt.csv"
    path.write_text("t,x,y\n0,0,0\n1,1,0\n")
    log = OdometryLog(np.array([0.0, 1.0]), {"dist": np.zeros(2)}, np.zeros((2, 3)), "log.csv")
    from_file = load_truth(TruthOptions(path, sigma=0.01), log)
    assert from_file.source == str(path) and from_file.theta is None and from_file.sigma == 0.01
    from_log = load_truth(TruthOptions(sigma=0.02), log)
    assert from_log.source == "log.csv" and from_log.sigma == 0.02 and from_log.theta is not None
    assert load_truth(TruthOptions(), OdometryLog(np.zeros(1), {"dist": np.zeros(1)})) is None
    assert load_truth(TruthOptions()) is None


def test_one_truth_per_log():
    base = TruthOptions(format="tum", sigma=0.1)
    assert truth_options_per_log(base, [], 3) == [base] * 3
    got = truth_options_per_log(base, [Path("a.tum"), Path("b.tum")], 2)
    assert [o.path for o in got] == [Path("a.tum"), Path("b.tum")] and got[1].sigma == 0.1
    with pytest.raises(InputError, match="one --truth per log"):
        truth_options_per_log(base, [Path("a.tum")], 2)
