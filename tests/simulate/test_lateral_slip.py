"""Monte Carlo of the lateral slip (:class:`odomkit.noise.LateralSlipNoise`): each run moves
every partition across its own chord by a fresh ε ~ N(0, α_lat·|Δd|), and the spread of
the end poses must match the engines' propagated covariance.

Tolerance from the sampling error: a sample covariance entry of n runs has standard error
√((c_ii c_jj + c_ij²)/n); every entry must lie within 5 of them (a false alarm per entry
has probability below 6e-7). With the slip alone the end pose is linear in the draws (the
heading is noise free), so no second-order slack is needed; with heading noise too, 2 % of
the largest entry covers the terms the first-order prediction leaves out. Both kernels
(numba and numpy) are checked, and the seeding: same seed, same numbers whatever the
chunking, and without a slip (or with a zero one) the numbers of before.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    LateralSlipNoise,
    ParameterUncertainty,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)
from odomkit.path import Arc, KellyArc, SteerArc, Straight
from odomkit.propagate.predict import predict
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry
from odomkit.simulate import _kernels
from odomkit.simulate.blocks import run_block
from odomkit.simulate.engine import simulate_runs
from odomkit.simulate.plan import make_plan

RUNS, PARTITIONS = 4000, 40
DIFF_PATH = [Arc(3.0, 2.0), Straight(2.0), Arc(1.0, 2.5)]
KELLY_PATH = [KellyArc(1.0, 0.2, 6.0), KellyArc(1.0, 0.0, 4.0), KellyArc(0.8, -0.3, 5.0)]
STEER_PATH = [SteerArc(2.0, 0.12, 5.0), SteerArc(2.0, 0.0, 3.0), SteerArc(1.5, -0.2, 4.0)]
SLIP = LateralSlipNoise(2e-3)

# (name, robot, path, noise, second-order slack)
CASES = [
    ("diff-slip-only", DiffDrive(0.4), DIFF_PATH, (SLIP,), 0.0),
    ("diff-slip+wheel", DiffDrive(0.4), DIFF_PATH, (WheelNoise(0.02, 0.03), SLIP), 0.02),
    ("diff-slip+wheel+bias", DiffDrive(0.4), DIFF_PATH,
     (WheelNoise(0.02, 0.03), SLIP, ParameterUncertainty(sigma_wheel_base=0.002)), 0.02),
    ("classical-slip", DiffDrive(0.4), DIFF_PATH, (ClassicalNoise(0.002, 0.002), SLIP), 0.02),
    ("gyro-slip+gyro", GyroOdometry(), KELLY_PATH, (SpeedNoise(1e-3), GyroNoise(1e-4), SLIP), 0.02),
    ("compass-slip-only", CompassOdometry(), KELLY_PATH, (SLIP,), 0.0),
    ("compass-slip+compass", CompassOdometry(), KELLY_PATH, (SpeedNoise(1e-3), CompassNoise(1e-5), SLIP),
     0.02),
    ("car-slip+steering", Car(2.7, 0.8), STEER_PATH, (TricycleNoise(0.02, 0.004), SLIP), 0.02),
]


def _check(final, c, slack, name):
    cov = np.cov(final.T)
    se = np.sqrt((np.outer(np.diag(c), np.diag(c)) + c**2) / final.shape[0])
    # (1e-20: the rounding of a spread that is nil, the heading's with the slip alone)
    assert np.all(np.abs(cov - c) <= 5 * se + slack * np.abs(c).max() + 1e-20), (name, cov, c)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_monte_carlo_confirms_the_propagated_covariance(case):
    name, robot, path, noise, slack = case
    # per-sample noise (a TricycleNoise) needs its sample period: 10 Hz
    per = {"sample_period": 0.1} if any(m.per_sample for m in noise) else {}
    theory = predict(path, noise, robot=robot, engine="recursion", partitions=PARTITIONS, **per)
    engines = ["numpy"] + (["numba"] if _kernels.have_numba() else [])
    for engine in engines:
        mc = simulate_runs(path, noise, robot=robot, runs=RUNS, partitions=PARTITIONS, seed=17,
                           engine=engine, workers=1, **per)
        _check(mc.final, theory.cov, slack, (name, mc.engine))
        if slack == 0.0 and not isinstance(robot, CompassOdometry):
            # the slip moves the position alone: every run keeps the nominal heading
            assert np.ptp(mc.final[:, 2]) < 1e-12


def test_the_slip_is_across_the_track():
    """A straight line along x: the slip spreads y only, var y = α·D."""
    mc = simulate_runs([Straight(5.0)], (SLIP,), robot=DiffDrive(0.4), runs=RUNS, partitions=50, seed=3,
                       engine="numpy", workers=1)
    assert np.ptp(mc.final[:, 0]) < 1e-12
    var_y = np.var(mc.final[:, 1], ddof=1)
    assert abs(var_y - 2e-3 * 5.0) < 5 * 2e-3 * 5.0 * np.sqrt(2 / RUNS)


@pytest.mark.skipif(not _kernels.have_numba(), reason="needs numba")
def test_numba_and_numpy_kernels_agree():
    noise = (WheelNoise(0.02, 0.03), SLIP)
    a = simulate_runs(DIFF_PATH, noise, 0.4, runs=300, partitions=70, seed=5, engine="numba", workers=1)
    b = simulate_runs(DIFF_PATH, noise, 0.4, runs=300, partitions=70, seed=5, engine="numpy", workers=1)
    np.testing.assert_allclose(a.final, b.final, rtol=0, atol=1e-12)


@pytest.mark.parametrize("engine", ["numpy", "numba"])
def test_seed_gives_the_same_numbers_whatever_the_chunking(engine):
    if engine == "numba" and not _kernels.have_numba():
        pytest.skip("needs numba")
    noise = (WheelNoise(0.02, 0.03), SLIP)
    ref = simulate_runs(DIFF_PATH, noise, 0.4, runs=600, partitions=30, seed=9, engine=engine, workers=1)
    other = simulate_runs(DIFF_PATH, noise, 0.4, runs=600, partitions=30, seed=9, engine=engine, workers=2,
                          chunk_runs=256)
    assert np.array_equal(ref.final, other.final)
    plan = make_plan(DIFF_PATH, noise, 0.4, 30)
    whole, _ = run_block(plan, 9, 1, 100, engine, False)
    pieces, _ = run_block(plan, 9, 1, 100, engine, False, partition_chunk=7)
    # the same draws: the numba kernel gives the same bits, the numpy one sums each
    # stretch of partitions apart (equal to rounding, as without the slip)
    np.testing.assert_allclose(pieces, whole, rtol=0, atol=0 if engine == "numba" else 1e-13)


@pytest.mark.parametrize("name,robot,path,noise", [
    ("diff", DiffDrive(0.4), DIFF_PATH, (WheelNoise(0.02, 0.03),)),
    ("classical", DiffDrive(0.4), DIFF_PATH, (ClassicalNoise(0.002, 0.002),)),
    ("compass", CompassOdometry(), KELLY_PATH, (SpeedNoise(1e-3), CompassNoise(1e-5))),
], ids=["diff", "classical", "compass"])
def test_zero_slip_draws_as_without(name, robot, path, noise):
    for engine in ("numpy", "numba") if _kernels.have_numba() else ("numpy",):
        ref = simulate_runs(path, noise, robot=robot, runs=300, partitions=20, seed=4, engine=engine)
        zero = simulate_runs(path, noise + (LateralSlipNoise(0.0),), robot=robot, runs=300, partitions=20,
                             seed=4, engine=engine)
        assert np.array_equal(ref.final, zero.final)
    assert make_plan(path, noise + (LateralSlipNoise(0.0),), None, 20, robot=robot).lateral is None


def test_simulate_command_takes_the_lateral_noise_flag(capsys):
    import json

    from odomkit.cli import main

    args = ["simulate", "--wheel-base", "0.4", "--k-left", "0.01", "--k-right", "0.01", "--segment",
            "arc:3,2", "--segment", "straight:2", "--runs", "4000", "--partitions", "40", "--seed", "2",
            "--json"]
    assert main([*args, "--lateral-noise", "2e-3"]) == 0
    out = json.loads(capsys.readouterr().out)
    theory = predict([Arc(3.0, 2.0), Straight(2.0)], (WheelNoise(0.01, 0.01), SLIP), 0.4)
    np.testing.assert_allclose(out["theory"]["cov"], theory.cov, rtol=1e-12, atol=0)
    # the runs' spread confirms it (the command's Box M test and the NEES)
    assert out["checks"]["cov"]["ok"] and out["checks"]["nees"]["ok"]
    assert main([*args, "--lateral-noise", "nan"]) == 2
