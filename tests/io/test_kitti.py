"""KITTI pose export (issue 12 item 8): ``odomkit track --kitti FILE``, checked by evo's own
reader against odomkit's TUM file, by hand on a quarter turn, and read back as truth."""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.io.trackio import kitti_times_path, write_kitti
from odomkit.io.truth import read_truth
from odomkit.track import Track

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")


def test_a_quarter_turn_by_hand(tmp_path):
    track = Track(np.array([0.0, 1.5]), np.array([[0.0, 0.0, 0.0], [1.0, 2.0, math.pi / 2]]), None, None)  # type: ignore[arg-type]
    poses, times = write_kitti(tmp_path / "q.kitti", track)
    assert times == tmp_path / "q.times.txt"
    rows = np.loadtxt(poses)
    assert rows.shape == (2, 12)
    np.testing.assert_array_equal(rows[0], [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0])
    # R = Rz(π/2) = [[0, −1, 0], [1, 0, 0], [0, 0, 1]], p = (1, 2, 0)
    np.testing.assert_allclose(rows[1], [0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 0], atol=1e-16)
    assert np.loadtxt(times).tolist() == [0.0, 1.5]


def test_track_kitti_agrees_with_evo_reading_the_tum_file(run_cli, tmp_path):
    file_interface = pytest.importorskip("evo.tools.file_interface")
    kitti, tum = tmp_path / "run.kitti", tmp_path / "run.tum"
    code, out, err = run_cli("track", RUN, "--robot", ROBOT, "--kitti", kitti, "--tum", tum, "--json")
    assert code == 0, err
    outputs = json.loads(out)["outputs"]
    assert outputs["kitti"] == str(kitti) and outputs["kitti_times"] == str(tmp_path / "run.times.txt")
    from_kitti = file_interface.read_kitti_poses_file(str(kitti))
    from_tum = file_interface.read_tum_trajectory_file(str(tum))
    assert from_kitti.num_poses == from_tum.num_poses == 1814
    # TUM is written to 9 decimals: the same poses to that
    np.testing.assert_allclose(np.array(from_kitti.poses_se3), np.array(from_tum.poses_se3), atol=2e-9)
    np.testing.assert_allclose(np.loadtxt(kitti_times_path(kitti)), from_tum.timestamps, atol=1e-9)


def test_kitti_with_its_times_reads_back_as_kitti_truth(tmp_path):
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(0.01, 0.1, 50))
    poses = np.column_stack((rng.normal(size=50), rng.normal(size=50), np.cumsum(rng.normal(0, 0.5, 50))))
    kitti, times = write_kitti(tmp_path / "p.txt", Track(t, poses, None, None))  # type: ignore[arg-type]
    pasted = tmp_path / "pasted.txt"
    pasted.write_text(subprocess.run(["paste", "-d", " ", str(times), str(kitti)], capture_output=True,
                                     text=True, check=True).stdout)
    truth = read_truth(pasted, "kitti")
    assert np.array_equal(truth.t, t)  # 17 digits: the same doubles
    np.testing.assert_allclose(truth.xy, poses[:, :2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(truth.theta, poses[:, 2], rtol=0, atol=1e-12)


@pytest.mark.parametrize("existing", ["run.kitti", "run.times.txt"])
def test_kitti_files_are_never_replaced_without_force(run_cli, tmp_path, existing):
    (tmp_path / existing).write_text("keep me\n")
    csv = tmp_path / "track.csv"
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--kitti", tmp_path / "run.kitti", "--out", csv)
    assert code == 2 and "exists already; pass --force" in err and str(tmp_path / existing) in err
    assert (tmp_path / existing).read_text() == "keep me\n"
    assert not csv.exists()  # every output is checked before any is written
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--kitti", tmp_path / "run.kitti", "--force")
    assert code == 0, err
    assert np.loadtxt(tmp_path / "run.kitti").shape == (1814, 12)


def test_kitti_may_not_land_on_another_output(run_cli, tmp_path):
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--kitti", tmp_path / "a.kitti",
                           "--tum", tmp_path / "a.times.txt")
    assert code == 2 and "name the same file" in err
