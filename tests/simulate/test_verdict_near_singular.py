"""The Monte Carlo verdict on a nearly singular predicted covariance (API study s24, L7).

Bias noise makes the end errors of a path nearly collinear: the predicted covariance has
directions with almost no variance. There the first-order prediction is of the size of
the second-order terms it neglects, so the whitened errors (NEES, the mean and covariance
tests) blew up, and the verdict read "linear model breaks down: mean NEES 350" where every
axis's σ agreed to 1 %. The checks now leave out a direction that both the theory and the
simulation find negligible (below 0.1 % of the largest standardised variance in theory,
0.2 % in the simulation) and say so; a direction the simulation fills is kept, so a real
disagreement still fails.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.noise import LateralSlipNoise, ParameterUncertainty, WheelNoise
from odomkit.path import Spin, Straight
from odomkit.simulate import compare, monte_carlo

SQUARE = [Straight(1.7), Spin(-np.pi / 2)] * 4
# s4b_bias.py of the study: a wheel-base bias and almost no white noise
BIAS = (WheelNoise(1e-5, 1e-5), ParameterUncertainty(sigma_wheel_base=0.00175))
# s4c.py: the noise fit-noise fitted on the OptiOdom squares
FITTED = (WheelNoise(0.0, 6.342e-4), LateralSlipNoise(1.324e-5),
          ParameterUncertainty(sigma_wheel_base=1.749e-3, sigma_scale_right=1.694e-3))


@pytest.mark.parametrize("noise,base", [(BIAS, 0.2)], ids=["bias"])
def test_bias_noise_that_agrees_is_consistent_and_names_what_was_left_out(noise, base):
    """Theory and simulation agree on every axis (σ within 1.5 %, checked here against
    their sampling error): the verdict is 'consistent' and names the left-out directions,
    whose own NEES is reported."""
    r = monte_carlo(SQUARE, noise, base, runs=4000, partitions=100, seed=2)
    th, sim = np.asarray(r["theory"]["std"]), np.asarray(r["simulation"]["std"])
    assert np.all(np.abs(sim / th - 1) < 0.015)
    assert r["consistent"] and r["linear_model_ok"], r["verdict"]
    assert r["verdict"].startswith("consistent (left out"), r["verdict"]
    left = r["checks"]["left_out"]
    assert left and all(d["predicted_share"] < 0.01 and d["simulated_share"] < 0.02 for d in left)
    assert r["checks"]["rank"] == 3 - len(left)
    if noise is BIAS:  # where the old verdict saw NEES 350: the second order dominates there
        assert max(d["nees"] for d in left) > 50


def test_bias_noise_with_a_wrong_theory_is_not_consistent():
    """The same simulation against a theory whose variance is 0.7 of the true one in
    every direction: the kept direction carries the disagreement."""
    from odomkit.propagate.predict import predict

    p = predict(SQUARE, BIAS, wheel_base=0.2, engine="recursion", partitions=100)
    r = monte_carlo(SQUARE, BIAS, 0.2, runs=4000, partitions=100, seed=2, theory=(p.pose, 0.7 * p.cov))
    assert not r["consistent"] and not r["linear_model_ok"], r["verdict"]
    assert r["verdict"].startswith("linear model breaks down")


def _near_singular():
    """A predicted covariance of rank one in (x, y, θ) plus 1e-6 of its trace (σ about
    0.05 m, 0.05 m, 0.06 rad; correlations ±0.9999...), and a unit direction of the
    standardised errors orthogonal to its main one (where it has almost no variance)."""
    u = np.array([0.6, -0.55, 0.58])
    scale = np.diag([0.05, 0.05, 0.06])
    core = np.outer(u, u) / (u @ u) * 3
    cov = scale @ (core + 1e-6 * np.eye(3)) @ scale
    v = np.linalg.svd(np.outer(u, u))[0][:, 1]  # a direction the theory says is empty
    return cov, scale, v


def test_second_order_noise_in_an_empty_direction_is_left_out():
    """Samples from the predicted Gaussian plus a quadratic term (z² − 1)·ε along a
    direction with 1e-6 of the largest standardised variance, ε = 1 % of the axes' σ:
    every axis's σ agrees, the whitened NEES there is in the hundreds; consistent, with
    that direction left out."""
    rng = np.random.default_rng(7)
    cov, scale, v = _near_singular()
    n = 20_000
    z = rng.standard_normal(n)
    e = rng.multivariate_normal(np.zeros(3), cov, n) + 0.01 * np.outer(z * z - 1.0, scale @ v)
    r = compare(e, np.zeros(3), cov)
    assert r["consistent"], r["verdict"]
    assert "left out" in r["verdict"]
    assert max(d["nees"] for d in r["checks"]["left_out"]) > 10


def test_noise_the_theory_misses_in_an_empty_direction_is_kept_and_fails():
    """The same theory against samples with real variance in its empty direction (σ half
    the axes'): that direction is not negligible for the simulation, so it is kept,
    and the verdict is not consistent, although the main direction agrees."""
    rng = np.random.default_rng(8)
    cov, scale, v = _near_singular()
    n = 20_000
    e = rng.multivariate_normal(np.zeros(3), cov, n) + 0.5 * np.outer(rng.standard_normal(n), scale @ v)
    r = compare(e, np.zeros(3), cov)
    assert not r["consistent"] and not r["linear_model_ok"], r["verdict"]
    assert "left_out" not in r["checks"] or all(
        d["simulated_share"] < 0.02 for d in r["checks"]["left_out"])


def test_a_well_conditioned_prediction_leaves_nothing_out():
    """Nothing changes where the prediction is well conditioned (the checks and their
    keys are as before)."""
    rng = np.random.default_rng(0)
    cov = np.diag([1e-4, 4e-4, 1e-2])
    r = compare(rng.multivariate_normal([1, 2, 3], cov, 5000), [1, 2, 3], cov)
    assert r["verdict"] == "consistent" and "left_out" not in r["checks"]
    assert r["checks"]["rank"] == 3


def test_a_theory_with_a_third_of_the_lateral_slip_is_not_passed():
    """A review's reproducer: the fitted square's theory with a third of the simulation's
    lateral slip. At a 1 % share its two smallest directions (0.3-0.5 %, NEES 1.8 and 2.0)
    were left out and the verdict read "consistent"; now it fails, as it should."""
    from odomkit.propagate.predict import predict
    from odomkit.robot import DiffDrive

    bias = ParameterUncertainty(sigma_wheel_base=1.7e-3, sigma_scale_right=1.7e-3)
    theory = predict(SQUARE, (WheelNoise(0.0, 6.3e-4), LateralSlipNoise(1.3e-5), bias), robot=DiffDrive(0.2),
                     engine="recursion", partitions=50)
    r = monte_carlo(SQUARE, (WheelNoise(0.0, 6.3e-4), LateralSlipNoise(4e-5), bias), robot=DiffDrive(0.2),
                    runs=4000, partitions=50, seed=1, workers=1, theory=(theory.pose, theory.cov))
    assert not r["consistent"], r["verdict"]


def test_second_order_effects_the_runs_measure_are_reported_not_hidden():
    """The fitted square's noise: every σ agrees within 1.5 %, but the runs' mean lies about
    0.3 σ off the first-order prediction (a bias's second-order mean error, −L·δθ²/2), beyond
    the 0.25 σ tolerance, in directions holding 0.7 % of the variance: that is measured, so
    the verdict says it rather than leaving those directions out."""
    r = monte_carlo(SQUARE, FITTED, 0.2, runs=4000, partitions=100, seed=2)
    th, sim = np.asarray(r["theory"]["std"]), np.asarray(r["simulation"]["std"])
    assert np.all(np.abs(sim / th - 1) < 0.015)
    assert not r["consistent"] and "mean biased" in r["verdict"] and "left_out" not in r["checks"]
