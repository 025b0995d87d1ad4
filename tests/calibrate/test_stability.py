"""Does a calibration from GPS positions hold along the drive? (odomkit.calibrate.stability)

A simulated car (L = 2.7 m, 10 min at 6–10 m/s) against a 1 Hz GPS with 1 m noise. In one
drive its steering offset is the same throughout; in the other it changes at the middle
(0.002 rad, then 0.008 rad: as a real car's did between two halves of a drive, where the
offset fitted on one half made the other half's error 4–5× the nominal robot's). The first
must pass quietly, the second must be named, with each half's own offset recovered.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from odomkit.calibrate.stability import calibrate_halves, halves_disagree, track_fitted_to_fixes
from odomkit.robot import Car

L = 2.7


@pytest.fixture()
def drive(car_gps_drive):
    """(log, fixes, true poses): steering measured ``offsets[0]`` rad off (``offsets[1]``
    in the second half) from the road wheel's angle (tests/conftest.py)."""
    return car_gps_drive


def test_a_track_fitted_to_its_own_exact_fixes_recovers_the_start_pose(drive):
    """Noise-free fixes of the odometry's own track from the origin, turned and shifted by a
    known start pose: the SE(2) fit finds that pose, and the errors vanish."""
    from odomkit.track import dead_reckon_log

    log, _, _ = drive((0.0, 0.0))
    true = dead_reckon_log(log, Car(L), "exact", np.zeros(3)).poses
    start = np.array([10.0, -4.0, 0.8])
    c, s = np.cos(start[2]), np.sin(start[2])
    moved = true[:, :2] @ np.array([[c, s], [-s, c]]) + start[:2]
    fix_t = log.t[::20]
    fixes = np.column_stack([np.interp(fix_t, log.t, moved[:, k]) for k in (0, 1)])
    poses, error = track_fitted_to_fixes(log, Car(L), fix_t, fixes)
    np.testing.assert_allclose(poses[0], start, atol=1e-6)
    assert np.max(np.abs(error)) < 1e-6


def test_a_steady_car_holds_along_its_drive(drive):
    log, fixes, _ = drive((0.005, 0.005))
    halves = calibrate_halves(log, fixes, Car(L))
    assert halves is not None
    for half in halves:
        k = half.calibration.names.index("steering_offset")
        assert half.calibration.values[k] == pytest.approx(0.005, abs=0.001)
    assert halves_disagree(halves) is None


def test_an_offset_that_changes_mid_drive_is_named_with_each_halfs_value(drive):
    log, fixes, _ = drive((0.002, 0.008))
    halves = calibrate_halves(log, fixes, Car(L))
    assert halves is not None
    k = halves[0].calibration.names.index("steering_offset")
    assert halves[0].calibration.values[k] == pytest.approx(0.002, abs=0.001)
    assert halves[1].calibration.values[k] == pytest.approx(0.008, abs=0.001)
    assert all(h.rms_other > 2 * h2.rms_own for h, h2 in ((halves[0], halves[1]), (halves[1], halves[0])))
    said = halves_disagree(halves)
    assert said is not None and "does not hold along this drive" in said and "steering_offset" in said


def test_calibrate_says_so_and_reports_the_halves(run_cli, tmp_path, drive):
    log, fixes, _ = drive((0.002, 0.008))
    np.savetxt(tmp_path / "car.csv", np.column_stack((log.t, log.channels["speed"], log.channels["steer"])),
               delimiter=",", header="t,speed,steer", comments="")
    np.savetxt(tmp_path / "gps.csv", np.column_stack((fixes.t, fixes.xy)), delimiter=",", header="t,x,y",
               comments="")
    (tmp_path / "car.toml").write_text(f'[robot]\ntype = "car"\nwheel_base = {L}\n')
    code, out, err = run_cli("calibrate", tmp_path / "car.csv", "--robot", tmp_path / "car.toml", "--truth",
                             tmp_path / "gps.csv", "--truth-sigma", "1", "--json")
    assert code == 0, err
    halves = json.loads(out)["halves"]
    assert [h["half"] for h in halves] == ["first half", "second half"]
    assert halves[1]["parameters"]["steering_offset"] == pytest.approx(0.008, abs=0.001)
    assert "does not hold along this drive" in err and "try --fit-steering-cubic" in err
