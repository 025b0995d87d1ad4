"""Progress reports of the long workflows (:mod:`odomkit.progress`, issue 13 item 3).

Each workflow is run with a :class:`~odomkit.progress.RecordingProgress`: every stage it
opens is closed, and the units it advances add up to the total it announced (counted
independently here: runs asked for, rows of the log, logs given). Each is also run with
:data:`~odomkit.progress.NO_PROGRESS`: the numbers are bit for bit the same, because
progress only observes.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.io.jsonfile import to_jsonable
from odomkit.noise import WheelNoise
from odomkit.path import Arc
from odomkit.progress import NO_PROGRESS, NoProgress, Progress, RecordingProgress, stage
from odomkit.workflows.truth import TruthOptions

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]
TIMES = ("seconds",)  # wall-clock figures: the only keys allowed to differ between two runs


def _same_json(a: dict, b: dict) -> None:
    """Identical JSON (every float to the bit) but for the wall-clock keys."""
    a = {k: v for k, v in to_jsonable(a).items() if k not in TIMES}
    b = {k: v for k, v in to_jsonable(b).items() if k not in TIMES}
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def _complete(seen: RecordingProgress) -> None:
    """Every stage closed; a counted stage advanced by exactly its total."""
    for s in seen.stages:
        assert s.closed, s
        if s.total is not None:
            assert s.done == s.total, s


# --- the protocol ---------------------------------------------------------------------------

def test_the_null_and_the_recording_progress_follow_the_protocol():
    assert isinstance(NO_PROGRESS, Progress) and isinstance(NoProgress(), Progress)
    assert isinstance(RecordingProgress(), Progress)
    assert not isinstance(object(), Progress)


def test_a_recording_progress_refuses_calls_outside_a_stage():
    seen = RecordingProgress()
    with pytest.raises(RuntimeError, match="start"):
        seen.advance(1)
    with stage(seen, 2, "a"):
        seen.advance(2)
    with pytest.raises(RuntimeError, match="start"):
        seen.close()


def test_a_stage_is_closed_when_its_block_fails():
    seen = RecordingProgress()
    with pytest.raises(ValueError), stage(seen, 5, "work"):
        raise ValueError
    assert seen.stages[0].closed and seen.stages[0].done == 0


# --- simulate -------------------------------------------------------------------------------

@pytest.mark.parametrize("workers,chunk_runs", [(1, None), (2, 512)])
def test_simulate_reports_every_run_once_and_the_same_numbers(workers, chunk_runs):
    from odomkit.workflows.simulate import run_simulate

    args = ([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4)
    kwargs = {"runs": 3000, "partitions": 20, "seed": 7, "workers": workers, "chunk_runs": chunk_runs}
    seen = RecordingProgress()
    with_bar = run_simulate(*args, **kwargs, progress=seen)
    (runs,) = seen.stages
    assert (runs.description, runs.total, runs.done, runs.closed) == ("Monte Carlo runs", 3000, 3000, True)
    # One advance per task: blocks of 256 runs, grouped in tasks of chunk_runs.
    assert runs.advances == math.ceil(3000 / (chunk_runs or 256))
    _same_json(with_bar, run_simulate(*args, **kwargs))


# --- track ----------------------------------------------------------------------------------

def test_track_reports_reading_dead_reckoning_covariance_and_writing(tmp_path):
    from odomkit.workflows.track import run_track

    seen = RecordingProgress()
    run = run_track(RUNS[0], ROBOT, out=tmp_path / "t.csv", tum=tmp_path / "t.tum", progress=seen)
    _complete(seen)
    names = [s.description for s in seen.stages]
    assert names == [f"reading {RUNS[0].name}", "dead reckoning", "covariance", "writing"]
    rows = len(np.loadtxt(RUNS[0], delimiter=",", ndmin=2))  # the log's rows, counted apart
    assert seen.stages[2].total == rows - 1 == len(run.track.poses) - 1  # one unit per step
    assert seen.stages[3].total == 2  # two outputs
    plain = run_track(RUNS[0], ROBOT, out=tmp_path / "u.csv", tum=tmp_path / "u.tum")
    assert np.array_equal(plain.track.poses, run.track.poses)
    assert np.array_equal(plain.track.cov, run.track.cov)
    assert (tmp_path / "t.csv").read_bytes() == (tmp_path / "u.csv").read_bytes()


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_the_covariance_is_reported_chunk_by_chunk_and_is_the_same(engine):
    from odomkit.integrate import dead_reckon
    from odomkit.io.optiodom import read_run
    from odomkit.io.robotfile import read_robot
    from odomkit.kinematics import body_steps
    from odomkit.propagate.recursion import track_covariance

    robot, noise = read_robot(ROBOT)
    steps = body_steps(robot, read_run(RUNS[1], "diff"))
    poses = dead_reckon(steps.dd, steps.dtheta)
    m = steps.dd.size
    seen = RecordingProgress()
    cov = track_covariance(steps, poses, noise[0], np.zeros((3, 3)), engine=engine, chunk_size=97,
                           progress=seen)
    (chunks,) = seen.stages
    assert (chunks.total, chunks.done, chunks.advances) == (m, m, math.ceil(m / 97))
    plain = track_covariance(steps, poses, noise[0], np.zeros((3, 3)), engine=engine, chunk_size=97)
    assert np.array_equal(cov, plain)


def test_a_covariance_flag_without_a_covariance_opens_no_stage():
    """A refusal comes before any work (and so before any stage)."""
    from odomkit.errors import InputError
    from odomkit.workflows.track import run_track

    seen = RecordingProgress()
    with pytest.raises(InputError, match="--engine"):
        run_track(RUNS[0], ROBOT, with_covariance=False, engine="transition", progress=seen)
    assert seen.stages == []


# --- fit-noise, evaluate, calibrate-noise: a unit per log ---------------------------------------

def test_fit_noise_reports_each_log_then_the_fit(tmp_path):
    from odomkit.workflows.fit_noise import fit_noise_files

    logs = RUNS[:3]
    seen = RecordingProgress()
    result = fit_noise_files(ROBOT, logs, [TruthOptions()] * 3, tmp_path / "a.toml", window="10s",
                             workers=1, progress=seen)
    _complete(seen)
    assert [(s.description, s.total, s.done) for s in seen.stages] == [("logs", 3, 3), ("fitting", None, 0)]
    plain = fit_noise_files(ROBOT, logs, [TruthOptions()] * 3, tmp_path / "b.toml", window="10s", workers=1)
    result["outputs"] = plain["outputs"]
    _same_json(result, plain)


def test_tasks_in_worker_processes_are_reported_as_they_arrive():
    from odomkit.workflows.fit_noise import _run_all

    seen = RecordingProgress()
    with stage(seen, 5, "logs"):
        out = _run_all(math.sqrt, [1.0, 4.0, 9.0, 16.0, 25.0], 2, None, seen)
    assert out == [1.0, 2.0, 3.0, 4.0, 5.0]  # in task order
    assert (seen.stages[0].done, seen.stages[0].advances) == (5, 5)


def test_evaluate_reports_each_log_and_each_track(tmp_path):
    from odomkit.workflows.evaluate import evaluate_logs, evaluate_tracks
    from odomkit.workflows.track import run_track

    seen = RecordingProgress()
    result = evaluate_logs(RUNS[:2], ROBOT, [TruthOptions()] * 2, window="10s", progress=seen)
    _complete(seen)
    assert [(s.description, s.total) for s in seen.stages] == [("logs", 2)]
    _same_json(result, evaluate_logs(RUNS[:2], ROBOT, [TruthOptions()] * 2, window="10s"))
    tracks = [run_track(r, ROBOT, out=tmp_path / f"{i}.csv").outputs["track_csv"]
              for i, r in enumerate(RUNS[:3])]
    seen = RecordingProgress()
    evaluate_tracks(tracks, [TruthOptions()] * 3, progress=seen)
    _complete(seen)
    assert [(s.description, s.total) for s in seen.stages] == [("tracks", 3)]


def test_calibrate_noise_reports_each_run_then_the_fit():
    from odomkit.workflows.calibration import noise_files

    seen = RecordingProgress()
    result = noise_files(RUNS, ROBOT, progress=seen)
    _complete(seen)
    assert [(s.description, s.total) for s in seen.stages] == [("runs", 6), ("fitting", None)]
    _same_json(result, noise_files(RUNS, ROBOT))
