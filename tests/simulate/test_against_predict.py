"""The simulator against the other engine: ``odomkit.propagate.predict`` (closed forms).

Both implement the same noise models independently (closed-form integrals vs per-partition
random draws), so agreement checks both. Small noise, so the first-order prediction must
hold: every std and correlation within 4.5 Monte Carlo standard errors (6 figures × 4
models: a false alarm has probability < 24 · 7e-6), and the verdict at worst "consistent
to first order" (10⁴ runs may detect second-order mean bias).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, WheelNoise
from odomkit.path import Arc, KellyArc, Spin, Straight
from odomkit.simulate import monte_carlo

CASES = {
    "wheel": ([Arc(3, 1), Straight(2), Spin(1.0), Arc(-1, 2)], WheelNoise(0.002, 0.003), 0.4,
              dict(cov0=[1e-4, 1e-4, 1e-4], pose0=(1.0, 2.0, 0.5))),
    "classical": ([Arc(3, 1), Straight(2)], ClassicalNoise(0.001, 0.0005), 0.4, {}),
    "gyro": ([KellyArc(0.5, 0.1, 20), KellyArc(0.5, 0.0, 10)],
             (SpeedNoise(1e-4), GyroNoise(1e-6)), None, dict(cov0=[1e-4, 0, 1e-6])),
    "compass": ([KellyArc(0.5, 0.1, 20), KellyArc(0.5, 0.0, 10)],
                (SpeedNoise(1e-4), CompassNoise(1e-6)), None, {}),
}


@pytest.mark.parametrize("model", list(CASES))
def test_simulation_agrees_with_closed_form_prediction(model):
    path, noise, wheel_base, kw = CASES[model]
    # The classical model's covariance depends on the step count: monte_carlo predicts
    # it for the same K steps per segment as it simulates.
    r = monte_carlo(path, noise, wheel_base, runs=10_000, partitions=200, seed=31, **kw)
    z = np.array(r["z"]["std"] + list(r["z"]["corr"].values()), dtype=float)
    known = z[np.isfinite(z)]
    assert known.size == 6
    assert np.all(np.abs(known) <= 4.5), z
    assert r["linear_model_ok"], r["verdict"]
    # predict's pose is the nominal end pose: the simulated mean is within sampling error
    # (4.5 SE) plus the second-order bias, which at this noise is below 0.05 σ
    sigma = np.array(r["theory"]["std"], dtype=float)
    err = np.array(r["simulation"]["mean_error"])
    ok = np.isfinite(sigma)
    assert np.all(np.abs(err[ok]) <= (4.5 / math.sqrt(r["runs"]) + 0.05) * sigma[ok])
