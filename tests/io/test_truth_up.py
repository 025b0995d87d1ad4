"""Truth files whose frame is not z-up (a Y-up motion capture, KITTI's camera frame):
``--truth-up`` reads their ground plane, and a z-up reading of them is warned about."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from odomkit.errors import InputError
from odomkit.io.truth import read_truth


def _ground_track():
    t = np.arange(0.0, 40.0, 0.05)
    heading = 0.25 * t
    xy = 2.0 * np.column_stack((np.sin(heading), 1 - np.cos(heading))) + [0.5, -1.0]
    return t, xy, heading


def _write_y_up_tum(path):
    """A motion capture's Y-up TUM file: file x' is the ground's y, y' the height (a marker
    0.2 m up, millimetre noise), z' the ground's x; a turn by ψ about the ground's up is a
    rotation by ψ about +y' (scipy's, independent of odomkit.frames)."""
    t, xy, heading = _ground_track()
    height = 0.2 + 0.001 * np.random.default_rng(0).standard_normal(t.size)
    q = Rotation.from_rotvec(np.outer(heading, [0.0, 1.0, 0.0])).as_quat()
    rows = np.column_stack((t, xy[:, 1], height, xy[:, 0], q))
    path.write_text("".join(" ".join(f"{v:.10g}" for v in row) + "\n" for row in rows))


def test_a_y_up_tum_file_reads_its_ground_track_and_heading(tmp_path):
    path = tmp_path / "mocap.tum"
    _write_y_up_tum(path)
    t, xy, heading = _ground_track()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        truth = read_truth(path, up="+y")
    assert np.allclose(truth.xy, xy, atol=1e-9)
    assert truth.theta is not None and np.allclose(truth.theta, heading, atol=1e-9)


def test_a_y_up_file_read_as_z_up_is_warned_about(tmp_path):
    """Before, it read silently as x' against the height: a track 0.2 m above nothing."""
    path = tmp_path / "mocap.tum"
    _write_y_up_tum(path)
    with pytest.warns(UserWarning, match=r"lies across y.*--truth-up \+y"):
        read_truth(path)


def test_kitti_camera_frame_reads_with_y_down(tmp_path):
    """KITTI's camera frame: x right, y down, z forward; -y up reads the ground as (z, -x),
    and the heading follows the motion."""
    t, xy, heading = _ground_track()
    rotation = Rotation.from_rotvec(np.outer(-heading, [0.0, 1.0, 0.0])).as_matrix()
    # The car drives along the camera's z (forward) with its left along -x.
    rows = [(ti, *r[0], -left, *r[1], 1.7, *r[2], forward)
            for ti, r, (forward, left) in zip(t, rotation, xy, strict=True)]
    path = tmp_path / "poses.txt"
    path.write_text("".join(" ".join(f"{v:.10g}" for v in row) + "\n" for row in rows))
    truth = read_truth(path, "kitti", up="-y")
    assert np.allclose(truth.xy, xy, atol=1e-9)
    assert truth.theta is not None and np.allclose(truth.theta, heading, atol=1e-9)
    from odomkit.truth import heading_against_motion

    assert heading_against_motion(truth)[0] < 0.01


def test_truth_up_is_for_3d_pose_files_and_names_its_axes(tmp_path):
    path = tmp_path / "gt.csv"
    path.write_text("t,x,y\n0,0,0\n1,1,0\n")
    with pytest.raises(InputError, match="TUM or KITTI.*--truth-columns"):
        read_truth(path, up="+y")
    with pytest.raises(InputError, match=r"one of \+x, -x, \+y, -y, \+z, -z"):
        read_truth(path, up="y")


def test_evaluate_scores_a_y_up_file_as_its_z_up_twin(tmp_path, run_cli):
    """The CLI end to end: the Y-up file read with --truth-up +y gives evaluate's JSON of the
    same poses written z-up, to the last digit that matters."""
    import json

    t, xy, heading = _ground_track()
    log = tmp_path / "log.csv"
    log.write_text("t,speed,yaw_rate\n" + "".join(f"{ti:.2f},0.5,0.25\n" for ti in t))
    robot = tmp_path / "robot.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n[noise]\nalpha_ss = 0.001\npsd_gyro = 1e-5\n')
    y_up = tmp_path / "y_up.tum"
    _write_y_up_tum(y_up)
    z_up = tmp_path / "z_up.tum"
    q = Rotation.from_rotvec(np.outer(heading, [0.0, 0.0, 1.0])).as_quat()
    rows = np.column_stack((t, xy, np.zeros(t.size), q))
    z_up.write_text("".join(" ".join(f"{v:.10g}" for v in row) + "\n" for row in rows))
    runs = [run_cli("evaluate", log, "--robot", robot, "--truth", path, "--window", "10s", "--json", *extra)
            for path, extra in ((y_up, ("--truth-up", "+y")), (z_up, ()))]
    assert all(code == 0 for code, _, _ in runs), runs
    got, want = (json.loads(out) for _, out, _ in runs)
    for key in ("ate_rmse", "final_position_error", "nees_position_mean", "windows"):
        assert got[key] == pytest.approx(want[key], rel=1e-6, abs=1e-9), key
    code, _, err = run_cli("evaluate", log, "--robot", robot, "--truth", y_up, "--truth-up", "up")
    assert code == 2 and "--truth-up must be one of" in err


def test_positions_in_millimetres_read_as_metres(tmp_path):
    """A Vicon export's x_mm, y_mm read as the same truth in metres (by header name or by
    --truth-columns); one of them alone, or beside x, is refused."""
    t, xy, heading = _ground_track()
    metres, mm = tmp_path / "m.csv", tmp_path / "mm.csv"
    metres.write_text("t,x,y,theta\n" + "".join(f"{a:.2f},{b:.6f},{c:.6f},{d:.6f}\n"
                                                for a, (b, c), d in zip(t, xy, heading, strict=True)))
    mm.write_text("time,x_mm,y_mm,theta\n" + "".join(f"{a:.2f},{1000 * b:.3f},{1000 * c:.3f},{d:.6f}\n"
                                                     for a, (b, c), d in zip(t, xy, heading, strict=True)))
    want = read_truth(metres)
    for got in (read_truth(mm), read_truth(mm, columns="t=time,x_mm=x_mm,y_mm=y_mm,theta=theta")):
        assert np.allclose(got.xy, want.xy, atol=1e-9) and np.allclose(got.theta, want.theta)
    with pytest.raises(InputError, match="x_mm and y_mm together"):
        read_truth(mm, columns="t=time,x_mm=x_mm,y=y_mm")


def test_a_climbing_road_read_z_up_is_not_taken_for_a_y_up_file(tmp_path):
    """A straight 200 m road climbing 10 m along y: x is nearly constant, but the heading read
    about z follows the motion, so the file is z-up and nothing is said."""
    t = np.arange(0.0, 20.0, 0.05)
    y = 10.0 * t
    rows = np.column_stack((t, 0.01 * np.sin(t), y, 0.05 * y,
                            Rotation.from_rotvec(np.outer(np.full(t.size, np.pi / 2), [0, 0, 1])).as_quat()))
    path = tmp_path / "road.tum"
    path.write_text("".join(" ".join(f"{v:.10g}" for v in row) + "\n" for row in rows))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        truth = read_truth(path)
    assert np.allclose(truth.xy[:, 1], y)
