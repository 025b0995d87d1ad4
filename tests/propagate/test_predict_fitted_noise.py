"""A fitted robot's noise predicts and simulates (API study s24, H1).

``fit-noise`` fits a diff robot's white noise as WheelNoise + SpeedNoise + LateralSlipNoise
and its bias as a ParameterUncertainty. ``predict``, ``monte_carlo`` and ``simulate_runs``
refused that set, although ``track`` (and ``evaluate``'s windows) propagate it on a log.
Now a planned path accepts every set the log-based track accepts for the vehicle: the
same engine (:func:`odomkit.propagate.recursion.iter_track_covariance`) on the path's
steps. Checked against an independent numpy simulation of the noise (sampling-error
tolerances), against the project's Monte Carlo, and against ``dead_reckon_log`` on a log
of the same path.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.log import OdometryLog
from odomkit.noise import (
    NOISE_MODELS,
    ClassicalNoise,
    GyroNoise,
    LateralSlipNoise,
    NoiseSet,
    ParameterUncertainty,
    SpeedNoise,
    WheelNoise,
)
from odomkit.path import Arc, KellyArc, Spin, SteerArc, Straight
from odomkit.propagate.predict import predict
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle
from odomkit.simulate import monte_carlo, simulate_runs
from odomkit.track import dead_reckon_log

B = 0.3
# fit-noise's default diff model (DEFAULT_WHITE["diff"] and a bias), at sizes that make
# every term visible at the end of a 1.7 m square
FITTED = (WheelNoise(0.0, 2e-3), SpeedNoise(4e-5), LateralSlipNoise(3e-5),
          ParameterUncertainty(sigma_wheel_base=2e-3, sigma_scale_right=2e-3))
SQUARE = [Straight(1.7), Spin(-np.pi / 2)] * 4
PATH = [Arc(1.0, 1.3), Straight(0.8), Spin(0.7), Arc(0.9, 0.5)]


def _simulate_diff(path, noise, base, runs, n, seed):
    """Independent numpy Monte Carlo of the fitted diff noise, from its definitions: each
    run draws a wheel-base error δb ~ N(0, σ_b²) and wheel-scale errors ε ~ N(0, σ²) once
    (a wheel travels d(1 + ε), the base is b + δb); each of the n partitions of a segment
    gets wheel-travel noise N(0, k²|d|) per wheel (Chong–Kleeman eq. 4), distance noise
    N(0, α_ss|Δd|) (Kelly Table 1) and a sideways slip N(0, α_lat|Δd|) across its chord;
    the pose moves along the exact arc. Returns the final poses (runs, 3)."""
    wheel, speed, slip, pu = noise
    rng = np.random.default_rng(seed)
    db = rng.normal(0.0, pu.sigma_wheel_base, runs)
    eps_l = rng.normal(0.0, pu.sigma_scale_left, runs)
    eps_r = rng.normal(0.0, pu.sigma_scale_right, runs)
    x, y, th = np.zeros(runs), np.zeros(runs), np.zeros(runs)
    for seg in path:
        left, right = seg.wheel_travel(base)
        dl, dr = left / n, right / n
        dd0 = 0.5 * (dl + dr)
        for _ in range(n):
            d_l = dl * (1 + eps_l) + rng.normal(0.0, wheel.k_left * np.sqrt(abs(dl)), runs)
            d_r = dr * (1 + eps_r) + rng.normal(0.0, wheel.k_right * np.sqrt(abs(dr)), runs)
            dd = 0.5 * (d_l + d_r) + rng.normal(0.0, np.sqrt(speed.alpha_ss * abs(dd0)), runs)
            dth = (d_r - d_l) / (base + db)
            chord = th + 0.5 * dth
            length = dd * np.sinc(dth / (2 * np.pi))  # chord = Δd·sin(Δθ/2)/(Δθ/2)
            side = rng.normal(0.0, np.sqrt(slip.alpha_lateral * abs(dd0)), runs)
            x += length * np.cos(chord) - side * np.sin(chord)
            y += length * np.sin(chord) + side * np.cos(chord)
            th += dth
    return np.column_stack([x, y, th])


def _assert_cov_agrees(final, pose, cov, name):
    """Sample covariance about the sample mean against the prediction, each entry within
    4.5 standard errors √((P_ii P_jj + P_ij²)/(N − 1)) (Wishart), and the mean within 4.5
    σ/√N of the predicted pose."""
    n = final.shape[0]
    s = np.cov(final.T)
    se = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / (n - 1))
    assert np.all(np.abs(s - cov) <= 4.5 * se), (name, s, cov, (s - cov) / se)
    mean_se = np.sqrt(np.diag(cov) / n)
    assert np.all(np.abs(final.mean(axis=0) - pose) <= 4.5 * mean_se), (name, final.mean(axis=0), pose)


def test_the_fitted_diff_noise_predicts_with_and_without_a_robot():
    """The reproducer of H1: the same set was 'not a prediction model'."""
    a = predict(SQUARE, FITTED, wheel_base=B, engine="recursion")
    b = predict(SQUARE, FITTED, robot=DiffDrive(B), engine="recursion")
    c = predict(SQUARE, FITTED, robot=DiffDrive(B), engine="transition")
    assert np.array_equal(a.cov, b.cov)
    assert np.allclose(b.cov, c.cov, rtol=1e-9, atol=1e-18)
    assert a.model == "wheel" and np.all(a.std > 0)
    # SpeedNoise has no closed form beside the wheels' (nor has bias noise): say which engines
    with pytest.raises(ModelError, match="no closed form here; use engine 'recursion' or 'transition'"):
        predict(SQUARE, FITTED[:3], wheel_base=B)


@pytest.mark.parametrize("path", [SQUARE, PATH], ids=["square", "mixed"])
def test_prediction_of_the_fitted_noise_against_an_independent_simulation(path):
    """Every covariance entry and the mean within their sampling error of an independent
    numpy simulation of the four models (8000 runs)."""
    n = 40
    p = predict(path, FITTED, wheel_base=B, engine="recursion", partitions=n)
    final = _simulate_diff(path, FITTED, B, 8000, n, seed=5)
    _assert_cov_agrees(final, p.pose, p.cov, "independent")


def test_monte_carlo_and_simulate_runs_take_the_fitted_noise():
    """The project's Monte Carlo accepts the set (with robot= too) and agrees with the
    prediction to its sampling error."""
    r = monte_carlo(SQUARE, FITTED, robot=DiffDrive(B), runs=8000, partitions=40, seed=3)
    p = predict(SQUARE, FITTED, robot=DiffDrive(B), engine="recursion", partitions=40)
    assert np.allclose(r["theory"]["cov"], p.cov, rtol=1e-12, atol=0)
    assert r["theory"]["engine"] == "recursion"
    mc = simulate_runs(SQUARE, FITTED, B, runs=8000, partitions=40, seed=3)
    _assert_cov_agrees(mc.final, p.pose, p.cov, "simulate_runs")


def test_prediction_equals_the_log_track_of_the_same_path():
    """``dead_reckon_log`` on a log that drives the path (n rows per segment, wheel
    travels as dist_left/dist_right increments) gives the prediction's end covariance:
    one engine for a log and a plan."""
    n = 25
    d_left = np.concatenate([[0.0]] + [np.full(n, s.wheel_travel(B)[0] / n) for s in PATH])
    d_right = np.concatenate([[0.0]] + [np.full(n, s.wheel_travel(B)[1] / n) for s in PATH])
    log = OdometryLog(0.1 * np.arange(d_left.size), {"dist_left": d_left, "dist_right": d_right})
    track = dead_reckon_log(log, DiffDrive(B), pose0=(0.0, 0.0, 0.0), noise=FITTED)
    p = predict(PATH, FITTED, robot=DiffDrive(B), engine="recursion", partitions=n)
    assert np.allclose(track.poses[-1], p.pose, rtol=0, atol=1e-12)
    assert np.allclose(track.cov[-1], p.cov, rtol=1e-10, atol=1e-20)


# Every vehicle with the models the track takes for it (check_robot), as a robot file
# could give them, and the segments it drives.
_VEHICLES = [
    (DiffDrive(B), PATH, {}),
    (GyroOdometry(), [KellyArc(0.5, 0.2, 4.0), KellyArc(0.5, 0.0, 2.0)], {}),
    (Unicycle(), [KellyArc(0.5, 0.2, 4.0), KellyArc(0.5, 0.0, 2.0)], {}),
    (CompassOdometry(), [KellyArc(0.5, 0.2, 4.0), KellyArc(0.5, 0.0, 2.0)], {"compass_period": 0.1}),
    (Tricycle(0.5), [SteerArc(0.5, 0.2, 4.0), SteerArc(0.5, 0.0, 2.0)], {"sample_period": 0.05}),
    (Car(2.5, 0.7), [SteerArc(2.0, 0.1, 4.0), SteerArc(2.0, -0.05, 2.0)], {"sample_period": 0.05}),
]


def _applicable(robot):
    """One instance of each registered model that the track accepts for ``robot``, with
    every parameter 1e-4 (the bias model: the robot's own parameters)."""
    out = []
    for cls in NOISE_MODELS.values():
        if cls is ParameterUncertainty:
            from odomkit.noise.parameters import PARAMETERS

            model = cls(**dict.fromkeys(PARAMETERS[robot.type_name], 1e-4))
        else:
            from dataclasses import fields

            model = cls(**{f.name: 1e-4 for f in fields(cls) if f.name != "mode"})
        try:
            NoiseSet((model,)).check_robot(robot)
        except ModelError:
            continue
        out.append(model)
    return out


@pytest.mark.parametrize("robot,path,period", _VEHICLES, ids=[type(v[0]).__name__ for v in _VEHICLES])
def test_every_set_the_track_accepts_predicts_and_simulates(robot, path, period):
    """For each vehicle, every subset of the models the track accepts (those a NoiseSet
    can hold together: a classical model stands alone) predicts with both engines and
    simulates, with ``robot=``. Two are refused with a one-line reason: a gyro's noise,
    which grows with time, on a diff path, which has no durations; the classical step
    map on a compass robot. The per-step noise of a classical model or a TricycleNoise
    takes the sample period on a path with durations."""
    models = _applicable(robot)
    # refused, with a reason: noise that grows with time on a path with no durations, and
    # the classical step map (rotate, then translate by an integrated heading) on a
    # compass robot, which measures its heading
    timed = [m for m in models if isinstance(m, GyroNoise) and robot.type_name == "diff"]
    own_map = [m for m in models if isinstance(m, ClassicalNoise) and robot.measures_heading]
    usable = [m for m in models if m not in timed + own_map]
    tried = 0
    for r in range(1, len(usable) + 1):
        for subset in itertools.combinations(usable, r):
            try:
                NoiseSet(subset)
            except ModelError:  # a classical model with another: refused by the track too
                assert any(isinstance(m, ClassicalNoise) for m in subset)
                continue
            kw = dict(period)
            if robot.type_name != "diff" and not kw and any(isinstance(m, ClassicalNoise) for m in subset):
                with pytest.raises(ModelError, match="ClassicalNoise is white noise per sample"):
                    predict(path, subset, robot=robot, engine="recursion")
                kw = {"sample_period": 0.05}
            a = predict(path, subset, robot=robot, engine="recursion", partitions=20, **kw)
            b = predict(path, subset, robot=robot, engine="transition", partitions=20, **kw)
            assert np.allclose(a.cov, b.cov, rtol=1e-8, atol=1e-15), subset
            mc = simulate_runs(path, subset, robot=robot, runs=64, partitions=20, seed=1, **kw)
            assert np.all(np.isfinite(mc.final))
            tried += 1
    assert tried >= 7
    for model in timed:
        with pytest.raises(ModelError, match="no duration"):
            predict(path, (WheelNoise(1e-3, 1e-3), model), robot=robot, engine="recursion")
    for model in own_map:
        with pytest.raises(ModelError, match="measures its heading"):
            predict(path, model, robot=robot, engine="recursion", **period)
