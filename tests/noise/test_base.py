"""The noise-model protocol: every registered model answers the same questions, and the
answers agree with each other and with first principles.

For each model on a random log of its robot:
- its Q (``input_cov``, which models may compute their own way) equals J diag(var) Jᵀ
  built from its ``input_jacobian`` and ``input_variances`` (a second method);
- its Monte Carlo factor satisfies A Aᵀ = Q;
- the Jacobian matches central finite differences of the body motion in the raw inputs;
- zero noise gives zero covariance; Q is symmetric PSD;
- sampling the raw inputs and pushing them through the kinematics reproduces Q
  (Monte Carlo, tolerance from the sampling error).
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps, car_body_steps, diff_body_steps, tricycle_body_steps
from odomkit.noise import (
    NOISE_MODELS,
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    NoiseModel,
    NoiseSet,
    ParameterUncertainty,
    SpeedNoise,
    TricycleNoise,
    TurnNoise,
    WheelNoise,
    noise_fields,
)
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle

M = 40


def diff_log(rng) -> BodySteps:
    dl, dr = rng.uniform(-0.02, 0.05, M), rng.uniform(-0.02, 0.05, M)
    robot = DiffDrive(0.4)
    dd, dth = diff_body_steps(dl, dr, robot.effective_wheel_base)
    return BodySteps(dd, dth, np.full(M, 0.1), {"d_left": dl, "d_right": dr}, robot)


def tricycle_log(rng) -> BodySteps:
    s, a = rng.uniform(0.0, 0.05, M), rng.uniform(-0.5, 0.5, M)
    robot = Tricycle(0.68)
    dd, dth = tricycle_body_steps(s, a, robot.wheel_to_axle)
    return BodySteps(dd, dth, rng.uniform(0.05, 0.15, M), {"travel": s, "steer": a}, robot)


def gyro_log(rng) -> BodySteps:
    dt = rng.uniform(0.05, 0.15, M)
    rate = rng.uniform(-0.5, 0.5, M)
    return BodySteps(rng.uniform(0, 0.05, M), rate * dt, dt, {"yaw_rate": rate}, GyroOdometry())


def car_log(rng, at="rear") -> BodySteps:
    s, a = rng.uniform(-0.02, 0.05, M), rng.uniform(-0.5, 0.5, M)
    robot = Car(2.7, 0.8, at)
    dd, dth = car_body_steps(s, a, robot.wheel_base, robot.encoder_offset, robot.encoder_at)
    return BodySteps(dd, dth, rng.uniform(0.05, 0.15, M), {"travel": s, "steer": a}, robot)


def unicycle_log(rng) -> BodySteps:
    dt = rng.uniform(0.05, 0.15, M)
    rate = rng.uniform(-0.5, 0.5, M)
    return BodySteps(rng.uniform(-0.02, 0.05, M), rate * dt, dt, {"yaw_rate": rate}, Unicycle())


def compass_log(rng) -> BodySteps:
    dt = rng.uniform(0.05, 0.15, M)
    heading = np.cumsum(np.concatenate([[0.0], rng.uniform(-0.05, 0.05, M)]))
    return BodySteps(rng.uniform(0, 0.05, M), np.diff(heading), dt, {"heading": heading},
                     CompassOdometry())


# Each model on each robot it applies to, with the body motion as a function of the raw
# inputs (for the finite-difference and Monte Carlo checks): g(steps, u) -> (dd, dθ) of
# one step k with raw-input perturbation u added.
def _diff_motion(steps, k, u):
    dl, dr = steps.inputs["d_left"][k] + u[0], steps.inputs["d_right"][k] + u[1]
    return np.array(diff_body_steps(dl, dr, steps.robot.effective_wheel_base), dtype=float)


def _tricycle_motion(steps, k, u):
    t = steps.dt[k]
    v = steps.inputs["travel"][k] / t
    return np.array(tricycle_body_steps((v + u[0]) * (t + u[2]), steps.inputs["steer"][k] + u[1],
                                        steps.robot.wheel_to_axle), dtype=float)


def _car_motion(steps, k, u):
    t, robot = steps.dt[k], steps.robot
    v = steps.inputs["travel"][k] / t
    return np.array(car_body_steps((v + u[0]) * (t + u[2]), steps.inputs["steer"][k] + u[1],
                                   robot.wheel_base, robot.encoder_offset, robot.encoder_at), dtype=float)


def _additive(steps, k, u, rows):
    out = np.array([steps.dd[k], steps.dtheta[k]])
    for r, du in zip(rows, u, strict=True):
        out[r] += du
    return out


def _diff_params(steps, k, u):
    b = steps.robot.effective_wheel_base + u[0]
    dl = steps.inputs["d_left"][k] * (1 + u[1])
    dr = steps.inputs["d_right"][k] * (1 + u[2])
    return np.array(diff_body_steps(dl, dr, b), dtype=float)


def _tricycle_params(steps, k, u):
    s = steps.inputs["travel"][k] * (1 + u[1])
    return np.array(tricycle_body_steps(s, steps.inputs["steer"][k] + u[2],
                                        steps.robot.wheel_to_axle + u[0]), dtype=float)


def _car_params(steps, k, u):
    s, robot = steps.inputs["travel"][k] * (1 + u[1]), steps.robot
    return np.array(car_body_steps(s, steps.inputs["steer"][k] + u[2], robot.wheel_base + u[0],
                                   robot.encoder_offset, robot.encoder_at), dtype=float)


def _rate_params(steps, k, u):
    """(speed scale ε, yaw-rate offset δω [rad/s], yaw-rate scale ε_ω)."""
    rate = steps.dtheta[k] / steps.dt[k]
    return np.array([steps.dd[k] * (1 + u[0]), (rate * (1 + u[2]) + u[1]) * steps.dt[k]])


def _compass_params(steps, k, u):
    """(speed scale, heading offset): the offset moves both headings of the step alike."""
    heading = steps.inputs["heading"]
    return np.array([steps.dd[k] * (1 + u[0]), (heading[k + 1] + u[1]) - (heading[k] + u[1])])


CASES = [
    ("wheel", WheelNoise(0.01, 0.02), diff_log, _diff_motion),
    ("classical", ClassicalNoise(0.01, 0.02), diff_log, lambda s, k, u: _additive(s, k, u, (0, 1))),
    ("speed", SpeedNoise(1e-3), gyro_log, lambda s, k, u: _additive(s, k, u, (0,))),
    ("gyro", GyroNoise(1e-3), gyro_log, lambda s, k, u: _additive(s, k, u, (1,))),
    ("tricycle", TricycleNoise(0.01, 0.02, 0.003), tricycle_log, _tricycle_motion),
    ("car-rear", TricycleNoise(0.01, 0.02, 0.003), car_log, _car_motion),
    ("car-front", TricycleNoise(0.01, 0.02, 0.003), lambda rng: car_log(rng, "front"), _car_motion),
    ("speed-unicycle", SpeedNoise(1e-3), unicycle_log, lambda s, k, u: _additive(s, k, u, (0,))),
    ("gyro-unicycle", GyroNoise(1e-3), unicycle_log, lambda s, k, u: _additive(s, k, u, (1,))),
    # raw inputs (heading error, travel error) enter (Δθ, Δd)
    ("turn", TurnNoise(1e-3, 2e-4), gyro_log, lambda s, k, u: _additive(s, k, u, (1, 0))),
    ("turn-unicycle", TurnNoise(1e-3, 2e-4), unicycle_log, lambda s, k, u: _additive(s, k, u, (1, 0))),
    ("params-diff-white", ParameterUncertainty(0.01, 0.02, 0.03, mode="white"), diff_log,
     _diff_params),
    ("params-tricycle-white", ParameterUncertainty(0.01, 0.02, mode="white", sigma_steering_offset=0.01),
     tricycle_log, _tricycle_params),
    ("params-car-white", ParameterUncertainty(0.01, 0.02, mode="white", sigma_steering_offset=0.01),
     lambda rng: car_log(rng, "front"), _car_params),
    ("params-gyro-white", ParameterUncertainty(0, 0.02, mode="white", sigma_yaw_rate_offset=0.01,
                                               sigma_yaw_rate_scale=0.03), gyro_log, _rate_params),
    ("params-unicycle-white", ParameterUncertainty(0, 0.02, mode="white", sigma_yaw_rate_offset=0.01,
                                                   sigma_yaw_rate_scale=0.03), unicycle_log, _rate_params),
]


@pytest.mark.parametrize("name,model,make,motion", CASES, ids=[c[0] for c in CASES])
def test_input_cov_is_j_diag_var_jt_and_factor_squares_to_it(name, model, make, motion):
    steps = make(np.random.default_rng(1))
    q = model.input_cov(steps, 3, 30)
    jac = model.input_jacobian(steps, 3, 30)
    var = model.input_variances(steps, 3, 30)
    assert q.shape == (27, 2, 2) and jac.shape[:2] == (27, 2) and var.shape == (27, jac.shape[2])
    assert np.allclose(q, np.einsum("nik,nk,njk->nij", jac, var, jac), rtol=1e-12, atol=1e-20)
    # symmetric to rounding (J diag Jᵀ sums its products in different orders above and
    # below the diagonal); the engines symmetrise what they store
    assert np.allclose(q, np.swapaxes(q, 1, 2), rtol=1e-14, atol=0)
    assert np.all(np.linalg.eigvalsh(q) >= -1e-18)
    factor = model.input_factor(steps, 3, 30)
    assert np.allclose(np.einsum("nik,njk->nij", factor, factor), q, rtol=1e-12, atol=1e-20)


@pytest.mark.parametrize("name,model,make,motion", CASES, ids=[c[0] for c in CASES])
def test_jacobian_matches_finite_differences(name, model, make, motion, numeric_jacobian):
    steps = make(np.random.default_rng(2))
    jac = model.input_jacobian(steps, 0, M)
    for k in (0, 7, M - 1):
        r = jac.shape[2]
        fd = numeric_jacobian(lambda u, k=k: motion(steps, k, u), np.zeros(r), eps=1e-7)
        assert np.allclose(jac[k], fd, rtol=1e-6, atol=1e-9), (name, k)


@pytest.mark.parametrize("name,model,make,motion", CASES, ids=[c[0] for c in CASES])
def test_monte_carlo_of_raw_inputs_reproduces_q(name, model, make, motion):
    """Draw the raw inputs with their variances, push them through the exact body
    motion: the sample covariance matches Q within 5 standard errors (to first order;
    the noise is small so the nonlinearity is far below that)."""
    rng = np.random.default_rng(3)
    steps = make(rng)
    k = 5
    var = model.input_variances(steps, k, k + 1)[0]
    n = 20000
    u = rng.standard_normal((n, var.size)) * np.sqrt(var) * 1e-2  # scaled down: first order
    samples = np.array([motion(steps, k, ui) for ui in u])
    emp = np.cov(samples.T)
    q = model.input_cov(steps, k, k + 1)[0] * 1e-4
    # standard error of a sample covariance entry: sqrt((q_ii q_jj + q_ij²)/n)
    se = np.sqrt((np.outer(np.diag(q), np.diag(q)) + q**2) / n)
    assert np.all(np.abs(emp - q) <= 5 * se + 1e-12 * np.abs(q).max()), (emp, q)


@pytest.mark.parametrize("name,model,make,motion", CASES, ids=[c[0] for c in CASES])
def test_zero_noise_gives_zero_covariance(name, model, make, motion):
    steps = make(np.random.default_rng(4))
    zero = type(model)(**{f.name: (0.0 if not isinstance(getattr(model, f.name), str)
                                   else getattr(model, f.name)) for f in fields(model)})
    assert np.array_equal(zero.input_cov(steps, 0, M), np.zeros((M, 2, 2)))


BIAS_CASES = [
    (diff_log, ParameterUncertainty(0.01, 0.02, 0.03), _diff_params),
    (tricycle_log, ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.01), _tricycle_params),
    (car_log, ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.01), _car_params),
    (lambda rng: car_log(rng, "front"), ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.01),
     _car_params),
    (gyro_log, ParameterUncertainty(0, 0.02, sigma_yaw_rate_offset=0.01, sigma_yaw_rate_scale=0.03),
     _rate_params),
    (unicycle_log, ParameterUncertainty(0, 0.02, sigma_yaw_rate_offset=0.01, sigma_yaw_rate_scale=0.03),
     _rate_params),
    (compass_log, ParameterUncertainty(0, 0.02, sigma_heading_offset=0.01), _compass_params),
]


def test_bias_sensitivity_matches_finite_differences(numeric_jacobian):
    """K = ∂(Δd, Δθ)/∂β of every vehicle against finite differences of its body motion
    with the parameters perturbed."""
    for make, model, motion in BIAS_CASES:
        steps = make(np.random.default_rng(5))
        assert model.kind == "bias"
        jac = model.bias_jacobian(steps, 0, M)
        assert jac.shape[2] == model.bias_variances(steps.robot).size
        for k in (0, 11):
            fd = numeric_jacobian(lambda u, k=k, g=motion, s=steps: g(s, k, u), np.zeros(jac.shape[2]),
                                  eps=1e-7)
            assert np.allclose(jac[k], fd, rtol=1e-6, atol=1e-9)


def test_compass_noise_gives_heading_variances_and_no_input_covariance():
    steps = compass_log(np.random.default_rng(6))
    model = CompassNoise(1e-3)
    assert model.input_cov(steps, 0, M).shape == (M, 2, 2)
    assert not model.input_cov(steps, 0, M).any()
    var = model.heading_variances(steps)
    # Kelly: a compass of density psd averaged over Δt has variance psd/Δt
    spacing = np.concatenate([[steps.dt[0]], 0.5 * (steps.dt[:-1] + steps.dt[1:]), [steps.dt[-1]]])
    assert np.allclose(var, 1e-3 / spacing, rtol=1e-14)


def test_models_check_their_robot():
    tri = tricycle_log(np.random.default_rng(7))
    with pytest.raises(ModelError, match="WheelNoise applies to a DiffDrive robot, not a Tricycle"):
        WheelNoise(0.1, 0.1).check_robot(tri.robot)
    with pytest.raises(ModelError, match="CompassNoise"):
        CompassNoise(0.1).check_robot(DiffDrive(0.4))
    with pytest.raises(ModelError, match="GyroNoise"):
        GyroNoise(0.1).check_robot(CompassOdometry())
    with pytest.raises(ModelError, match="sigma_scale_right"):
        ParameterUncertainty(sigma_scale_right=0.1).check_robot(tri.robot)
    with pytest.raises(ModelError, match="sigma_heading_offset does not apply to a GyroOdometry"):
        ParameterUncertainty(sigma_heading_offset=0.1).check_robot(GyroOdometry())
    with pytest.raises(ModelError, match="bias only"):
        ParameterUncertainty(sigma_heading_offset=0.1, mode="white").check_robot(CompassOdometry())
    with pytest.raises(ModelError, match="TricycleNoise applies to a Tricycle or Car robot"):
        TricycleNoise(0.1, 0.1).check_robot(Unicycle())
    for robot, why in ((DiffDrive(0.4), "per-wheel noise"), (tri.robot, "steering noise"),
                       (Car(2.7), "steering noise"), (CompassOdometry(), "measures its heading")):
        with pytest.raises(ModelError, match=f"TurnNoise applies to a GyroOdometry or Unicycle robot, "
                                             f"not a {type(robot).__name__}; .*{why}"):
            TurnNoise(0.1).check_robot(robot)
    TurnNoise(0.1).check_robot(Unicycle())
    TurnNoise(0.1).check_robot(GyroOdometry())
    ClassicalNoise(0.1, 0.1).check_robot(tri.robot)  # the classical model fits any robot


def test_noise_set_validation_and_sums():
    steps = gyro_log(np.random.default_rng(8))
    with pytest.raises(ModelError, match="given twice"):
        NoiseSet((SpeedNoise(1.0), SpeedNoise(2.0)))
    with pytest.raises(ModelError, match="cannot be combined"):
        NoiseSet((ClassicalNoise(1.0, 1.0), SpeedNoise(1.0)))
    with pytest.raises(ModelError, match="not an odomkit noise model"):
        NoiseSet.of((SpeedNoise(1.0), "k=0.1"))  # type: ignore[arg-type]
    both = NoiseSet.of((SpeedNoise(1e-3), GyroNoise(1e-4), None))
    q = both.input_cov(steps, 0, M)
    assert np.allclose(q, SpeedNoise(1e-3).input_cov(steps, 0, M) + GyroNoise(1e-4).input_cov(steps, 0, M))
    assert both.family == "gyro" and both.get(GyroNoise) == GyroNoise(1e-4)
    assert both.get(WheelNoise) is None
    factor = both.input_factor(steps, 0, M)
    assert np.allclose(factor @ np.swapaxes(factor, 1, 2), q, rtol=1e-12, atol=1e-20)


def test_three_raw_inputs_get_a_cholesky_factor():
    steps = tricycle_log(np.random.default_rng(9))
    noise = NoiseSet.of(TricycleNoise(0.01, 0.02, 0.003))
    factor = noise.input_factor(steps, 0, M)
    assert factor.shape == (M, 2, 2) and np.all(factor[:, 0, 1] == 0.0)
    assert np.allclose(factor @ np.swapaxes(factor, 1, 2), noise.input_cov(steps, 0, M),
                       rtol=1e-10, atol=1e-20)


def test_bad_parameters_are_rejected():
    for bad in (-1.0, float("nan"), float("inf"), True):
        with pytest.raises(ModelError, match="k_left"):
            WheelNoise(bad, 0.1)  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="mode"):
        ParameterUncertainty(mode="pink")  # type: ignore[arg-type]


def test_registry_knows_every_model_with_its_robot_file_keys():
    assert set(NOISE_MODELS) == {"WheelNoise", "ClassicalNoise", "SpeedNoise", "GyroNoise",
                                 "CompassNoise", "TricycleNoise", "ParameterUncertainty",
                                 "LateralSlipNoise", "TurnNoise"}
    assert all(issubclass(cls, NoiseModel) for cls in NOISE_MODELS.values())
    assert noise_fields(TricycleNoise) == (frozenset({"sigma_speed", "sigma_steer"}),
                                           frozenset({"sigma_dt"}))
    assert noise_fields(WheelNoise)[0] == {"k_left", "k_right"}
