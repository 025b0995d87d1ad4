"""TurnNoise in every engine: the log engines (recursion, transition) against an
independent Monte Carlo of a log that turns both ways, spins in place, stands and drives
straight; partition invariance (10 Hz and 100 Hz logs of one drive); the planned-path
closed form against the log engines, against Kelly's speed + gyro closed form it equals
on an arc, and against quadrature on a spin in place; the project's Monte Carlo
(``simulate_runs``) against the prediction; and the ``predict``/``simulate`` flags.

Monte Carlo tolerances come from the sampling error of a covariance estimate: entry
(i, j) of a sample covariance of n draws has standard error √((P_ii P_jj + P_ij²)/n).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, body_steps
from odomkit.log import OdometryLog
from odomkit.noise import GyroNoise, LateralSlipNoise, ParameterUncertainty, SpeedNoise, TurnNoise
from odomkit.path import KellyArc
from odomkit.propagate.closed_kelly import gyro_arc_cov
from odomkit.propagate.predict import predict
from odomkit.propagate.recursion import track_covariance
from odomkit.robot import GyroOdometry, Unicycle
from odomkit.simulate import simulate_runs

# Straight, a left arc, a spin in place to the right, standing, a right arc, straight.
DRIVE = [KellyArc(0.4, 0.0, 1.0), KellyArc(0.3, 0.8, 2.0), KellyArc(0.0, -1.2, 1.0),
         KellyArc(0.0, 0.0, 0.5), KellyArc(0.35, -0.5, 2.0), KellyArc(0.4, 0.0, 1.0)]
TURN = TurnNoise(alpha_turn=5e-4, alpha_turn_travel=2e-4)
PU = ParameterUncertainty(sigma_scale_left=0.01, sigma_yaw_rate_offset=0.005, sigma_yaw_rate_scale=0.02)
SETS = {
    "turn": (TURN,),
    "turn+speed+gyro": (SpeedNoise(3e-4), GyroNoise(2e-4), TURN),
    "turn+bias": (TURN, PU),
    "all": (SpeedNoise(3e-4), GyroNoise(2e-4), TURN, PU),
}


def drive_log(segments, rate, robot=None):
    """The body steps of a unicycle log at ``rate`` Hz whose rows hold each segment's
    speed and yaw rate (through the log reader's kinematics)."""
    counts = [round(seg.duration * rate) for seg in segments]
    speed = np.repeat([seg.speed for seg in segments], counts)
    yaw = np.repeat([seg.yaw_rate for seg in segments], counts)
    t = np.arange(speed.size + 1) / rate
    log = OdometryLog(t, {"speed": np.append(speed, 0.0), "yaw_rate": np.append(yaw, 0.0)})
    return body_steps(robot or Unicycle(), log)


def log_cov(steps, noise, engine="recursion"):
    poses = dead_reckon(steps.dd, steps.dtheta)
    return track_covariance(steps, poses, noise, np.zeros((3, 3)), "exact", engine)


def monte_carlo_log(steps, noise, runs, seed):
    """Independent Monte Carlo of a log from the models' definitions: every step's
    (Δd, Δθ) gets its own draws (speed α_ss|Δd|; gyro σ_gg·Δt over steps that move; turn
    α_turn|Δθ| on Δθ and α_turn_travel|Δθ| on Δd), every run one draw of the speed scale,
    yaw-rate offset and yaw-rate scale; the exact arc by hand. Poses after each step,
    (runs, M + 1, 3)."""
    rng = np.random.default_rng(seed)
    dd, dth, dt = steps.dd, steps.dtheta, steps.dt
    n = dd.size
    moving = (dd != 0) | (steps.inputs["yaw_rate"] != 0)
    d = np.broadcast_to(dd, (runs, n)).copy()
    a = np.broadcast_to(dth, (runs, n)).copy()
    for model in noise:
        if isinstance(model, SpeedNoise):
            d += rng.standard_normal((runs, n)) * np.sqrt(model.alpha_ss * np.abs(dd))
        elif isinstance(model, GyroNoise):
            a += rng.standard_normal((runs, n)) * np.sqrt(model.psd_gyro * dt * moving)
        elif isinstance(model, TurnNoise):
            a += rng.standard_normal((runs, n)) * np.sqrt(model.alpha_turn * np.abs(dth))
            d += rng.standard_normal((runs, n)) * np.sqrt(model.alpha_turn_travel * np.abs(dth))
        elif isinstance(model, ParameterUncertainty):
            sigma = [model.sigma_scale_left, model.sigma_yaw_rate_offset, model.sigma_yaw_rate_scale]
            scale, offset, rate_scale = rng.standard_normal((3, runs, 1)) * np.array(sigma)[:, None, None]
            d += dd * scale
            a += dth * rate_scale + offset * dt * moving
        else:
            raise AssertionError(model)
    theta = np.concatenate([np.zeros((runs, 1)), np.cumsum(a, axis=1)], axis=1)
    chord = d * np.sinc(a / (2 * np.pi))  # numpy's sinc(x) = sin(πx)/(πx): sin(a/2)/(a/2)
    mid = theta[:, :-1] + a / 2
    poses = np.zeros((runs, n + 1, 3))
    poses[:, 1:, 0] = np.cumsum(chord * np.cos(mid), axis=1)
    poses[:, 1:, 1] = np.cumsum(chord * np.sin(mid), axis=1)
    poses[:, :, 2] = theta
    return poses


def assert_cov_within_sampling_error(samples, cov, n_se=5.0, what=""):
    emp = np.cov(samples.T)
    se = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / samples.shape[0])
    assert np.all(np.abs(emp - cov) <= n_se * se), (what, emp, cov, (emp - cov) / se)


@pytest.mark.parametrize("name", list(SETS))
def test_log_engines_match_a_monte_carlo_of_the_log(name):
    """On a log turning both ways, spinning in place, standing and driving straight, the
    recursion's and transition's covariance after the spin and at the end match 40 000
    simulated runs within 5 standard errors of each entry."""
    noise = SETS[name]
    steps = drive_log(DRIVE, 10.0)
    cov = log_cov(steps, noise)
    np.testing.assert_allclose(log_cov(steps, noise, "transition"), cov, rtol=1e-9, atol=1e-15)
    runs = monte_carlo_log(steps, noise, 40_000, seed=7)
    for row in (40, len(steps)):  # after the spin, and the end
        assert_cov_within_sampling_error(runs[:, row], cov[row], what=(name, row))


def test_a_gyro_robot_takes_it_alike():
    """A gyro robot's steps (its Δθ the integrated yaw rate) gather the same turn noise."""
    uni = drive_log(DRIVE, 10.0)
    gyro = BodySteps(uni.dd, uni.dtheta, uni.dt, {"yaw_rate": uni.inputs["yaw_rate"]}, GyroOdometry())
    np.testing.assert_allclose(log_cov(gyro, (TURN,)), log_cov(uni, (TURN,)), rtol=1e-13, atol=1e-18)
    runs = monte_carlo_log(gyro, (TURN,), 40_000, seed=8)
    assert_cov_within_sampling_error(runs[:, -1], log_cov(gyro, (TURN,))[-1], what="gyro")


def test_partition_invariance_10_and_100_hz_give_the_same_covariance():
    """The same drive logged at 10 Hz and at 100 Hz: the end covariance agrees to the
    integration error (O(Δt²) of the sum over the arc: 1e-4 relative here), as the
    variance of a turn cut into pieces sums to the same. A noise per update, as AMCL's
    α·rot², would differ tenfold."""
    slow, fast = drive_log(DRIVE, 10.0), drive_log(DRIVE, 100.0)
    assert len(fast) == 10 * len(slow)
    a, b = log_cov(slow, (TURN,))[-1], log_cov(fast, (TURN,))[-1]
    np.testing.assert_allclose(a, b, rtol=2e-3, atol=2e-3 * np.abs(b).max())
    assert a[2, 2] == pytest.approx(b[2, 2], rel=1e-12)  # the heading: exactly α_turn·Σ|Δθ|
    total_turn = sum(abs(seg.yaw_rate) * seg.duration for seg in DRIVE)
    assert b[2, 2] == pytest.approx(TURN.alpha_turn * total_turn, rel=1e-12)


def test_zero_noise_gives_zero_covariance_and_the_covariance_is_symmetric_psd():
    steps = drive_log(DRIVE, 10.0)
    assert not log_cov(steps, (TurnNoise(0.0, 0.0),)).any()
    cov = log_cov(steps, SETS["all"])
    np.testing.assert_allclose(cov, np.swapaxes(cov, 1, 2), rtol=1e-12, atol=1e-18)
    assert np.all(np.linalg.eigvalsh(cov) >= -1e-15 * np.abs(cov).max())


def test_a_straight_drive_gathers_nothing_from_it():
    steps = drive_log([KellyArc(0.5, 0.0, 4.0)], 20.0)
    assert not log_cov(steps, (TurnNoise(1.0, 1.0),)).any()
    base = (SpeedNoise(1e-3), GyroNoise(1e-4), PU)
    np.testing.assert_array_equal(log_cov(steps, (*base, TurnNoise(1.0, 1.0))), log_cov(steps, base))


@pytest.mark.parametrize("name", ["turn", "turn+speed+gyro"])
def test_planned_path_closed_form_equals_the_log_engines(name):
    """predict's closed form on the drive against the track's engines on its 10 Hz samples
    (the same engine, to rounding) and on 4000 steps a segment (the closed form is their
    limit); a lateral slip beside it changes nothing in this."""
    noise = SETS[name]
    closed = predict(DRIVE, noise, robot=Unicycle())
    sampled = predict(DRIVE, noise, robot=Unicycle(), engine="recursion", sample_period=0.1)
    np.testing.assert_allclose(sampled.cov, log_cov(drive_log(DRIVE, 10.0), noise)[-1], rtol=1e-12,
                               atol=1e-18)
    fine = predict(DRIVE, noise, robot=Unicycle(), engine="recursion", partitions=4000)
    np.testing.assert_allclose(closed.cov, fine.cov, rtol=1e-7, atol=1e-7 * np.abs(fine.cov).max())
    assert closed.model == "gyro" and closed.engine == "closed"
    # a gyro robot (the default vehicle without a robot) differs only where it stands:
    # its gyro drifts then, a unicycle told to stand does not turn
    standing = predict([DRIVE[3]], noise[:-1] or (GyroNoise(0.0),)).cov[2, 2]
    assert predict(DRIVE, noise).cov[2, 2] - closed.cov[2, 2] == pytest.approx(standing, rel=1e-12, abs=1e-18)
    slip = LateralSlipNoise(1e-4)
    with_slip = predict(DRIVE, (*noise, slip), robot=Unicycle())
    np.testing.assert_allclose(with_slip.cov - closed.cov,
                               predict(DRIVE, (GyroNoise(0.0), slip), robot=Unicycle()).cov,
                               rtol=1e-10, atol=1e-16)


def test_a_unicycle_told_to_stand_gathers_no_gyro_noise_in_the_closed_form_either():
    """A unicycle's yaw-rate noise acts only while it moves (GyroNoise.noisy_time): the
    engines and the Monte Carlo said so, the closed form drifted through a standing
    segment (σ_gg·T too much heading variance)."""
    path = [KellyArc(0.5, 0.3, 2.0), KellyArc(0.0, 0.0, 1.0), KellyArc(0.5, 0.0, 1.0)]
    noise = (SpeedNoise(1e-4), GyroNoise(1e-4))
    closed = predict(path, noise, robot=Unicycle())
    engines = predict(path, noise, robot=Unicycle(), engine="recursion", partitions=4000)
    assert closed.cov[2, 2] == pytest.approx(1e-4 * 3.0, rel=1e-12)
    np.testing.assert_allclose(closed.cov, engines.cov, rtol=1e-7, atol=1e-7 * np.abs(engines.cov).max())
    assert predict(path, noise).cov[2, 2] == pytest.approx(1e-4 * 4.0, rel=1e-12)  # a gyro drifts


@pytest.mark.parametrize("v,w", [(0.5, 0.7), (0.3, -1.9), (-0.4, 0.6)])
def test_on_an_arc_it_is_a_gyro_noise_plus_a_speed_noise(v, w):
    """On a constant-curvature arc TurnNoise is GyroNoise(α_turn·|ω|) + SpeedNoise
    (α_turn_travel·|ω/V|): Kelly's closed form of those two, a second method."""
    seg, theta0 = KellyArc(v, w, 2.5), 0.3
    cov0 = np.array([[1e-3, 2e-4, -1e-4], [2e-4, 2e-3, 3e-4], [-1e-4, 3e-4, 5e-4]])
    ours = gyro_arc_cov(seg, SpeedNoise(0.0), GyroNoise(0.0), theta0, cov0, TURN)
    kelly = gyro_arc_cov(seg, SpeedNoise(TURN.alpha_turn_travel * abs(w / v)),
                         GyroNoise(TURN.alpha_turn * abs(w)), theta0, cov0)
    np.testing.assert_allclose(ours, kelly, rtol=1e-12, atol=1e-18)


def test_a_spin_in_place_moves_the_robot_along_its_turning_heading():
    """A spin of a = ωT from heading θ₀: the travel error of each piece moves the robot
    along its heading at that moment, so P_xy = α_turn_travel·|a|·∫₀¹ u uᵀ dτ with
    u = (cos, sin)(θ₀ + τa), by quadrature; the heading error moves no position."""
    theta0, w, t = 0.4, -2.0, 1.5
    a = w * t
    closed = predict([KellyArc(0.0, w, t)], (TURN,), robot=Unicycle(), pose0=(1.0, 2.0, theta0)).cov
    tau = (np.arange(200_000) + 0.5) / 200_000  # midpoint rule, error ~1e-11
    u = np.stack([np.cos(theta0 + tau * a), np.sin(theta0 + tau * a)])
    expected = np.zeros((3, 3))
    expected[:2, :2] = TURN.alpha_turn_travel * abs(a) * (u @ u.T) / tau.size
    expected[2, 2] = TURN.alpha_turn * abs(a)
    np.testing.assert_allclose(closed, expected, rtol=1e-9, atol=1e-15)
    # and the project's Monte Carlo draws it so
    mc = simulate_runs([KellyArc(0.0, w, t)], (TURN,), robot=Unicycle(), runs=40_000, partitions=50,
                       seed=5, pose0=(1.0, 2.0, theta0))
    assert_cov_within_sampling_error(mc.final, closed, what="spin")


@pytest.mark.parametrize("name", list(SETS))
def test_simulate_runs_matches_the_prediction(name):
    """The project's Monte Carlo of the planned drive (its kernels, the models' own
    factors) against predict (closed form, or the engines with bias noise)."""
    noise = SETS[name]
    engine = "recursion" if any(m.kind == "bias" for m in noise) else "closed"
    p = predict(DRIVE, noise, robot=Unicycle(), engine=engine, partitions=100)
    mc = simulate_runs(DRIVE, noise, robot=Unicycle(), runs=40_000, partitions=100, seed=11)
    assert_cov_within_sampling_error(mc.final, p.cov, what=name)


def test_predict_and_simulate_flags(run_cli):
    segs = ["--segment", "arc:0.3,0.8,2", "--segment", "arc:0,-1.2,1", "--segment", "straight:0.4,1"]
    base = ["--model", "gyro", "--speed-noise", "3e-4", "--gyro-noise", "2e-4"]
    code, out, err = run_cli("predict", *base, "--turn-noise", "5e-4", "--turn-travel-noise", "2e-4", *segs,
                             "--json")
    assert code == 0, err
    path = [KellyArc(0.3, 0.8, 2.0), KellyArc(0.0, -1.2, 1.0), KellyArc(0.4, 0.0, 1.0)]
    expected = predict(path, (SpeedNoise(3e-4), GyroNoise(2e-4), TURN))
    np.testing.assert_allclose(json.loads(out)["cov"], expected.cov, rtol=1e-12, atol=1e-18)
    # one flag alone: the other term is zero
    code, out, err = run_cli("predict", *base, "--turn-travel-noise", "2e-4", *segs, "--json")
    assert code == 0, err
    alone = predict(path, (SpeedNoise(3e-4), GyroNoise(2e-4), TurnNoise(alpha_turn_travel=2e-4)))
    np.testing.assert_allclose(json.loads(out)["cov"], alone.cov, rtol=1e-12, atol=1e-18)
    code, out, err = run_cli("simulate", *base, "--turn-noise", "5e-4", "--turn-travel-noise", "2e-4",
                             *segs, "--runs", "4000", "--partitions", "50", "--seed", "3", "--json")
    assert code == 0, err
    result = json.loads(out)
    np.testing.assert_allclose(result["theory"]["cov"], expected.cov, rtol=1e-12, atol=1e-18)
    assert result["verdict"] == "consistent"
    for model, extra in (("diff", ["--wheel-base", "0.4", "--k-left", "1e-3", "--k-right", "1e-3"]),
                         ("compass", ["--heading-noise", "1e-4"])):
        code, out, err = run_cli("predict", "--model", model, *extra, "--turn-noise", "1e-3",
                                 "--segment", "straight:1" if model == "diff" else "straight:1,1")
        assert code == 2 and err.strip().count("\n") == 0
        assert f"--turn-noise does not apply to --model {model}" in err
    code, out, err = run_cli("predict", *base, "--turn-noise", "-1", *segs)
    assert code == 2 and "--turn-noise must be a non-negative number" in err


def test_turn_noise_alone_needs_no_gyro_noise_flag(run_cli):
    """A base whose heading noise is all turning (MRCLAM's fit puts σ_gg near zero): the
    reviewer's `predict --model gyro --turn-noise 1e-3` was refused for want of --gyro-noise;
    with a turn-noise flag the time-driven heading noise defaults to 0, and the covariance is
    predict's of SpeedNoise + GyroNoise(0) + TurnNoise. With neither flag --gyro-noise is
    still required."""
    segs = ["--segment", "arc:0.3,0.8,2", "--segment", "straight:0.4,1"]
    code, out, err = run_cli("predict", "--model", "gyro", "--speed-noise", "3e-4", "--turn-noise", "1e-3",
                             *segs, "--json")
    assert code == 0, err
    path = [KellyArc(0.3, 0.8, 2.0), KellyArc(0.4, 0.0, 1.0)]
    expected = predict(path, (SpeedNoise(3e-4), GyroNoise(0.0), TurnNoise(alpha_turn=1e-3)))
    np.testing.assert_allclose(json.loads(out)["cov"], expected.cov, rtol=1e-12, atol=1e-18)
    code, _, err = run_cli("predict", "--model", "gyro", "--speed-noise", "3e-4", *segs)
    assert code == 2 and "--gyro-noise is required" in err


def test_a_predicted_yaw_variance_beyond_a_uniform_heading_is_said(run_cli):
    """predict's JSON ros_pose_covariance is what a ROS consumer takes literally: a yaw
    variance past π²/3 (a heading spread uniformly around the circle) is no Gaussian's, and
    predict says so as track and report do (io.ros.yaw_variance_note); a small one is quiet.
    Gyro noise 0.05 rad²/s over 100 s: var θ = 5 rad², by Kelly's closed form exactly."""
    base = ["predict", "--model", "gyro", "--speed-noise", "1e-4", "--segment", "straight:0.1,100", "--json"]
    code, out, err = run_cli(*base[:5], "--gyro-noise", "0.05", *base[5:])
    assert code == 0, err
    result = json.loads(out)
    assert result["ros_pose_covariance"][35] == pytest.approx(5.0, rel=1e-9)
    assert "beyond π²/3" in err and "ros_pose_covariance" in err and err.startswith("odomkit: warning:")
    assert any("beyond π²/3" in w for w in result["warnings"])  # in the JSON too, as other commands do
    code, out, err = run_cli(*base[:5], "--gyro-noise", "1e-4", *base[5:])
    assert code == 0, err
    assert "π²/3" not in err
