"""Compass Monte Carlo (issue 10 item 2): one heading error per physical compass sample,
so the partitions are only the numerical resolution and do not change the statistics."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.cli import main
from odomkit.errors import ModelError
from odomkit.noise import CompassNoise, SpeedNoise
from odomkit.path import KellyArc
from odomkit.simulate import monte_carlo, simulate_runs

PATH = [KellyArc(0.5, 0.2, 4.0), KellyArc(0.5, 0.0, 2.0)]
NOISE = (SpeedNoise(1e-4), CompassNoise(1e-4))


def _combined_z(a: dict, b: dict, key: str) -> np.ndarray:
    """z of the difference of two independent simulations' figure ``key`` (std)."""
    diff = np.array(a["simulation"][key]) - np.array(b["simulation"][key])
    se = np.hypot(a["simulation"]["se"][key], b["simulation"]["se"][key])
    return diff / se


def test_statistics_do_not_depend_on_partitions():
    """The same path and noise with 10 and 100 partitions per segment (default compass
    period 0.1 s: 40 and 20 samples): the simulated σ of x, y, θ and the mean agree within
    4.5 standard errors of their difference. Drawing the heading error per partition
    made σθ grow as √K (by √10 here)."""
    coarse = monte_carlo(PATH, NOISE, runs=4000, partitions=10, seed=1)
    fine = monte_carlo(PATH, NOISE, runs=4000, partitions=100, seed=2)
    assert np.all(np.abs(_combined_z(coarse, fine, "std")) < 4.5)
    assert np.all(np.abs(_combined_z(coarse, fine, "mean")) < 4.5)
    for r in (coarse, fine):
        assert r["simulation"]["std"][2] == pytest.approx(math.sqrt(1e-4 / 0.1), rel=0.05)


@pytest.mark.parametrize("period", [0.1, 0.5])
def test_simulation_matches_the_sampled_prediction(period):
    """Against ``predict``'s sampled closed form (an independent implementation): all six
    σ and correlation figures within 4.5 standard errors, θ included."""
    r = monte_carlo(PATH, NOISE, runs=10_000, partitions=50, seed=3, compass_period=period,
                    cov0=[1e-4, 2e-4, 1.0])  # the compass reading replaces the θ variance
    z = np.array(r["z"]["std"] + list(r["z"]["corr"].values()))
    assert np.all(np.isfinite(z)) and np.all(np.abs(z) <= 4.5), z
    assert r["checks"]["components"] == ["x", "y", "theta"]
    assert r["linear_model_ok"], r["verdict"]
    assert r["theory"]["cov"][2][2] == pytest.approx(1e-4 / period, rel=1e-12)


def test_partitions_are_whole_steps_per_sample():
    """Each segment is cut into a whole number of steps per compass sample, at least
    ``partitions``; fewer partitions than samples are raised to one step per sample."""
    mc = simulate_runs(PATH, NOISE, runs=4, partitions=7, seed=0, compass_period=0.1)
    assert mc.partitions == 40  # 40 samples in the 4 s segment
    mc = simulate_runs(PATH, NOISE, runs=4, partitions=50, seed=0, compass_period=0.1)
    assert mc.partitions == 80  # 2 steps per sample in the first segment (20 × 3 in the second)


def test_zero_noise_ends_on_the_nominal_pose():
    mc = simulate_runs(PATH, (SpeedNoise(0.0), CompassNoise(0.0)), runs=3, partitions=13,
                       seed=0, pose0=(1.0, 2.0, 0.3))
    x = 1.0 + (0.5 / 0.2) * (math.sin(0.3 + 0.8) - math.sin(0.3)) + 1.0 * math.cos(1.1)
    y = 2.0 - (0.5 / 0.2) * (math.cos(0.3 + 0.8) - math.cos(0.3)) + 1.0 * math.sin(1.1)
    np.testing.assert_allclose(mc.final, [[x, y, 1.1]] * 3, rtol=0, atol=1e-12)


def test_period_must_divide_each_segment():
    with pytest.raises(ModelError, match="whole number of compass periods"):
        simulate_runs([KellyArc(0.5, 0.0, 0.25)], NOISE, runs=4, compass_period=0.1)


def test_cli_compass_period(capsys):
    args = ["simulate", "--model", "compass", "--speed-noise", "1e-4", "--heading-noise", "1e-4",
            "--segment", "arc:0.5,0.2,4", "--runs", "2000", "--partitions", "20",
            "--compass-period", "0.2", "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["theory"]["ros_pose_covariance"][35] == pytest.approx(1e-4 / 0.2, rel=1e-12)
    assert out["simulation"]["std"][2] == pytest.approx(math.sqrt(1e-4 / 0.2), rel=0.1)
    assert out["verdict"] != "" and out["linear_model_ok"]


@pytest.mark.parametrize("chunk", [1, 7, 64])
def test_partition_chunks_never_change_the_numbers(chunk):
    """Readings whose interval straddles a chunk boundary carry their errors across it:
    any chunk size gives the numbers of one chunk (to rounding of the summation order)."""
    from odomkit.simulate.blocks import run_block
    from odomkit.simulate.plan import make_plan

    plan = make_plan(PATH, NOISE, None, 100, (0.5, -1.0, 0.3), [1e-4, 1e-4, 0.0],
                     compass_period=0.1)
    assert plan.kind == "compass" and plan.partitions == 120  # q = 3 and 5 steps per reading
    whole, ends = run_block(plan, 11, 0, 50, "numpy", True, partition_chunk=1000)
    part, ends_c = run_block(plan, 11, 0, 50, "numpy", True, partition_chunk=chunk)
    np.testing.assert_allclose(part, whole, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ends_c, ends, rtol=0, atol=1e-12)
