"""Times in messages: a ROS bag's epoch clock printed with six significant digits read
"1.43224e+09 s" for every time of its day (a user study on a real Husky bag); they are now
printed to the millisecond, and a clock that starts near zero keeps its six digits."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.log import clock_text
from odomkit.truth import Truth, no_overlap
from odomkit.windows import late_start_note

EPOCH = 1_432_235_497.988949


@pytest.mark.parametrize(("t", "text"), [(EPOCH, "1432235497.989"), (-EPOCH, "-1432235497.989"),
                                         (12.3456789, "12.3457"), (0.0, "0"), (999_999.0, "999999")])
def test_clock_text(t, text):
    assert clock_text(t) == text
    # Each is the time to within half its last digit.
    assert abs(float(text) - t) <= (5e-4 if abs(t) >= 1e6 else 5e-6 * max(abs(t), 1.0))


def test_messages_tell_epoch_times_apart():
    t = EPOCH + 0.1 * np.arange(10)
    note = late_start_note("run.bag", "the track", t, 3, 3)
    assert "starts at 1432235498.289 s" in note and "e+09" not in note
    truth = Truth(EPOCH + 100 + np.arange(5.0), np.zeros((5, 2)))
    said = no_overlap(truth, t)
    assert ("the truth (1432235597.989..1432235601.989 s) and the log (1432235497.989..1432235498.889 s)"
            in said)
