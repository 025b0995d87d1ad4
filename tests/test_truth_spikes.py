"""Spikes in a truth's positions (odomkit.truth_spikes) and their screening where truth is read.

Independent truth: the spikes are planted, so which fixes they are is known; honest noise
of known σ (Gaussian, 2-D) must give none over 100 000 fixes (each passes 6 σ on its
neighbours' line with probability about e⁻¹⁸); a sharp manoeuvre of a real vehicle,
noise-free, must give none either; and the windowed honesty test on a simulated log of
known noise, whose position-only truth gets spikes at window ends and starts, must score
as with the clean truth (before the screening, its NEES mean was hundreds of times its
bound).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from odomkit.log import OdometryLog
from odomkit.truth import Truth
from odomkit.truth_spikes import MAX_ACCELERATION, SPIKE_SIGMAS, spike_fixes
from odomkit.workflows.evaluate import evaluate_logs
from odomkit.workflows.logs import LogOptions
from odomkit.workflows.results import truths_given
from odomkit.workflows.truth import TruthOptions

SIM_COLUMNS = "t=t,dist_left=L,dist_right=R"


def _curving_drive(seconds: float, dt: float, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Times and positions of a car at 3 m/s whose heading swings (up to 0.3 rad/s) and whose
    speed changes by ±1 m/s: accelerations up to about 1 m/s² along and across."""
    t = np.arange(0.0, seconds, dt)
    heading = 2.0 * np.sin(0.15 * t)
    speed = 3.0 + np.sin(0.5 * t + seed)
    xy = np.column_stack((np.cumsum(speed * np.cos(heading)) * dt, np.cumsum(speed * np.sin(heading)) * dt))
    return t, xy


def test_planted_spikes_of_one_and_two_fixes_are_found_and_their_neighbours_kept():
    rng = np.random.default_rng(0)
    t, xy = _curving_drive(120.0, 0.2)
    xy = xy + 0.1 * rng.standard_normal(xy.shape)
    planted = [40, 141, 142, 300, 301, 455]  # single spikes, and two pairs of neighbouring fixes
    jumps = {40: (8.0, 0.0), 141: (0.0, -5.0), 142: (0.5, -5.2), 300: (-3.0, 3.0), 301: (-3.1, 2.8),
             455: (1.5, 1.0)}
    for i, jump in jumps.items():
        xy[i] += jump
    found = spike_fixes(t, xy)
    assert found.index.tolist() == planted
    assert found.t.tolist() == t[planted].tolist()
    # The robust scatter reads the honest noise (σ = 0.1 m per axis): its median-based
    # estimate from 600 fixes has a relative standard error near 5 %.
    assert found.scatter == pytest.approx(0.1, rel=0.2)
    # A lone spike lies off its neighbours' line by its whole jump.
    assert found.off[0] == pytest.approx(8.0, abs=0.6)


def test_honest_noise_of_any_size_gives_no_spike_in_100000_fixes():
    rng = np.random.default_rng(1)
    for sigma, dt in ((0.002, 0.01), (1.5, 0.1), (3.0, 1.0)):
        t, xy = _curving_drive(100_000 * dt, dt)
        found = spike_fixes(t, xy + sigma * rng.standard_normal(xy.shape))
        assert len(found) == 0, (sigma, dt, found.off[:5])
        # The scatter about the neighbours' lines is the fixes' own σ (the path's curvature
        # adds a·Δt²/4 at most, far below σ here).
        assert found.scatter == pytest.approx(sigma, rel=0.05)


def test_a_sharp_real_manoeuvre_is_no_spike():
    """A noise-free motion capture (100 Hz, positions to 1e-6 m) of a robot that brakes from
    2 m/s to rest in 0.15 s (13 m/s², under the 2 g bound) and then drives off turning sharply: the
    scatter about the neighbours' lines is rounding, so only the acceleration bound keeps
    the stop from being a spike."""
    dt = 0.01
    t = np.arange(0.0, 6.0, dt)
    speed = np.clip(2.0 - 13.3 * np.clip(t - 2.0, 0.0, None), 0.0, None)
    speed[t > 3.0] = np.clip(10.0 * (t[t > 3.0] - 3.0), 0.0, 1.0)  # off again at 10 m/s²
    heading = np.where(t > 3.0, 3.0 * (t - 3.0), 0.0)
    xy = np.column_stack((np.cumsum(speed * np.cos(heading)) * dt, np.cumsum(speed * np.sin(heading)) * dt))
    xy = np.round(xy, 6)
    assert np.max(np.abs(np.diff(speed))) / dt < MAX_ACCELERATION
    assert len(spike_fixes(t, xy)) == 0
    # The same path with one fix 5 cm off is a spike: 5 cm is far beyond rounding and beyond
    # what 2 g can do in 10 ms (1 mm).
    xy[250] += (0.0, 0.05)
    assert spike_fixes(t, xy).index.tolist() == [250]


def test_a_spike_beside_a_gap_is_found_from_its_other_side():
    """A GPS under trees: fixes at 5 Hz, a jump of 8 m, then 7 s without fixes. The line
    between its neighbours spans the gap and says nothing; the line through the two fixes
    before it finds it, and the honest fixes before it, each with a line clear of it, stay."""
    t, xy = _curving_drive(60.0, 0.2)
    keep = (t < 20.0) | (t > 27.2)
    t, xy = t[keep], xy[keep].copy()
    last = int(np.flatnonzero(t < 20.0)[-1])
    xy[last] += (4.0, -7.0)
    assert spike_fixes(t, xy).index.tolist() == [last]


def test_a_long_jump_is_left_as_it_is():
    """Three fixes or more off the path look like a shift of the path itself, which only a
    comparison with the odometry could tell from a jump: no fix of it is taken."""
    t, xy = _curving_drive(60.0, 0.2)
    xy[100:104] += (0.0, 6.0)
    assert len(spike_fixes(t, xy)) == 0


def _spiky(path, rows: list[int], jump: float = 6.0):
    """The fixes of ``path`` (t,x,y) with ``jump`` metres added across the track at ``rows``."""
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    data[rows, 2] += jump
    out = path.with_name("xy_spiky.csv")
    np.savetxt(out, data, delimiter=",", header="t,x,y", comments="")
    return out


def test_the_honesty_test_scores_a_spiky_truth_as_the_clean_one(noisy_diff_log, tmp_path):
    """Position-only truth (σ 0.02 m) of a log whose wheel noise the robot file states
    exactly, scored in 10 s windows: with spikes at 12 window ends and 6 starts the figures
    are those of the clean truth (a window end or start between kept fixes is interpolated
    from them, 0.1 s apart, on a path that curves gently), where before the screening the
    NEES mean was over 100 times its bound."""
    log, _, robot = noisy_diff_log(tmp_path, 0.01, 0.01, 300.0, seed=5, truth_noise=0.02)
    xy = tmp_path / "xy.csv"
    ends = [100 * k for k in range(2, 26, 2)]  # rows at 20 s, 40 s, ...: 12 window ends
    starts = [100 * k + 1 for k in range(3, 27, 4)]  # beside 6 window starts
    spiky = _spiky(xy, ends + starts)
    kwargs = {"log_options": LogOptions(columns=SIM_COLUMNS), "window": "10s"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        clean = evaluate_logs([log], robot, [TruthOptions(xy, sigma=0.02)], **kwargs)
    said = r"18 of 3001 truth fixes left out as spikes, each 5\.\d+\.\.6\.\d+ m off"
    with pytest.warns(UserWarning, match=said):
        screened = evaluate_logs([log], robot, [TruthOptions(spiky, sigma=0.02)], **kwargs)
    assert screened["windows"] == clean["windows"] == 30
    # Inside the bounds of an honest NEES mean, as the clean truth's: a little smaller, as a
    # window end between kept fixes is their interpolation, whose noise is σ/√2 where it was σ.
    lo, hi = clean["nees_bounds"]
    assert lo < clean["nees_position_mean"] < hi
    assert lo < screened["nees_position_mean"] < hi
    assert screened["nees_position_mean"] == pytest.approx(clean["nees_position_mean"], rel=0.15)
    for level, inside in clean["coverage"].items():
        assert abs(screened["coverage"][level] - inside) <= 2 / 30  # two window ends of 30 at most


def test_a_truth_in_memory_is_screened_as_a_file_is():
    t, xy = _curving_drive(30.0, 0.2)
    xy[50] += (0.0, 9.0)
    from odomkit.log import OdometryLog

    log = OdometryLog(t, {"speed": np.full(t.size, 3.0), "yaw_rate": np.zeros(t.size)}, source="log")
    said = r"truth: 1 of 150 truth fixes left out as spikes, each 9 m off .* at 10 s:"
    with pytest.warns(UserWarning, match=said):
        (kept,) = truths_given(Truth(t, xy, source="truth"), [log])
    assert len(kept) == 149 and 10.0 not in kept.t
    assert math.isclose(SPIKE_SIGMAS, 6.0)


def test_the_spikes_are_said_at_their_times_in_the_truth_file(noisy_diff_log, tmp_path):
    """A truth on a clock 2 s late (--truth-time-offset 2): the spike stamped 50 s in the file
    is said at 50 s, where the user finds it, not at the log's 48 s."""
    log, _, robot = noisy_diff_log(tmp_path, 0.01, 0.01, 100.0, seed=2, truth_noise=0.02)
    spiky = _spiky(tmp_path / "xy.csv", [500])
    with pytest.warns(UserWarning, match=r"1 of 1001 truth fixes left out as spikes, .* at 50 s:"):
        evaluate_logs([log], robot, [TruthOptions(spiky, sigma=0.02, time_offset=2.0)],
                      log_options=LogOptions(columns=SIM_COLUMNS), window="10s")


def _bursty_circle(arrival_period=0.1, rate=87.0, seconds=60.0):
    """A robot on a circle (radius 2 m, 0.3 m/s) measured at ``rate`` Hz but stamped when the
    fixes arrived: each ``arrival_period`` a burst, 0.2 ms apart (a bag's receive times)."""
    measured = np.arange(0.0, seconds, 1.0 / rate)
    burst = np.ceil(measured / arrival_period) * arrival_period
    order = np.arange(measured.size) - np.searchsorted(burst, burst)  # place within its burst
    stamps = burst + 2e-4 * order
    th = 0.15 * measured
    xy = 2.0 * np.column_stack((np.sin(th), 1 - np.cos(th)))
    return stamps, xy, th


def test_fixes_stamped_in_bursts_are_said_and_not_taken_for_spikes():
    """A motion capture at 87 Hz stamped on arrival, in bursts every 0.1 s (user study: a
    Pioneer's OptiTrack read with --bag-time): its times are off by up to the burst's period,
    which moved a fitted start heading 11σ without a word, and the spike screening dropped
    5.8 % of its fixes for lying off lines in time. Now one warning names the bursts and no
    fix is dropped; a steady truth and a 5 Hz GPS with gaps are not bursts."""
    from odomkit.truth import stamp_bursts

    stamps, xy, th = _bursty_circle()
    median, period = stamp_bursts(stamps) or (math.nan, math.nan)
    assert median == pytest.approx(2e-4, rel=0.01) and period == pytest.approx(0.1, rel=0.05)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        log = OdometryLog(stamps, {"speed": 0 * stamps})
        (kept,) = truths_given(Truth(stamps, xy, th, source="bursts"), [log])
    said = [str(w.message) for w in caught]
    assert len(kept) == stamps.size and not [m for m in said if "left out as spikes" in m]
    assert [m for m in said if "come in bursts" in m and "header stamps" in m]
    steady = np.arange(0.0, 60.0, 0.01)
    gps = np.concatenate([np.arange(0.0, 100.0, 0.2), np.arange(130.0, 200.0, 0.2),
                          np.arange(260.0, 300.0, 0.2)])
    for t in (steady, gps):
        assert stamp_bursts(t) is None
