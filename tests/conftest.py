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


def _noisy_diff_log(tmp_path, k_true, k_model, seconds, seed=11, truth_noise=0.0):
    """A diff-drive log whose wheel noise is known (variance k_true²|d| per wheel and step,
    0.1 s rows, wheel base 0.4 m) with its exact truth: ``log.csv`` (t,L,R), ``gt.csv``
    (t,x,y,theta), ``xy.csv`` (positions with ``truth_noise`` [m] per axis) and
    ``robot.toml`` (k_left = k_right = ``k_model``); returns (log, gt, robot) paths."""
    from odomkit.integrate import dead_reckon

    rng = np.random.default_rng(seed)
    dt, B = 0.1, 0.4
    t = np.arange(0.0, seconds + dt / 2, dt)
    w = 0.4 * np.sin(0.05 * t)
    dl, dr = (0.3 - w * B / 2) * dt, (0.3 + w * B / 2) * dt
    dl[0] = dr[0] = 0.0
    truth = dead_reckon((dl[1:] + dr[1:]) / 2, (dr[1:] - dl[1:]) / B, (0.0, 0.0, 0.0), "exact")
    ml = dl + rng.standard_normal(t.size) * k_true * np.sqrt(np.abs(dl))
    mr = dr + rng.standard_normal(t.size) * k_true * np.sqrt(np.abs(dr))
    np.savetxt(tmp_path / "log.csv", np.column_stack((t, ml, mr)), delimiter=",", header="t,L,R",
               comments="")
    np.savetxt(tmp_path / "gt.csv", np.column_stack((t, truth)), delimiter=",", header="t,x,y,theta",
               comments="")
    xy = truth[:, :2] + truth_noise * rng.standard_normal((t.size, 2))
    np.savetxt(tmp_path / "xy.csv", np.column_stack((t, xy)), delimiter=",", header="t,x,y", comments="")
    (tmp_path / "robot.toml").write_text(
        f'[robot]\ntype = "diff"\nwheel_base = {B}\nm_per_tick = 0.0001\n'
        f"[noise]\nk_left = {k_model}\nk_right = {k_model}\n")
    return tmp_path / "log.csv", tmp_path / "gt.csv", tmp_path / "robot.toml"


@pytest.fixture(scope="session")
def noisy_diff_log():
    """The simulated diff-drive log of known wheel noise the evaluate tests share
    (:func:`_noisy_diff_log`)."""
    return _noisy_diff_log


def _husky_drive(seed, duration=400.0, dt=0.1):
    """A base at about 0.9 m/s that turns gently (knots of the yaw rate every 10 s, each a turn
    of up to 0.25 rad/s with probability 0.3), as a real Husky bag's did: its unicycle log
    (speed, yaw_rate) and true poses (N, 3)."""
    from odomkit.log import OdometryLog
    from odomkit.robot import Unicycle
    from odomkit.track import dead_reckon_log

    rng = np.random.default_rng(seed)
    t = dt * np.arange(int(duration / dt))
    knots = rng.uniform(-0.25, 0.25, t.size // 100 + 2) * (rng.random(t.size // 100 + 2) < 0.3)
    log = OdometryLog(t, {"speed": 0.9 + 0.2 * np.sin(t / 23.0),
                          "yaw_rate": np.interp(t, np.arange(knots.size) * 10.0, knots)})
    return log, dead_reckon_log(log, Unicycle(), pose0=(5.0, -3.0, 0.4)).poses


@pytest.fixture(scope="session")
def husky_drive():
    """``husky_drive(seed, duration=400, dt=0.1)``: a Husky-like unicycle drive and its true
    poses (:func:`_husky_drive`)."""
    return _husky_drive
