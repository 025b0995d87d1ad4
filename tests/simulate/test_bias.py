"""Monte Carlo confirms every vehicle's white and bias noise (issue 11 item 1, issue 12
item 3): each run draws one bias per parameter (:mod:`odomkit.simulate.plan`) and the
covariance of the simulated end poses must match the engines' propagated covariance
(``predict(..., engine="recursion")``, the bias path of ``odomkit track``).

Tolerance from the sampling error: a sample covariance entry of n runs has standard
error √((c_ii c_jj + c_ij²)/n); every entry must lie within 5 of them (a false alarm per
entry has probability below 6e-7), plus 2 % of the largest entry for the second-order
terms the first-order prediction leaves out (the σ's are small, so those are well below
that). The mean end pose must be the nominal one within 5 standard errors.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.noise import CompassNoise, GyroNoise, ParameterUncertainty, SpeedNoise, TricycleNoise, WheelNoise
from odomkit.path import Arc, KellyArc, SteerArc, Straight
from odomkit.propagate.predict import predict
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle
from odomkit.simulate.engine import simulate_runs

RUNS, PARTITIONS = 20_000, 40

DIFF_PATH = [Arc(3.0, 2.0), Straight(2.0), Arc(1.0, 2.5)]
KELLY_PATH = [KellyArc(1.0, 0.2, 6.0), KellyArc(1.0, 0.0, 4.0), KellyArc(0.8, -0.3, 5.0)]
STEER_PATH = [SteerArc(2.0, 0.12, 5.0), SteerArc(2.0, 0.0, 3.0), SteerArc(1.5, -0.2, 4.0)]

# (name, robot, path, noise): one bias term at a time, then white noise of the new vehicles
CASES = [
    ("diff-wheel-base", DiffDrive(0.4), DIFF_PATH, ParameterUncertainty(sigma_wheel_base=0.001)),
    ("diff-scale-left", DiffDrive(0.4), DIFF_PATH, ParameterUncertainty(sigma_scale_left=5e-4)),
    ("diff-scale-right", DiffDrive(0.4), DIFF_PATH, ParameterUncertainty(sigma_scale_right=5e-4)),
    ("diff-white+bias", DiffDrive(0.4), DIFF_PATH,
     (WheelNoise(0.003, 0.004), ParameterUncertainty(5e-4, 5e-4, 4e-4))),
    ("tricycle-wheel-base", Tricycle(0.7), STEER_PATH, ParameterUncertainty(sigma_wheel_base=0.005)),
    ("tricycle-scale", Tricycle(0.7), STEER_PATH, ParameterUncertainty(sigma_scale_left=0.01)),
    ("tricycle-steering-offset", Tricycle(0.7), STEER_PATH,
     ParameterUncertainty(sigma_steering_offset=5e-4)),
    ("tricycle-white", Tricycle(0.7), STEER_PATH, TricycleNoise(0.02, 0.004, 0.001)),
    ("car-wheel-base", Car(2.7, 0.8), STEER_PATH, ParameterUncertainty(sigma_wheel_base=0.05)),
    ("car-scale", Car(2.7, 0.8), STEER_PATH, ParameterUncertainty(sigma_scale_left=0.01)),
    ("car-steering-offset", Car(2.7, 0.8), STEER_PATH, ParameterUncertainty(sigma_steering_offset=0.003)),
    ("car-front-steering-offset", Car(2.7, -0.8, "front"), STEER_PATH,
     ParameterUncertainty(sigma_steering_offset=0.003)),
    ("car-white", Car(2.7, 0.8, "front"), STEER_PATH, (TricycleNoise(0.02, 0.004), SpeedNoise(1e-4))),
    ("car-white+bias", Car(2.7, 0.8), STEER_PATH,
     (TricycleNoise(0.02, 0.004), ParameterUncertainty(0.03, 0.005, sigma_steering_offset=0.002))),
    ("gyro-speed-scale", GyroOdometry(), KELLY_PATH, ParameterUncertainty(sigma_scale_left=0.01)),
    ("gyro-yaw-rate-offset", GyroOdometry(), KELLY_PATH, ParameterUncertainty(sigma_yaw_rate_offset=0.001)),
    ("gyro-yaw-rate-scale", GyroOdometry(), KELLY_PATH, ParameterUncertainty(sigma_yaw_rate_scale=0.01)),
    ("unicycle-speed-scale", Unicycle(), KELLY_PATH, ParameterUncertainty(sigma_scale_left=0.01)),
    ("unicycle-yaw-rate-offset", Unicycle(), KELLY_PATH,
     ParameterUncertainty(sigma_yaw_rate_offset=0.001)),
    ("unicycle-yaw-rate-scale", Unicycle(), KELLY_PATH, ParameterUncertainty(sigma_yaw_rate_scale=0.01)),
    ("unicycle-white+bias", Unicycle(), KELLY_PATH,
     (SpeedNoise(2e-4), GyroNoise(2e-6), ParameterUncertainty(0, 0.005, sigma_yaw_rate_offset=5e-4))),
    ("compass-speed-scale", CompassOdometry(), KELLY_PATH,
     (CompassNoise(1e-7), ParameterUncertainty(sigma_scale_left=0.01))),
    ("compass-heading-offset", CompassOdometry(), KELLY_PATH,
     (CompassNoise(1e-7), ParameterUncertainty(sigma_heading_offset=0.01))),
    ("compass-white+bias", CompassOdometry(), KELLY_PATH,
     (SpeedNoise(2e-4), CompassNoise(1e-5), ParameterUncertainty(0, 0.005, sigma_heading_offset=0.005))),
]


def _period(noise):
    """A 10 Hz sample period for per-sample noise (a TricycleNoise), which needs one."""
    models = noise if isinstance(noise, tuple) else (noise,)
    return {"sample_period": 0.1} if any(m.per_sample for m in models) else {}


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_monte_carlo_confirms_the_propagated_covariance(case):
    name, robot, path, noise = case
    per = _period(noise)
    theory = predict(path, noise, robot=robot, engine="recursion", partitions=PARTITIONS, **per)
    mc = simulate_runs(path, noise, robot=robot, runs=RUNS, partitions=PARTITIONS, seed=7, **per)
    if isinstance(robot, CompassOdometry):  # the compass's readings are its steps
        assert mc.partitions >= PARTITIONS
    final = mc.final
    cov = np.cov(final.T)
    c = theory.cov
    se = np.sqrt((np.outer(np.diag(c), np.diag(c)) + c**2) / RUNS)
    assert np.all(np.abs(cov - c) <= 5 * se + 0.02 * np.abs(c).max()), (name, cov, c)
    # the variances themselves, relative: sampling error √(2/(n−1)) each
    big = np.diag(c) > 1e-6 * np.diag(c).max()
    ratio = np.diag(cov)[big] / np.diag(c)[big]
    assert np.all(np.abs(ratio - 1) <= 5 * np.sqrt(2 / (RUNS - 1)) + 0.02), (name, ratio)
    mean_err = final.mean(axis=0) - theory.pose
    sigma = np.sqrt(np.diag(c))
    assert np.all(np.abs(mean_err) <= 5 * sigma / np.sqrt(RUNS) + 0.02 * sigma + 1e-9), name


def test_bias_draws_do_not_depend_on_chunking_workers_or_the_numba_kernel():
    """Same seed, same numbers: the bias normals are drawn per block right after the
    start pose (tasks of 1 or 4 blocks, 1 or 2 threads give identical bits); the numba
    and numpy kernels agree to rounding."""
    path, noise = DIFF_PATH, (WheelNoise(0.003, 0.004), ParameterUncertainty(0.002, 0.005, 0.004))
    robot = DiffDrive(0.4)
    runs = [simulate_runs(path, noise, robot=robot, runs=1000, partitions=30, seed=3, chunk_runs=c,
                          workers=w).final for c, w in ((256, 1), (1024, 2), (512, 2))]
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])
    numpy = simulate_runs(path, noise, robot=robot, runs=1000, partitions=30, seed=3, engine="numpy").final
    assert np.allclose(numpy, runs[0], rtol=0, atol=1e-12)
    # the bias really varies from run to run, and is the same within a run
    plain = simulate_runs(path, noise[0], robot=robot, runs=1000, partitions=30, seed=3).final
    assert not np.allclose(plain, runs[0])


def test_no_bias_leaves_the_random_streams_as_they_were():
    """Without bias noise nothing extra is drawn: a zero-σ bias model (which draws) and
    none (which does not) differ, but none gives the numbers of before (the golden
    simulate outputs pin those)."""
    path, robot = DIFF_PATH, DiffDrive(0.4)
    plain = simulate_runs(path, WheelNoise(0.003, 0.004), 0.4, runs=300, partitions=20, seed=5).final
    again = simulate_runs(path, WheelNoise(0.003, 0.004), robot=robot, runs=300, partitions=20, seed=5).final
    assert np.array_equal(plain, again)


def test_closed_engine_refuses_bias_and_steered_vehicles():
    with pytest.raises(ModelError, match="bias noise has no closed form"):
        predict(DIFF_PATH, (WheelNoise(0.01, 0.01), ParameterUncertainty(0.01)), 0.4)
    with pytest.raises(ModelError, match="steering model has no closed form"):
        predict(STEER_PATH, TricycleNoise(0.01, 0.01), robot=Car(2.7), sample_period=0.1)
    # the transition engine gives the recursion's numbers
    a = predict(STEER_PATH, TricycleNoise(0.01, 0.01), robot=Car(2.7), engine="recursion", sample_period=0.1)
    b = predict(STEER_PATH, TricycleNoise(0.01, 0.01), robot=Car(2.7), engine="transition", sample_period=0.1)
    assert np.allclose(a.cov, b.cov, rtol=1e-9, atol=1e-18)


def test_monte_carlo_experiment_gives_a_car_with_bias_its_verdict():
    """``monte_carlo`` (behind ``odomkit simulate``) predicts bias noise and steered
    vehicles with the step recursion on the simulated steps and calls them consistent."""
    from odomkit.simulate import monte_carlo

    noise = (TricycleNoise(0.02, 0.004), ParameterUncertainty(0.03, 0.005, sigma_steering_offset=0.002))
    r = monte_carlo(STEER_PATH, noise, robot=Car(2.7, 0.8), runs=4000, partitions=40, seed=11,
                    sample_period=0.1)
    p = predict(STEER_PATH, noise, robot=Car(2.7, 0.8), engine="recursion", sample_period=0.1)
    assert r["theory"]["pose"] == pytest.approx(p.to_dict()["pose"])
    assert r["linear_model_ok"], r["verdict"]
