"""Compass (direct-heading) prediction of a planned path: the sampled compass (issue 10
items 4 and 7).

A compass sampled every T [s] with white heading noise of density σ_θθ [rad²·s] reads
each heading with an independent error of variance σ_θθ/T; the odometry between two
samples is the exact arc from one measured heading to the next (what ``odomkit track``
does with a compass log). ``predict`` must give that model's covariance: finite θ
variance σ_θθ/T, the same end covariance as ``track`` on a log of the same path, with
every engine, and the Kelly eq. (10)/(14) continuous covariance as T -> 0.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.cli import main
from odomkit.errors import ModelError
from odomkit.log import OdometryLog
from odomkit.noise import CompassNoise, SpeedNoise, WheelNoise
from odomkit.path import Arc, KellyArc
from odomkit.propagate.closed_kelly import compass_arc_cov
from odomkit.propagate.predict import predict
from odomkit.robot import CompassOdometry
from odomkit.track import dead_reckon_log

PATH = [KellyArc(0.4, 0.3, 6.0), KellyArc(0.5, -0.2, 4.0), KellyArc(0.3, 0.0, 2.0)]
NOISE = (SpeedNoise(2e-3), CompassNoise(4e-4))
COV0 = np.array([[1e-3, 2e-4, -1e-4], [2e-4, 2e-3, 3e-4], [-1e-4, 3e-4, 5e-4]])


def rel_err(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


def compass_log(segments, period, theta0):
    """A log sampled every ``period``: constant speed per segment, the nominal heading."""
    t, speed, heading = [0.0], [], [theta0]
    for seg in segments:
        n = round(seg.duration / period)
        for _ in range(n):
            speed.append(seg.speed)
            heading.append(heading[-1] + seg.yaw_rate * period)
            t.append(len(t) * period)
    speed.append(speed[-1])  # the last row's speed is not used (speed[:-1]·dt)
    return OdometryLog(np.array(t), {"speed": np.array(speed), "heading": np.array(heading)})


def run_json(capsys, *args: str) -> dict:
    code = main(["predict", *args, "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out)


COMPASS = ["--model", "compass", "--speed-noise", "1e-4", "--heading-noise", "1e-5",
           "--segment", "arc:0.5,0.2,10", "--segment", "arc:0.5,0,5"]


def test_ros_pose_covariance_has_finite_heading_variance(capsys):
    """Item 4: the θ variance is the sampled compass's σ_θθ/T (default T = 0.1 s), so a ROS
    consumer gets 36 finite numbers."""
    d = run_json(capsys, *COMPASS)
    ros = d["ros_pose_covariance"]
    assert len(ros) == 36 and all(isinstance(v, float) and math.isfinite(v) for v in ros)
    assert ros[35] == pytest.approx(1e-5 / 0.1, rel=1e-12)
    assert d["std"][2] == pytest.approx(math.sqrt(1e-4), rel=1e-12)
    assert all(v is not None for v in d["corr"].values())
    d2 = run_json(capsys, *COMPASS, "--compass-period", "0.05")
    assert d2["ros_pose_covariance"][35] == pytest.approx(1e-5 / 0.05, rel=1e-12)


@pytest.mark.parametrize("period", [0.05, 0.2])
@pytest.mark.parametrize("engine", ["closed", "recursion", "transition"])
def test_predict_equals_track_of_the_same_sampled_path(engine, period):
    """Items 4 and 7: ``track`` on a log of the path sampled every T (each row a compass
    sample) and ``predict --compass-period T`` give the same end covariance (one
    convention), with the closed form and with both step engines."""
    theta0 = 0.7
    log = compass_log(PATH, period, theta0)
    tr = dead_reckon_log(log, CompassOdometry(), pose0=(1.0, -2.0, theta0), noise=NOISE, cov0=COV0)
    p = predict(PATH, NOISE, pose0=(1.0, -2.0, theta0), cov0=COV0, engine=engine,
                compass_period=period)
    assert rel_err(p.cov, tr.cov[-1]) < 1e-10
    assert np.allclose(p.pose, tr.poses[-1], rtol=0, atol=1e-12)
    assert p.cov[2, 2] == pytest.approx(4e-4 / period, rel=1e-12)


def test_engines_work_through_the_cli(capsys):
    """Item 7: ``--engine recursion|transition`` run the track engines on the compass
    samples and agree with the closed form."""
    closed = run_json(capsys, *COMPASS, "--compass-period", "0.25")
    for engine in ("recursion", "transition"):
        d = run_json(capsys, *COMPASS, "--compass-period", "0.25", "--engine", engine)
        assert d["engine"] == engine
        assert rel_err(d["cov"], np.array(closed["cov"])) < 1e-11


def _monte_carlo_sampled(segments, alpha, psd, period, theta0, runs, rng):
    """Independent Monte Carlo of the sampled compass: a heading error of variance
    psd/period at every sample, a distance error of variance α|Δd| per sample step,
    exact arcs between consecutive measured headings."""
    headings = [np.full(1, theta0)]
    dd = []
    for seg in segments:
        n = round(seg.duration / period)
        headings.append(headings[-1][-1] + seg.yaw_rate * period * np.arange(1, n + 1))
        dd.append(np.full(n, seg.speed * period))
    h_nom, d_nom = np.concatenate(headings), np.concatenate(dd)
    h = h_nom + rng.normal(0.0, math.sqrt(psd / period), (runs, h_nom.size))
    d = d_nom + rng.normal(0.0, 1.0, (runs, d_nom.size)) * np.sqrt(alpha * np.abs(d_nom))
    dth = np.diff(h, axis=1)
    chord = d * np.sinc(dth / (2 * np.pi))  # numpy's sinc(x) = sin(πx)/(πx)
    mid = h[:, :-1] + 0.5 * dth
    return np.stack([np.sum(chord * np.cos(mid), axis=1), np.sum(chord * np.sin(mid), axis=1),
                     h[:, -1]], axis=1)


def test_sampled_closed_form_against_monte_carlo():
    """The covariance of the sampled model against 20 000 runs of an independent
    simulation of it: every entry within 4.5 standard errors (Wishart SE
    √((σᵢ²σⱼ² + σᵢⱼ²)/N)); small noise, so the first-order theory must hold."""
    segs = [KellyArc(0.5, 0.4, 3.0), KellyArc(0.5, 0.0, 1.0)]
    alpha, psd, period, runs = 1e-4, 2e-5, 0.1, 20_000
    final = _monte_carlo_sampled(segs, alpha, psd, period, 0.3, runs, np.random.default_rng(7))
    p = predict(segs, (SpeedNoise(alpha), CompassNoise(psd)), pose0=(0, 0, 0.3),
                compass_period=period)
    sample = np.cov(final, rowvar=False)
    var = np.diag(p.cov)
    se = np.sqrt((np.outer(var, var) + p.cov**2) / runs)
    assert np.all(np.abs(sample - p.cov) <= 4.5 * se), (sample - p.cov) / se
    assert np.allclose(final.mean(axis=0), p.pose, atol=4.5 * np.sqrt(var / runs) + 1e-3 * np.sqrt(var))


@pytest.mark.parametrize("seg", [KellyArc(1.0, 0.3, 5.0), KellyArc(-0.7, 0.2, 6.0),
                                 KellyArc(0.5, 0.0, 8.0), KellyArc(2.0, -1.5, 4.0)])
def test_sampled_tends_to_kelly_continuous(seg):
    """Derivation check: interior samples weigh d·sinc²(a/2) ⊥ their heading and the two end
    samples half as much, so P(T) = Kelly eq. (10)/(14) − σ_θθV²T/4·(n₀n₀ᵀ + n₁n₁ᵀ) + O(T²)
    (n the unit normals at the ends). The remainder must shrink 4× when T halves."""
    psd, theta0 = 3e-4, 0.4
    cont = compass_arc_cov(seg, SpeedNoise(0.0), CompassNoise(psd), theta0)[:2, :2]
    theta1 = theta0 + seg.yaw_rate * seg.duration

    def remainder(period):
        ours = compass_arc_cov(seg, SpeedNoise(0.0), CompassNoise(psd), theta0,
                               period=period)[:2, :2]
        n0, n1 = (np.array([-np.sin(a), np.cos(a)]) for a in (theta0, theta1))
        lead = psd * seg.speed**2 * period / 4 * (np.outer(n0, n0) + np.outer(n1, n1))
        return np.max(np.abs(ours - (cont - lead))), np.max(np.abs(ours - cont))

    r1, total1 = remainder(0.01)
    r2, _ = remainder(0.005)
    assert r1 < 0.05 * total1  # the T/4 end correction is the leading difference
    assert r2 / r1 == pytest.approx(0.25, abs=0.03) or r1 < 1e-14 * np.max(np.abs(cont))


def test_period_must_divide_each_segment():
    with pytest.raises(ModelError, match="whole number of compass periods"):
        predict([KellyArc(1.0, 0.0, 0.25)], NOISE, compass_period=0.1)
    with pytest.raises(ModelError, match="compass_period"):
        predict([KellyArc(1.0, 0.0, 1.0)], NOISE, compass_period=0.0)
    with pytest.raises(ModelError, match="compass"):
        predict([Arc(3.0, 1.0)], WheelNoise(1e-3, 1e-3), 0.4, compass_period=0.1)
    for engine in ("closed", "recursion"):  # half a turn between readings: direction unknown
        with pytest.raises(ModelError, match="below π"):
            predict([KellyArc(1.0, 40.0, 1.0)], NOISE, compass_period=0.1, engine=engine)


def test_compass_period_flag_belongs_to_the_compass_model(capsys):
    code = main(["predict", "--wheel-base", "0.4", "--k-left", "1e-3", "--k-right", "1e-3",
                 "--segment", "arc:3,1", "--compass-period", "0.1"])
    assert code == 2
    assert "--compass-period" in capsys.readouterr().err


def test_bad_compass_period_is_one_line_exit_2(capsys):
    for extra, words in ((["--compass-period", "0"], "--compass-period"),
                         (["--compass-period", "0.3"], "whole number of compass periods")):
        assert main(["predict", *COMPASS, *extra]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_help_states_the_default_period(capsys):
    from odomkit.noise.kelly import DEFAULT_COMPASS_PERIOD

    assert main(["predict", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"(default {DEFAULT_COMPASS_PERIOD:g})" in text
