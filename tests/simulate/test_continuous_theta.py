"""Issue 10 item 1: the Monte Carlo statistics use continuous θ (DESIGN: θ is continuous
inside and in every statistic; wrapped only for display)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.noise import WheelNoise
from odomkit.path import Arc, Spin
from odomkit.simulate import compare, monte_carlo


def test_chong_kleeman_table7_theta_spread_is_not_wrapped():
    """Table 7 (arc L = 15 m, R = 10 m, B = 0.4 m, k_L = k_R = 0.5 m^½): θ = (R − L)/B is
    linear in the wheel noise, so its σ is exactly √(k²(L + R))/B = 6.25 rad at any noise
    level; the paper's simulation gives 6.206 rad (10⁴ runs). Wrapping θ errors to
    [−π, π) squeezed the simulated σθ to 1.82 rad. 4000 runs: SE of σ = 6.25/√8000 = 0.07."""
    r = monte_carlo([Arc(15, 10)], WheelNoise(0.5, 0.5), 0.4, runs=4000, partitions=20, seed=5)
    sigma = r["simulation"]["std"][2]
    theory = math.sqrt(0.25 * 25) / 0.4
    assert r["theory"]["std"][2] == pytest.approx(theory, rel=1e-12)
    se = theory / math.sqrt(2 * (r["runs"] - 1))
    assert abs(sigma - theory) < 4 * se, sigma
    # against the paper's simulated 6.206 (its own SE from 10⁴ runs: 0.044)
    assert abs(sigma - 6.206) < 4 * math.hypot(se, 6.206 / math.sqrt(2e4)), sigma
    # σ is also the spread of the simulated means' θ: no run was moved by 2π
    assert r["simulation"]["mean"][2] == pytest.approx(-12.5, abs=4 * theory / math.sqrt(4000))


def test_exactly_linear_spin_is_consistent():
    """A spin on the spot with a large initial heading variance (σθ = 2 rad) and no wheel
    noise is exactly linear: the end pose is the start pose turned by 1 rad. Wrapping
    declared it 'linear model breaks down'."""
    r = monte_carlo([Spin(1.0)], WheelNoise(0.0, 0.0), 0.4, runs=4000, partitions=10, seed=2,
                    cov0=[1e-4, 1e-4, 4.0])
    assert r["verdict"] == "consistent", r["verdict"]
    assert r["simulation"]["std"][2] == pytest.approx(2.0, rel=4 / math.sqrt(8000))


def test_simulated_mean_theta_is_continuous():
    """Arc(3, 1) turns by −5 rad: the theory's pose is displayed wrapped (1.283 rad), the
    simulated mean is the continuous −5 rad (DESIGN: simulation.mean with θ continuous)."""
    r = monte_carlo([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=500, partitions=20, seed=1)
    assert r["theory"]["pose"][2] == pytest.approx(-5.0 + 2 * math.pi, abs=1e-12)
    assert r["simulation"]["mean"][2] == pytest.approx(-5.0, abs=1e-3)
    assert r["simulation"]["mean_error"][2] == pytest.approx(0.0, abs=1e-3)


def test_a_full_turn_counts():
    """A run that ends a full turn away from the predicted heading is 2π off (continuous
    θ), not on target."""
    rng = np.random.default_rng(0)
    cov = np.diag([1e-4, 1e-4, 1e-2])
    final = rng.multivariate_normal([1.0, 2.0, 3.0], cov, 2000)
    assert compare(final, [1.0, 2.0, 3.0], cov)["verdict"] == "consistent"
    final[:, 2] += 2 * np.pi
    s = compare(final, [1.0, 2.0, 3.0], cov)
    assert s["simulation"]["mean_error"][2] == pytest.approx(2 * np.pi, abs=0.01)
    assert s["verdict"].startswith("linear model breaks down")


def test_user_theory_heading_is_taken_on_the_simulated_branch():
    """A theory given with a wrapped heading (here 1.283 rad for the −5 rad turn of
    Arc(3, 1)) is read on the branch of the nominal continuous end heading."""
    r0 = monte_carlo([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=500, partitions=20, seed=1)
    pose = np.array(r0["theory"]["pose"])
    assert pose[2] == pytest.approx(-5.0 + 2 * math.pi)
    r = monte_carlo([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=500, partitions=20, seed=1,
                    theory=(pose, r0["theory"]["cov"]))
    assert r["verdict"] == r0["verdict"]
    assert r["simulation"]["mean"][2] == pytest.approx(-5.0, abs=1e-3)
