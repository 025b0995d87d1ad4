"""Path-level prediction: composition over segments, the three engines, the classical
model's inconsistency, the JSON dict, and input validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.kinematics import step_jacobians
from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, WheelNoise
from odomkit.path import Arc, KellyArc, Spin, Straight
from odomkit.propagate.predict import discretise_path, predict, wrap_angle

PATH = [Arc(3.0, 1.0), Straight(2.0), Spin(1.5708), Arc(-1.0, 2.0), Straight(-0.5)]
NOISE = WheelNoise(0.002, 0.004)
COV0 = np.array([[1e-4, 2e-5, -1e-5], [2e-5, 3e-4, 4e-5], [-1e-5, 4e-5, 2e-4]])
POSE0 = (0.5, -1.0, 0.7)


def rel_err(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


def _reference(poses, dd, dth, q, cov0):
    """Test-only step recursion P <- F P Fᵀ + G Q Gᵀ (exact-arc Jacobians)."""
    F, G = step_jacobians(poses[:-1, 2], dd, dth, "exact")
    P = np.array(cov0, dtype=float)
    for k in range(dd.size):
        P = F[k] @ P @ F[k].T + G[k] @ q[k] @ G[k].T
    return P


def test_path_closed_equals_extrapolated_reference_recursion():
    closed = predict(PATH, NOISE, 0.4, POSE0, COV0)
    p1 = _reference(*discretise_path(PATH, NOISE, 0.4, 200, POSE0), COV0)
    p2 = _reference(*discretise_path(PATH, NOISE, 0.4, 400, POSE0), COV0)
    assert rel_err(p2, closed.cov) < 1e-5
    assert rel_err((4 * p2 - p1) / 3, closed.cov) < 1e-9  # O(1/n²) Richardson


def test_end_pose_is_the_exact_arc_chain():
    poses, *_ = discretise_path(PATH, NOISE, 0.4, 7, POSE0)
    assert np.allclose(predict(PATH, NOISE, 0.4, POSE0).pose, poses[-1], rtol=0, atol=1e-13)


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_closed_equals_other_engines_on_fine_partitions(engine):
    closed = predict(PATH, NOISE, 0.4, POSE0, COV0)
    fine = predict(PATH, NOISE, 0.4, POSE0, COV0, engine=engine, partitions=2000)
    assert rel_err(fine.cov, closed.cov) < 1e-6
    assert np.allclose(fine.pose, closed.pose, rtol=0, atol=1e-11)


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_gyro_closed_equals_other_engines(engine):
    segs = [KellyArc(1.0, 0.3, 5.0), KellyArc(-0.5, 0.0, 3.0), KellyArc(2.0, -1.0, 2.0)]
    noise = (SpeedNoise(1e-3), GyroNoise(1e-4))
    closed = predict(segs, noise, pose0=POSE0, cov0=COV0)
    fine = predict(segs, noise, pose0=POSE0, cov0=COV0, engine=engine, partitions=2000)
    assert rel_err(fine.cov, closed.cov) < 1e-6


def test_classical_model_is_inconsistent_as_in_the_paper():
    D, sd, sa = 1.5, 0.2, 0.03
    noise = ClassicalNoise(sd, sa)
    one = predict([Straight(2 * D)], noise, wheel_base=0.4).cov
    two = predict([Straight(D), Straight(D)], noise, wheel_base=0.4).cov
    split = predict([Straight(2 * D)], noise, wheel_base=0.4, partitions=2).cov
    # Chong–Kleeman section 1, cases (i) and (ii)
    case_i = [[sd**2, 0, 0], [0, 4 * D**2 * sa**2, 2 * D * sa**2], [0, 2 * D * sa**2, sa**2]]
    case_ii = [[2 * sd**2, 0, 0], [0, 5 * D**2 * sa**2, 3 * D * sa**2],
               [0, 3 * D * sa**2, 2 * sa**2]]
    assert np.allclose(one, case_i, rtol=1e-14, atol=0)
    assert np.allclose(two, case_ii, rtol=1e-14, atol=0)
    assert np.allclose(split, case_ii, rtol=1e-14, atol=0)
    # ...whereas the per-wheel model does not care how the path is cut
    wheel = WheelNoise(0.01, 0.01)
    assert rel_err(predict([Straight(D), Straight(D)], wheel, 0.4).cov,
                   predict([Straight(2 * D)], wheel, 0.4).cov) < 1e-14


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_classical_closed_equals_step_engines(engine):
    segs, noise = [Arc(2.0, 1.0), Spin(-1.0), Straight(1.0)], ClassicalNoise(0.01, 0.02)
    closed = predict(segs, noise, 0.5, POSE0, COV0, partitions=5)
    steps = predict(segs, noise, 0.5, POSE0, COV0, engine=engine, partitions=5)
    assert rel_err(steps.cov, closed.cov) < 1e-12
    assert np.allclose(steps.pose, closed.pose, rtol=0, atol=1e-13)


def test_compass_path_chains_segments_through_the_shared_reading():
    """A compass path's position covariance is the sum of its segments' own terms (Φ = I,
    Kelly 3.1) plus, at each junction, the cross term of the reading both segments
    share: with the cross-covariance carried in cov[:2, 2], cutting a segment in two
    changes nothing."""
    noise = (SpeedNoise(1e-3), CompassNoise(2e-4))
    whole = predict([KellyArc(1.0, 0.2, 4.0)], noise, cov0=COV0, compass_period=0.1)
    cut = predict([KellyArc(1.0, 0.2, 1.5), KellyArc(1.0, 0.2, 2.5)], noise, cov0=COV0,
                  compass_period=0.1)
    assert rel_err(cut.cov, whole.cov) < 1e-13
    # the θ row and column of cov0 give way to the first reading: no trace of them
    other = predict([KellyArc(1.0, 0.2, 4.0)], noise, cov0=np.diag([1e-4, 3e-4, 9.0]),
                    compass_period=0.1)
    assert other.cov[2, 2] == pytest.approx(2e-3, rel=1e-12)
    d = whole.to_dict()
    assert d["std"][2] == pytest.approx(math.sqrt(2e-3), rel=1e-12)
    assert all(math.isfinite(v) for v in d["corr"].values())


def test_to_dict_wraps_heading_and_reports_coefficients():
    p = predict([Arc(3.0, 1.0)], WheelNoise(0.01, 0.02), 0.4)
    d = p.to_dict()
    assert p.pose[2] == pytest.approx(-5.0)
    assert d["pose"][2] == pytest.approx(-5.0 + 2 * np.pi) and -np.pi <= d["pose"][2] < np.pi
    cov = np.array(d["cov"])
    std = np.sqrt(np.diag(cov))
    assert np.allclose(d["std"], std)
    assert d["corr"]["xy"] == pytest.approx(cov[0, 1] / (std[0] * std[1]))
    assert d["corr"]["ytheta"] == pytest.approx(cov[1, 2] / (std[1] * std[2]))
    assert all(-1 <= v <= 1 for v in d["corr"].values())


def test_zero_noise_gives_zero_covariance_and_undefined_correlation():
    p = predict(PATH, WheelNoise(0.0, 0.0), 0.4)
    assert np.array_equal(p.cov, np.zeros((3, 3)))
    assert all(math.isnan(v) for v in p.corr.values())


def test_wrap_angle_range():
    t = np.array([-np.pi, np.pi, 3 * np.pi + 0.1, -7.0])
    w = wrap_angle(t)
    assert np.all((w >= -np.pi) & (w < np.pi))
    assert np.allclose(np.cos(w), np.cos(t)) and np.allclose(np.sin(w), np.sin(t))


@pytest.mark.parametrize("kwargs,match", [
    (dict(wheel_base=None), "wheel base"),
    (dict(wheel_base=-0.4), "wheel base"),
    (dict(cov0=np.eye(2)), "3x3"),
    (dict(cov0=[[1, 2, 0], [0, 1, 0], [0, 0, 1]]), "symmetric"),
    (dict(cov0=[[1, 2, 0], [2, 1, 0], [0, 0, 1]]), "positive semi-definite"),
    (dict(engine="magic"), "engine"),
    (dict(pose0=(0, 0)), "initial pose"),
    (dict(engine="recursion", partitions=0), "partitions"),
])
def test_bad_input_raises_model_error(kwargs, match):
    args = dict(segments=[Arc(3.0, 1.0)], noise=NOISE, wheel_base=0.4) | kwargs
    with pytest.raises(ModelError, match=match):
        predict(**args)


def test_segments_must_fit_the_model():
    with pytest.raises(ModelError, match="segment 1"):
        predict([KellyArc(1, 0, 1)], NOISE, 0.4)
    with pytest.raises(ModelError, match="segment 2"):
        predict([KellyArc(1, 0, 1), Straight(1)], (SpeedNoise(0), GyroNoise(1e-3)))
    with pytest.raises(ModelError, match="not a prediction model"):
        predict([KellyArc(1, 0, 1)], SpeedNoise(1e-3))
    with pytest.raises(ModelError, match="compass samples"):
        discretise_path([KellyArc(1, 0, 1)], (SpeedNoise(0), CompassNoise(1e-3)))
