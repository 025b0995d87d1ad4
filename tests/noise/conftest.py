"""Shared logs for the noise tests (tests cannot import each other under importlib mode)."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.kinematics import BodySteps, diff_body_steps
from odomkit.robot import DiffDrive


def _straight_diff(m, dist=10.0, base=0.4):
    """A differential drive going straight ``dist`` [m] in ``m`` equal steps of 0.1 s."""
    d = np.full(m, dist / m)
    dd, dth = diff_body_steps(d, d, base)
    return BodySteps(dd, dth, np.full(m, 0.1), {"d_left": d, "d_right": d}, DiffDrive(base))


@pytest.fixture(scope="session")
def straight_diff():
    """``straight_diff(m, dist=10.0, base=0.4)`` -> the BodySteps of a straight line."""
    return _straight_diff
