"""``odomkit demo``: the main job on built-in data (OptiOdom experiment 230620202042,
MIT licence): dead reckoning with covariance, calibration, and a closed-form prediction.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from odomkit.calibrate.exact import calibrate_exact
from odomkit.calibrate.realdata import e_max_syst_of_runs, umbmark_from_runs
from odomkit.data import builtin_data_path
from odomkit.evaluate import evaluate_track
from odomkit.io.files import check_outputs
from odomkit.io.jsonfile import write_json
from odomkit.io.optiodom import read_experiment
from odomkit.io.robotfile import read_robot, write_robot
from odomkit.io.ros import write_ros2_yaml
from odomkit.io.trackio import write_track_csv, write_tum
from odomkit.path import Spin, Straight
from odomkit.propagate.predict import predict
from odomkit.robot import DiffDrive
from odomkit.track import dead_reckon_log
from odomkit.workflows.predict import add_ros_pose_covariance

__all__ = ["run_demo"]


def run_demo(out_dir: str | Path, overwrite: bool = False) -> dict[str, Any]:
    """Dead-reckon the six built-in UMBmark runs (0.75 m square, 3 CW + 3 CCW) with the
    per-wheel noise model, calibrate the robot from them (UMBmark and the exact fit), and
    predict the error of one square in closed form. Writes into ``out_dir``: a track CSV
    (with covariance) and a TUM file per run, the calibrated robot file, a ROS 2
    ``diff_drive_controller`` snippet, ``summary.json`` and, with matplotlib, a figure.
    """
    out = Path(out_dir)
    check_outputs({"--out": out}, folders={"--out"})
    robot_file = builtin_data_path("optiodom_diff.toml")
    robot, noise = read_robot(robot_file)
    assert isinstance(robot, DiffDrive)  # the shipped robot file is a differential drive
    experiment = read_experiment(builtin_data_path("230620202042_metadata.csv").parent)
    runs = experiment.runs
    truths = [r.ground_truth for r in runs if r.ground_truth is not None]
    assert len(truths) == len(runs)  # OptiOdom runs carry OptiTrack poses
    stems = [Path(r.source).stem for r in runs]
    targets = [out / f"{s}_track.csv" for s in stems] + [out / f"{s}.tum" for s in stems]
    targets += [out / n for n in ("calibrated_robot.toml", "diff_drive_controller.yaml",
                                  "summary.json", "demo_tracks.png")]
    check_outputs({"--out": out, **{str(p): p for p in targets}}, overwrite=overwrite,
                  folders={"--out"})
    out.mkdir(parents=True, exist_ok=True)

    summary: dict[str, Any] = {"robot": str(robot_file), "runs": {}}
    tracks = []
    for stem, direction, run, truth in zip(stems, experiment.directions, runs, truths, strict=True):
        track = dead_reckon_log(run, robot, "exact", noise=noise[0])
        write_track_csv(out / f"{stem}_track.csv", track, overwrite=True)
        write_tum(out / f"{stem}.tum", track, overwrite=True)
        summary["runs"][stem] = {"direction": direction, "path_length": track.path_length,
                                 **evaluate_track(track.poses, truth, track.cov).to_dict()}
        tracks.append((stem, track, truth))

    side = float(experiment.metadata.side or 0.75)
    um = umbmark_from_runs(runs, robot, side)
    exact = calibrate_exact(runs, robot, "endpoints")
    calibrated = exact.robot
    assert isinstance(calibrated, DiffDrive)
    summary["calibration"] = {
        "e_max_syst_before": e_max_syst_of_runs(runs, robot),
        "umbmark": {"E_d": um.result.E_d, "E_b": um.result.E_b,
                    "e_max_syst_after": um.e_max_syst_after},
        "exact": {"E_d": exact.E_d, "E_b": exact.E_b, "std_errors": exact.std_errors,
                  "e_max_syst_after": e_max_syst_of_runs(runs, calibrated)},
    }
    # The same runs with the calibrated robot: with the systematic error gone, is the
    # per-wheel noise model's 95 % ellipse honest?
    for stem, run, truth in zip(stems, runs, truths, strict=True):
        track = dead_reckon_log(run, calibrated, "exact", noise=noise[0])
        ev = evaluate_track(track.poses, truth, track.cov)
        summary["runs"][stem]["calibrated"] = ev.to_dict()
    write_robot(out / "calibrated_robot.toml", calibrated, noise, overwrite=True)
    write_ros2_yaml(out / "diff_drive_controller.yaml", calibrated,
                    wheel_radius=experiment.metadata.wheel_diameters[0] / 2, overwrite=True)

    # One clockwise square as planned: four legs and four right turns on the spot.
    square = [seg for _ in range(4) for seg in (Straight(side), Spin(-np.pi / 2))]
    prediction = predict(square, noise[0], wheel_base=robot.effective_wheel_base)
    summary["prediction_one_square"] = add_ros_pose_covariance(prediction.to_dict())

    from odomkit.plot import have_matplotlib, plot_tracks

    # matplotlib is the optional "plot" extra
    summary["figure"] = str(plot_tracks(tracks, out / "demo_tracks.png")) if have_matplotlib() else None
    summary_path = out / "summary.json"
    write_json(summary_path, summary, overwrite=True)
    summary["summary"] = str(summary_path)
    summary["outputs"] = [str(p) for p in targets if p.exists()]
    return summary
