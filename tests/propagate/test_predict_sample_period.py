"""Per-sample noise needs the sample period (API study s24, H2).

:class:`~odomkit.noise.TricycleNoise` is white noise on each *sample's* speed, steering
angle and period: its covariance over a segment depends on how many samples the segment
has. ``predict`` took that count from ``partitions`` (a numerical resolution), so the
predicted σ of a tricycle path fell as 1/√partitions. A planned path with per-sample noise
now needs the sample period T (``sample_period``, as a compass needs ``compass_period``):
a segment of duration D has D/T samples, whatever ``partitions`` says.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.kinematics import car_body_steps, tricycle_body_steps
from odomkit.log import OdometryLog
from odomkit.noise import LateralSlipNoise, ParameterUncertainty, SpeedNoise, TricycleNoise
from odomkit.path import SteerArc
from odomkit.propagate.predict import predict
from odomkit.robot import Car, Tricycle
from odomkit.simulate import monte_carlo
from odomkit.track import dead_reckon_log

TRI = Tricycle(0.5)
NOISE = TricycleNoise(sigma_speed=0.02, sigma_steer=0.01, sigma_dt=0.0005)
PATH = [SteerArc(0.4, 0.3, 4.0), SteerArc(0.5, 0.0, 2.0), SteerArc(0.3, -0.25, 3.0)]
T = 0.05


def test_per_sample_noise_without_a_sample_period_is_refused():
    """One line naming what to give, for predict and for the Monte Carlo."""
    with pytest.raises(ModelError, match=r"TricycleNoise is white noise per sample.*sample_period"):
        predict(PATH, NOISE, robot=TRI, engine="recursion")
    with pytest.raises(ModelError, match="sample_period"):
        monte_carlo(PATH, NOISE, robot=TRI, runs=100, partitions=10)
    # noise per metre or per run needs none: partitions stay a resolution there
    predict(PATH, (SpeedNoise(1e-4), ParameterUncertainty(sigma_steering_offset=1e-3)), robot=TRI,
            engine="recursion")


def test_the_prediction_no_longer_depends_on_partitions():
    """The reproducer of H2 (σ ∝ 1/√K before): with a sample period the steps are the
    samples, so partitions change nothing at all."""
    ref = predict(PATH, NOISE, robot=TRI, engine="recursion", sample_period=T)
    for k in (10, 100, 10_000):
        p = predict(PATH, NOISE, robot=TRI, engine="recursion", partitions=k, sample_period=T)
        assert np.array_equal(p.cov, ref.cov)
    other = predict(PATH, NOISE, robot=TRI, engine="transition", sample_period=T)
    assert np.allclose(other.cov, ref.cov, rtol=1e-9, atol=1e-18)
    # a period four times shorter: four times the samples, each as noisy: σ_v² T² per
    # sample summed over D/T samples gives var Δs = σ_v² T D, so the speed term shrinks as T
    fine = predict([SteerArc(0.5, 0.0, 2.0)], TricycleNoise(0.02, 0.0), robot=TRI, engine="recursion",
                   sample_period=T / 4)
    coarse = predict([SteerArc(0.5, 0.0, 2.0)], TricycleNoise(0.02, 0.0), robot=TRI, engine="recursion",
                     sample_period=T)
    assert fine.cov[0, 0] == pytest.approx(coarse.cov[0, 0] / 4, rel=1e-12)
    assert coarse.cov[0, 0] == pytest.approx(0.02**2 * T * 2.0, rel=1e-12)  # exact: σ_v² T D


def test_segments_must_last_whole_samples():
    with pytest.raises(ModelError, match="not a whole number of sample periods"):
        predict([SteerArc(0.4, 0.3, 1.01)], NOISE, robot=TRI, engine="recursion", sample_period=T)
    with pytest.raises(ModelError, match="sample_period must be"):
        predict(PATH, NOISE, robot=TRI, engine="recursion", sample_period=-1.0)


def _simulate_steered(robot, path, noise, period, runs, seed):
    """Independent numpy Monte Carlo of per-sample noise: every sample of period T draws
    its speed v + N(0, σ_v²), steering angle α + N(0, σ_α²) and period T + N(0, σ_T²),
    and the vehicle moves along the exact arc of that sample (the kinematics' own body
    steps); one row per sample, as a log at that period has."""
    rng = np.random.default_rng(seed)
    x, y, th = np.zeros(runs), np.zeros(runs), np.zeros(runs)
    for seg in path:
        for _ in range(round(seg.duration / period)):
            v = seg.speed + rng.normal(0.0, noise.sigma_speed, runs)
            a = seg.steer + rng.normal(0.0, noise.sigma_steer, runs)
            dt = period + rng.normal(0.0, noise.sigma_dt, runs)
            if isinstance(robot, Car):
                dd, dth = car_body_steps(v * dt, a, robot.wheel_base, robot.encoder_offset, robot.encoder_at)
            else:
                dd, dth = tricycle_body_steps(v * dt, a, robot.wheel_to_axle)
            chord = th + 0.5 * dth
            length = dd * np.sinc(dth / (2 * np.pi))
            x += length * np.cos(chord)
            y += length * np.sin(chord)
            th += dth
    return np.column_stack([x, y, th])


@pytest.mark.parametrize("robot,path", [
    (TRI, PATH),
    (Car(2.5, 0.7), [SteerArc(3.0, 0.1, 4.0), SteerArc(3.0, -0.08, 2.0)]),
], ids=["tricycle", "car"])
def test_prediction_at_a_sample_period_against_an_independent_simulation(robot, path):
    """Each covariance entry within 4.5 Wishart standard errors of the simulation."""
    p = predict(path, NOISE, robot=robot, engine="recursion", sample_period=T)
    final = _simulate_steered(robot, path, NOISE, T, 6000, seed=2)
    n = final.shape[0]
    s = np.cov(final.T)
    se = np.sqrt((np.outer(np.diag(p.cov), np.diag(p.cov)) + p.cov**2) / (n - 1))
    assert np.all(np.abs(s - p.cov) <= 4.5 * se), ((s - p.cov) / se)


def test_monte_carlo_at_a_sample_period_agrees_with_predict():
    """The project's Monte Carlo steps the samples (duration/T per segment, whatever K)
    and its theory is the prediction at that period; 'consistent'."""
    noise = (NOISE, LateralSlipNoise(1e-5))
    r = monte_carlo(PATH, noise, robot=TRI, runs=6000, partitions=7, seed=4, sample_period=T)
    p = predict(PATH, noise, robot=TRI, engine="recursion", sample_period=T)
    assert np.allclose(r["theory"]["cov"], p.cov, rtol=1e-12, atol=0)
    assert r["partitions"] == 80  # the most samples of a segment: 4.0 s / 0.05 s
    assert r["consistent"], r["verdict"]


@pytest.mark.parametrize("form", ["speed", "dist"])
def test_log_track_at_the_sample_period_matches_predict(form):
    """``dead_reckon_log`` on a synthetic tricycle log sampled every T gives the
    prediction's end pose and covariance: the steps are the log's rows. A speed rate is
    held from its row over the next step; a distance increment counts the step that ends
    at its row (one segment there: its steering angle is the mean of both rows')."""
    noise = (NOISE, SpeedNoise(1e-4), ParameterUncertainty(sigma_steering_offset=2e-3))
    path = PATH if form == "speed" else PATH[:1]
    counts = [round(s.duration / T) for s in path]
    speed = np.concatenate([np.full(c, s.speed) for s, c in zip(path, counts, strict=True)])
    steer = np.concatenate([np.full(c, s.steer) for s, c in zip(path, counts, strict=True)])
    t = T * np.arange(speed.size + 1)
    if form == "speed":
        chan = {"speed": np.append(speed, 0.0), "steer": np.append(steer, 0.0)}
    else:
        chan = {"dist": np.concatenate([[0.0], speed * T]), "steer": np.full(t.size, path[0].steer)}
    track = dead_reckon_log(OdometryLog(t, chan), TRI, pose0=(0.0, 0.0, 0.0), noise=noise)
    p = predict(path, noise, robot=TRI, engine="recursion", sample_period=T)
    assert np.allclose(track.poses[-1], p.pose, rtol=0, atol=1e-12)
    assert np.allclose(track.cov[-1], p.cov, rtol=1e-10, atol=1e-20)


def test_a_compass_sample_period_is_its_compass_period_and_a_diff_path_takes_none():
    """One period for a sampled path: a compass's readings are its samples."""
    from odomkit.noise import CompassNoise, WheelNoise
    from odomkit.path import KellyArc, Straight

    path, noise = [KellyArc(1.0, 0.2, 2.0)], (SpeedNoise(1e-4), CompassNoise(1e-5))
    a = predict(path, noise, sample_period=0.05)
    b = predict(path, noise, compass_period=0.05)
    assert np.array_equal(a.cov, b.cov)
    with pytest.raises(ModelError, match="sample_period 0.05 s and compass_period 0.1 s differ"):
        predict(path, noise, sample_period=0.05, compass_period=0.1)
    with pytest.raises(ModelError, match=r"sample_period \(--sample-period\) needs segments with durations"):
        predict([Straight(1.0)], WheelNoise(1e-3, 1e-3), wheel_base=0.4, engine="recursion",
                sample_period=0.05)
