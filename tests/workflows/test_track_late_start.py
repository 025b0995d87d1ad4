"""``odomkit track`` where the truth begins a fraction of a log period after the log's first
row (a real car's user study, finding 14).

The car's log and its GPS were one file; ``calibrate`` fitted the truth's clock offset
(−0.007 s, inside its standard error) and wrote it to the robot file's ``[truth]``
``time_offset``. A fix stamped s is the pose at log time s − offset, so every fix moves
0.007 s later and the log's first row, 7 ms before the first fix, has no truth: it is left
out of the track and its outputs. That is true and still counted, but the warning must say
why, or it reads as a bug ("1 row precedes the truth" of the same file). Here a log and a
truth file share their stamps (10 Hz), as that file's columns did.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.workflows.track import run_track
from odomkit.workflows.truth import TruthOptions

PERIOD = 0.1
COLUMNS = "t=t,speed=speed,yaw_rate=yaw_rate"


@pytest.fixture()
def files(tmp_path):
    t = np.round(np.arange(300) * PERIOD, 6)
    speed = 1.0 + 0.2 * np.sin(t / 5)
    yaw_rate = 0.1 * np.cos(t / 7)
    theta = np.concatenate([[0.0], np.cumsum(yaw_rate[:-1] * PERIOD)])
    x = np.concatenate([[0.0], np.cumsum(speed[:-1] * np.cos(theta[:-1]) * PERIOD)])
    y = np.concatenate([[0.0], np.cumsum(speed[:-1] * np.sin(theta[:-1]) * PERIOD)])
    log, truth = tmp_path / "log.csv", tmp_path / "truth.csv"
    np.savetxt(log, np.column_stack((t, speed, yaw_rate)), delimiter=",", header="t,speed,yaw_rate",
               comments="", fmt="%.9g")
    np.savetxt(truth, np.column_stack((t, x, y, theta)), delimiter=",", header="t,x,y,theta", comments="",
               fmt="%.12g")

    def robot(offset: float | None) -> str:
        path = tmp_path / f"robot{offset}.toml"
        path.write_text('[robot]\ntype = "unicycle"\n' + ("" if offset is None else
                                                             f"\n[truth]\ntime_offset = {offset!r}\n"))
        return str(path)

    return log, truth, robot


def _track(log, truth, robot_path, offset=None):
    from odomkit.workflows.logs import LogOptions

    with pytest.warns(UserWarning) as caught:
        run = run_track(log, robot_path, log_options=LogOptions(columns=COLUMNS),
                        truth=TruthOptions(path=truth, time_offset=offset), with_covariance=False)
    return run, [str(w.message) for w in caught if "the track starts at" in str(w.message)]


def test_a_clock_offset_smaller_than_a_period_is_named_as_why_the_first_row_is_left_out(files):
    log, truth, robot = files
    run, said = _track(log, truth, robot(-0.007))
    assert run.track.poses.shape[0] == 299  # the first row is left out, and the warning counts it
    assert len(said) == 1 and "the 1 row(s) before it" in said[0]
    assert "[truth] time_offset" in said[0] and "-0.007 s" in said[0]
    assert "0.007 s after the log's first row" in said[0] and "one log period (0.1 s)" in said[0]


def test_the_flag_is_named_when_it_gave_the_offset(files):
    log, truth, robot = files
    _, said = _track(log, truth, robot(None), offset=-0.007)
    assert len(said) == 1 and "--truth-time-offset" in said[0] and "-0.007 s" in said[0]


def test_no_offset_no_warning(files):
    import warnings

    log, truth, robot = files
    from odomkit.workflows.logs import LogOptions

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run = run_track(log, robot(0.0), log_options=LogOptions(columns=COLUMNS),
                        truth=TruthOptions(path=truth), with_covariance=False)
    assert run.track.poses.shape[0] == 300


def test_a_truth_that_starts_periods_late_gets_no_clock_explanation(files):
    """Rows left out because the truth starts 0.35 s late (3.5 periods): nothing to explain."""
    log, truth, robot = files
    _, said = _track(log, truth, robot(-0.35))
    assert len(said) == 1 and "the 4 row(s) before it" in said[0]
    assert "time_offset" not in said[0] and "log period" not in said[0]
