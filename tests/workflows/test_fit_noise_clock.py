"""fit-noise says when the truth's fitted time σ is no clock's (a user study: a Husky's 2.5 Hz
GPS, 0.4 s between fixes, fitted truth_time_sigma 1.5–1.95 s on 30 s and 60 s windows, under
the tenth of a window that was the only limit, and nothing was said; its fixes lagged the
odometry by 1.42 s, which ``calibrate`` fits and ``fit-noise`` does not).

Independent truth: a simulated base's exact log against fixes whose only clock error is a
constant lag of 1.5 s. A time σ beyond the fixes' spacing is then the lag absorbed, and
given the lag (``--truth-time-offset``) the fit finds no such σ.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.calibrate.noise_plausible import PLAUSIBLE_CLOCK_FLOOR, implausible_truth_clock

LAG = 1.5
SPACING = 0.4
ROBOT = """[robot]
type = "unicycle"
[noise]
alpha_ss = 0.001
psd_gyro = 1e-5
[noise.parameters]
sigma_scale_left = 0.01
sigma_yaw_rate_offset = 0.001
sigma_yaw_rate_scale = 0.01
"""


def test_the_limit_is_the_larger_of_the_fix_spacing_and_half_a_second():
    assert implausible_truth_clock(0.3, 0.4) is None and implausible_truth_clock(0.45, 0.01) is None
    said = implausible_truth_clock(1.95, 0.4)
    assert said is not None and said.startswith("truth_time_sigma = 1.95 s is implausible for a clock")
    assert "(limit 0.5 s: the larger of the truth's median fix spacing, 0.4 s, and 0.5 s)" in said
    assert "correlated in time" in said and "clock offset" in said and "--truth-time-sigma" in said
    # A 1 Hz GPS: its spacing is the limit; no spacing known: the floor.
    assert implausible_truth_clock(0.9, 1.0) is None and implausible_truth_clock(1.1, 1.0) is not None
    assert implausible_truth_clock(PLAUSIBLE_CLOCK_FLOOR + 0.01, None) is not None
    assert implausible_truth_clock(math.nan, 0.4) is None


@pytest.fixture()
def lagging_gps(tmp_path, husky_drive):
    """A 400 s drive as a CSV log, and its 2.5 Hz fixes (0.3 m white noise) stamped 1.5 s late."""
    log, poses = husky_drive(0)
    rng = np.random.default_rng(0)
    t = np.arange(0.13, log.t[-1], SPACING)
    xy = np.column_stack([np.interp(t, log.t, poses[:, k]) for k in (0, 1)])
    xy = xy + rng.normal(0.0, 0.3, (t.size, 2))
    rows = np.column_stack((log.t, log.channels["speed"], log.channels["yaw_rate"]))
    np.savetxt(tmp_path / "log.csv", rows, delimiter=",", header="t,speed,yaw_rate", comments="")
    np.savetxt(tmp_path / "gps.csv", np.column_stack((t + LAG, xy)), delimiter=",", header="t,x,y",
               comments="")
    (tmp_path / "uni.toml").write_text(ROBOT)
    return tmp_path


def _fit(run_cli, d, *extra):
    code, out, err = run_cli("fit-noise", "--robot", d / "uni.toml", "--log", d / "log.csv", "--truth",
                             d / "gps.csv", "--truth-sigma", "0.3", "--window", "30s", "--window", "60s",
                             "--out", d / "fn.toml", "--force", "--json", *extra)
    assert code == 0, err
    return json.loads(out)


def test_a_time_sigma_beyond_the_fix_spacing_is_warned_about(run_cli, lagging_gps):
    result = _fit(run_cli, lagging_gps)
    value = result["parameters"]["truth_time_sigma"]
    assert value > PLAUSIBLE_CLOCK_FLOOR  # the 1.5 s lag, absorbed as noise at each fix
    [said] = [w for w in result["warnings"] if w.startswith("truth_time_sigma =")]
    assert f"truth_time_sigma = {value:.3g} s is implausible for a clock" in said
    assert f"median fix spacing, {SPACING:.3g} s" in said
    # Given the lag, the fit needs no time noise, and nothing is said; held, nothing is judged.
    honest = _fit(run_cli, lagging_gps, "--truth-time-offset", str(LAG))
    assert honest["parameters"]["truth_time_sigma"] < 0.1
    assert not any(w.startswith("truth_time_sigma =") for w in honest["warnings"])
    held = _fit(run_cli, lagging_gps, "--truth-time-sigma", "1.2")
    assert not any(w.startswith("truth_time_sigma =") for w in held["warnings"])
