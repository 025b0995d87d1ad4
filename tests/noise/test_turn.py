"""TurnNoise (:mod:`odomkit.noise.turn`): white heading and travel errors whose variances
grow with the heading change of each step, α_turn·|Δθ| and α_turn_travel·|Δθ|.

Per-step values by hand, the robots it applies to, and the robot file (read, written,
documented in the example). The protocol checks every model passes (J diag(var) Jᵀ,
finite differences, a Monte Carlo of its raw inputs, zero noise) run on it in
test_base.py; the engines' covariance in tests/propagate/test_turn_noise.py.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from odomkit.calibrate.fit_noise import DEFAULT_WHITE, models_to_fit
from odomkit.errors import InputError, ModelError
from odomkit.io.robotfile import read_robot, write_robot
from odomkit.kinematics import BodySteps
from odomkit.noise import GyroNoise, NoiseSet, SpeedNoise, TurnNoise
from odomkit.noise.base import variance_power
from odomkit.robot import GyroOdometry, Unicycle

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _steps(robot=None):
    """Four steps: straight, a left turn, a right turn backwards, a standing base."""
    dd = np.array([0.05, 0.03, -0.02, 0.0])
    dth = np.array([0.0, 0.2, -0.4, 0.0])
    dt = np.full(4, 0.1)
    return BodySteps(dd, dth, dt, {"yaw_rate": dth / dt}, robot or Unicycle())


def test_variances_are_alpha_times_the_turn_of_each_step_by_hand():
    model = TurnNoise(alpha_turn=0.01, alpha_turn_travel=0.003)
    steps = _steps()
    var = model.input_variances(steps, 0, 4)
    # (heading, travel): α_turn·|Δθ|, α_turn_travel·|Δθ|; a turn either way counts alike
    np.testing.assert_allclose(var, [[0.0, 0.0], [0.002, 0.0006], [0.004, 0.0012], [0.0, 0.0]],
                               rtol=1e-14, atol=0)
    q = model.input_cov(steps, 1, 3)
    np.testing.assert_allclose(q, [[[0.0006, 0.0], [0.0, 0.002]], [[0.0012, 0.0], [0.0, 0.004]]],
                               rtol=1e-14, atol=0)
    # partition invariance of one step: the turn of step 2 cut in two gathers the same
    half = BodySteps(np.full(2, -0.01), np.full(2, -0.2), np.full(2, 0.05),
                     {"yaw_rate": np.full(2, -4.0)}, Unicycle())
    np.testing.assert_allclose(model.input_cov(half, 0, 2).sum(axis=0), q[1], rtol=1e-14)


def test_each_term_alone_and_zero_defaults():
    steps = _steps(GyroOdometry())
    heading = TurnNoise(alpha_turn=0.01).input_cov(steps, 0, 4)
    travel = TurnNoise(alpha_turn_travel=0.003).input_cov(steps, 0, 4)
    assert not heading[:, 0].any() and not heading[:, :, 0].any()
    assert not travel[:, 1].any() and not travel[:, :, 1].any()
    np.testing.assert_array_equal(TurnNoise(0.01, 0.003).input_cov(steps, 0, 4), heading + travel)
    assert TurnNoise() == TurnNoise(0.0, 0.0)
    assert not TurnNoise().input_cov(steps, 0, 4).any()


def test_a_straight_drive_gathers_nothing():
    dd = np.full(50, 0.02)
    steps = BodySteps(dd, np.zeros(50), np.full(50, 0.1), {"yaw_rate": np.zeros(50)}, Unicycle())
    assert not TurnNoise(1.0, 1.0).input_cov(steps, 0, 50).any()
    assert not TurnNoise(1.0, 1.0).input_factor(steps, 0, 50).any()
    # beside another model, it adds nothing to its Q
    both = NoiseSet.of((SpeedNoise(1e-3), GyroNoise(1e-4), TurnNoise(1.0, 1.0)))
    alone = NoiseSet.of((SpeedNoise(1e-3), GyroNoise(1e-4)))
    np.testing.assert_array_equal(both.input_cov(steps, 0, 50), alone.input_cov(steps, 0, 50))


def test_fields_are_variances_per_radian_and_validated():
    assert [variance_power(n) for n in ("alpha_turn", "alpha_turn_travel")] == [1, 1]
    assert TurnNoise(0.01, 0.003).variance_parameters(Unicycle()) == {"alpha_turn": 0.01,
                                                                      "alpha_turn_travel": 0.003}
    assert TurnNoise().from_variances({"alpha_turn_travel": 0.2}) == TurnNoise(0.0, 0.2)
    for bad in (-1e-3, float("nan"), float("inf")):
        with pytest.raises(ModelError, match="alpha_turn"):
            TurnNoise(alpha_turn=bad)
        with pytest.raises(ModelError, match="alpha_turn_travel"):
            TurnNoise(alpha_turn_travel=bad)
    assert TurnNoise.family == "gyro" and TurnNoise().kind == "white"


def test_robot_file_round_trip_and_either_key_alone(tmp_path):
    noise = (SpeedNoise(1e-3), GyroNoise(2e-5), TurnNoise(4e-3, 7e-4))
    path = write_robot(tmp_path / "r.toml", Unicycle(), noise)
    text = path.read_text()
    assert "alpha_turn = 0.004" in text and "alpha_turn_travel = 0.0007" in text
    robot, back = read_robot(path)
    assert robot == Unicycle() and NoiseSet.of(back).get(TurnNoise) == TurnNoise(4e-3, 7e-4)
    assert set(back) == set(noise)
    # either key names the model; the other is zero
    for key, expected in (("alpha_turn", TurnNoise(0.02, 0.0)), ("alpha_turn_travel", TurnNoise(0.0, 0.02))):
        one = tmp_path / f"{key}.toml"
        one.write_text(f'[robot]\ntype = "gyro"\n[noise]\n{key} = 0.02\n')
        assert read_robot(one)[1] == (expected,)
    bad = tmp_path / "bad.toml"
    bad.write_text('[robot]\ntype = "unicycle"\n[noise]\nalpha_turn = -0.1\n')
    with pytest.raises((InputError, ModelError), match="alpha_turn"):
        read_robot(bad)


def test_the_example_unicycle_names_the_default_white_set():
    """A user who copies examples/unicycle.toml fits fit-noise's default white models."""
    robot, noise = read_robot(EXAMPLES / "unicycle.toml")
    white = [type(m).__name__ for m in noise if m.kind == "white"]
    assert set(white) == set(DEFAULT_WHITE["unicycle"])
    assert "TurnNoise" in DEFAULT_WHITE["unicycle"]
    models, _ = models_to_fit(robot, (), ("white",))
    assert {type(m).__name__ for m in models} == set(DEFAULT_WHITE["unicycle"])
    # A gyro's measured turn grows with its own noise and the sample rate: not its default.
    others = ("diff", "tricycle", "car", "gyro", "compass")
    assert not any("TurnNoise" in DEFAULT_WHITE[kind] for kind in others)
