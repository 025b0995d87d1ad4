"""Shared fixtures: where the real data lives (ODOMKIT_DATA or ../shared/data)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


def _data_dir() -> Path | None:
    env = os.environ.get("ODOMKIT_DATA")
    for candidate in ([Path(env)] if env else []) + [REPO.parent / "shared" / "data"]:
        if candidate.is_dir():
            return candidate
    return None


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """The real-data folder; tests that need it skip with a reason when it is absent."""
    found = _data_dir()
    if found is None:
        pytest.skip("real data not found: set ODOMKIT_DATA or place shared/data beside the repo")
    return found


@pytest.fixture()
def run_cli(capsys):
    """Run ``odomkit`` in-process; return (exit code, stdout, stderr)."""
    from odomkit.cli import main

    def run(*args: str) -> tuple[int, str, str]:
        code = main([str(a) for a in args])
        captured = capsys.readouterr()
        return code, captured.out, captured.err

    return run


def _central_difference_jacobian(f, x, eps=1e-6):
    """∂f/∂x by central differences (manif-style perturbation check of a Jacobian):
    column i is (f(x + eps·e_i) − f(x − eps·e_i)) / (2·eps), error O(eps²)."""
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(x.size):
        h = np.zeros_like(x)
        h[i] = eps
        cols.append((np.asarray(f(x + h)) - np.asarray(f(x - h))) / (2 * eps))
    return np.column_stack(cols)


@pytest.fixture(scope="session")
def numeric_jacobian():
    """The central-difference Jacobian every Jacobian test compares against (session
    scope, so hypothesis tests may use it)."""
    return _central_difference_jacobian


def _car_gps_drive(offsets=(0.0, 0.0), seed=3, minutes=10.0, dt=0.05, wheel_base=2.7):
    """(log, fixes, true poses) of a car on a steering random walk at 6–10 m/s with a 1 Hz
    GPS of 1 m noise: its steering measured ``offsets[0]`` rad off the road wheel's angle in
    the first half and ``offsets[1]`` in the second."""
    from odomkit.log import OdometryLog
    from odomkit.truth import Truth

    rng = np.random.default_rng(seed)
    n = int(minutes * 60 / dt)
    t = np.arange(n) * dt
    v = 8 + 2 * np.sin(t / 29)
    steer = np.zeros(n)
    for j in range(1, n):
        steer[j] = 0.995 * steer[j - 1] + rng.normal(0, 0.004)
    steer = np.clip(steer, -0.4, 0.4)
    heading = np.concatenate([[0.0], np.cumsum(v[:-1] * np.tan(steer[:-1]) / wheel_base) * dt])
    x = np.concatenate([[0.0], np.cumsum(v[:-1] * np.cos(heading[:-1])) * dt])
    y = np.concatenate([[0.0], np.cumsum(v[:-1] * np.sin(heading[:-1])) * dt])
    offset = np.where(t < t[-1] / 2, offsets[0], offsets[1])
    log = OdometryLog(t, {"speed": v, "steer": steer - offset})
    fix_t = np.arange(0.5, t[-1], 1.0)
    xy = np.column_stack([np.interp(fix_t, t, x), np.interp(fix_t, t, y)])
    xy += rng.normal(0, 1.0, (fix_t.size, 2))
    return log, Truth(fix_t, xy, sigma=1.0), np.column_stack((x, y, heading))


@pytest.fixture(scope="session")
def car_gps_drive():
    """The simulated car and GPS the calibration-stability and report tests share
    (:func:`_car_gps_drive`)."""
    return _car_gps_drive
