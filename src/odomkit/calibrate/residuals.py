"""The numerical core of :mod:`odomkit.calibrate.exact`: weighted pose residuals of a
set of runs and their analytic Jacobian with respect to the robot's parameters.

* :func:`integrate_with_sensitivity` dead-reckons body steps and, in the same vectorised
  pass, the derivative of every pose with respect to the parameters;
* :class:`DiffCalibrationModel`, :class:`TricycleCalibrationModel`,
  :class:`CarCalibrationModel`, :class:`UnicycleCalibrationModel` and
  :class:`GyroCalibrationModel` map a parameter vector p onto the body steps of each run
  (and their derivatives) and back onto a robot; :func:`calibration_model` picks the one
  for a robot (:data:`CALIBRATED_ROBOTS`);
* :class:`ResidualProblem` compares the integrated poses with the ground truth (endpoints or whole
  trajectories), weights or whitens the residuals and stacks them, with their Jacobian,
  over all runs for :func:`scipy.optimize.least_squares`; :func:`endpoint_whitening` gives
  the endpoint whitening matrices from a per-wheel noise model.

It is separate from :mod:`odomkit.calibrate.exact`, which keeps the fit itself, its input
checks and its result type, because this part is self-contained mathematics: it takes
raw body steps and parameter vectors, knows nothing of observability decisions or
standard errors, and is tested on its own against finite differences and the library's
dead reckoning.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import wrap_angle
from odomkit.errors import ModelError
from odomkit.kinematics import (
    Method,
    body_steps,
    car_body_jacobian,
    car_body_steps,
    step_jacobians,
    unicycle_moving,
)
from odomkit.log import OdometryLog
from odomkit.robot import Car, DiffDrive, GyroOdometry, Tricycle, Unicycle
from odomkit.track import initial_pose

__all__ = ["CALIBRATED_ROBOTS", "CalibratedRobot", "CalibrationModel", "CarCalibrationModel",
           "DiffCalibrationModel", "GyroCalibrationModel", "ResidualProblem", "TricycleCalibrationModel",
           "UnicycleCalibrationModel", "calibration_model", "endpoint_whitening", "heading_residual",
           "integrate_with_sensitivity"]

CalibratedRobot: TypeAlias = DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
"""A robot whose systematic parameters the exact calibration fits."""

CALIBRATED_ROBOTS = (DiffDrive, Tricycle, Car, Unicycle, GyroOdometry)
"""The robot classes of :data:`CalibratedRobot`, for ``isinstance`` checks."""


def integrate_with_sensitivity(
    dd: NDArray[np.float64],
    dtheta: NDArray[np.float64],
    ddd_dp: NDArray[np.float64],
    ddtheta_dp: NDArray[np.float64],
    pose0: NDArray[np.float64],
    method: Method = "exact",
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Dead-reckon body steps and, in the same vectorised pass, the derivative of every
    pose with respect to P parameters the steps depend on.

    Parameters
    ----------
    dd, dtheta : ndarray, shape (M,)
        Body steps [m], [rad].
    ddd_dp, ddtheta_dp : ndarray, shape (M, P)
        Their derivatives with respect to the parameters.
    pose0 : ndarray, shape (3,)
        Initial pose (independent of the parameters).
    method : {"exact", "midpoint", "euler"}

    Returns
    -------
    poses : ndarray, shape (M + 1, 3)
    dposes_dp : ndarray, shape (M + 1, 3, P)

    Examples
    --------
    A straight metre with dd = p: x_end = p, so ∂x_end/∂p = 1.

    >>> p, dp = integrate_with_sensitivity(np.full(4, 0.25), np.zeros(4), np.full((4, 1), 0.25),
    ...                                    np.zeros((4, 1)), np.zeros(3))
    >>> float(p[-1, 0]), float(dp[-1, 0, 0])
    (1.0, 1.0)
    """
    m, n_par = ddd_dp.shape
    theta = np.empty(m + 1)
    theta[0] = pose0[2]
    np.cumsum(dtheta, out=theta[1:])
    theta[1:] += pose0[2]
    dtheta_p = np.zeros((m + 1, n_par))
    np.cumsum(ddtheta_dp, axis=0, out=dtheta_p[1:])
    F, G = step_jacobians(theta[:-1], dd, dtheta, method)
    # The step displacement depends on the parameters through (Δd, Δθ) of the step (G)
    # and through the heading at its start (F[:, :2, 2] = (−Δy, Δx)).
    ddx = G[:, 0, 0, None] * ddd_dp + G[:, 0, 1, None] * ddtheta_dp + F[:, 0, 2, None] * dtheta_p[:-1]
    ddy = G[:, 1, 0, None] * ddd_dp + G[:, 1, 1, None] * ddtheta_dp + F[:, 1, 2, None] * dtheta_p[:-1]
    poses = np.empty((m + 1, 3))
    poses[0] = pose0
    poses[1:, 0] = pose0[0] + np.cumsum(F[:, 1, 2])  # F[:, 1, 2] = Δx
    poses[1:, 1] = pose0[1] - np.cumsum(F[:, 0, 2])  # F[:, 0, 2] = −Δy
    poses[:, 2] = theta
    dposes = np.zeros((m + 1, 3, n_par))
    np.cumsum(ddx, axis=0, out=dposes[1:, 0])
    np.cumsum(ddy, axis=0, out=dposes[1:, 1])
    dposes[:, 2] = dtheta_p
    return poses, dposes


def heading_residual(theta: NDArray[np.float64], truth_theta: NDArray[np.float64],
                     weight: float = 1.0) -> NDArray[np.float64]:
    """The heading residual of a calibration against a truth that measures heading:
    ``weight``·wrap(θ − θ_truth), odometry minus truth, wrapped into [−π, π)
    (:func:`odomkit.angles.wrap_angle`). With ``weight`` a length [m/rad] it is a metre
    beside the position residuals (a heading error δθ counts like a lateral miss of
    weight·δθ); its derivative in anything θ depends on is ``weight`` times θ's. Shapes
    alike, (n,). :class:`ResidualProblem` (the log's own gt_θ) and
    :func:`odomkit.calibrate.positions.calibrate_positions` (a truth file's heading) compare
    by it."""
    return weight * wrap_angle(theta - truth_theta)


class DiffCalibrationModel:
    """p = (c_left, c_right, c_wheel_base) of a DiffDrive."""

    names = ("c_left", "c_right", "c_wheel_base")
    positive = (True, True, True)

    def __init__(self, robot: DiffDrive, runs: Sequence[OdometryLog]):
        self.robot = robot
        raw = replace(robot, c_left=1.0, c_right=1.0, c_wheel_base=1.0)
        steps = [body_steps(raw, log) for log in runs]
        self.raw = [(s.inputs["d_left"], s.inputs["d_right"]) for s in steps]
        self.p0 = np.array([robot.c_left, robot.c_right, robot.c_wheel_base])
        self.unobservable: dict[str, str] = {}

    def steps(self, p: NDArray[np.float64], i: int) -> tuple[NDArray[np.float64], ...]:
        a, r = self.raw[i]
        b = p[2] * self.robot.wheel_base
        d_left, d_right = p[0] * a, p[1] * r
        # Borenstein–Feng (2.2)–(2.4) with (4.33): d = c·c_m·N, Δd = (dR + dL)/2, Δθ = (dR − dL)/b
        dd = 0.5 * (d_left + d_right)
        dtheta = (d_right - d_left) / b
        ddd = np.stack([0.5 * a, 0.5 * r, np.zeros_like(a)], axis=1)
        ddt = np.stack([-a / b, r / b, -dtheta / p[2]], axis=1)
        return dd, dtheta, ddd, ddt

    def make_robot(self, p: NDArray[np.float64]) -> DiffDrive:
        return replace(self.robot, c_left=float(p[0]), c_right=float(p[1]), c_wheel_base=float(p[2]))

    def fixed_scale_map(self, p0: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """p = offset + T q keeping (c_left + c_right)/2 at its current value
        (Borenstein–Feng eq. 4.28); q = (half difference, c_wheel_base)."""
        mean = 0.5 * (p0[0] + p0[1])
        T = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
        return np.array([mean, mean, 0.0]), T


class _ScaleFirst:
    """A model whose first parameter is the travel scale (c_scale, m_per_tick): with the
    overall scale unobservable it is kept and the others are fitted."""

    def fixed_scale_map(self, p0: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """p = offset + T q keeping p[0]; q = (p[1], p[2], ...)."""
        n = len(p0)
        offset = np.zeros(n)
        offset[0] = p0[0]
        return offset, np.eye(n)[:, 1:]


class TricycleCalibrationModel(_ScaleFirst):
    """p = (c_scale, steering_offset, wheel_to_axle) of a Tricycle."""

    names = ("c_scale", "steering_offset", "wheel_to_axle")
    positive = (True, False, True)

    def __init__(self, robot: Tricycle, runs: Sequence[OdometryLog]):
        self.robot = robot
        raw = replace(robot, c_scale=1.0, steering_offset=0.0)
        steps = [body_steps(raw, log) for log in runs]
        self.raw = [(s.inputs["travel"], s.inputs["steer"]) for s in steps]
        self.p0 = np.array([robot.c_scale, robot.steering_offset, robot.wheel_to_axle])
        self.unobservable: dict[str, str] = {}

    def steps(self, p: NDArray[np.float64], i: int) -> tuple[NDArray[np.float64], ...]:
        s0, a0 = self.raw[i]
        s, alpha, L = p[0] * s0, a0 + p[1], p[2]
        cos_a, sin_a = np.cos(alpha), np.sin(alpha)
        # Tricycle model Δd = s·cos α, Δθ = s·sin α / L (kinematics.tricycle_body_steps)
        dd, dtheta = s * cos_a, s * sin_a / L
        ddd = np.stack([s0 * cos_a, -s * sin_a, np.zeros_like(s)], axis=1)
        ddt = np.stack([s0 * sin_a / L, s * cos_a / L, -dtheta / L], axis=1)
        return dd, dtheta, ddd, ddt

    def make_robot(self, p: NDArray[np.float64]) -> Tricycle:
        return replace(self.robot, c_scale=float(p[0]), steering_offset=float(p[1]),
                       wheel_to_axle=float(p[2]))



class CarCalibrationModel(_ScaleFirst):
    """p = (c_scale, steering_offset, wheel_base) of a Car (its encoder offset and position
    are geometry, known), and ``steering_cubic`` fourth where asked (``cubic``): a steering
    ratio that varies with the angle, which only large steering angles identify."""

    positive: tuple[bool, ...]

    def __init__(self, robot: Car, runs: Sequence[OdometryLog], cubic: bool = False):
        self.robot, self.cubic = robot, cubic
        self.names = ("c_scale", "steering_offset", "wheel_base") + (("steering_cubic",) if cubic else ())
        self.positive = (True, False, True) + ((False,) if cubic else ())
        # The raw angle s = measured / ratio when the cubic is fitted (α = s + k s³ + offset),
        # else the robot's own mapping without its offset.
        raw = replace(robot, c_scale=1.0, steering_offset=0.0,
                      steering_cubic=0.0 if cubic else robot.steering_cubic)
        steps = [body_steps(raw, log) for log in runs]
        self.raw = [(s.inputs["travel"], s.inputs["steer"]) for s in steps]
        p0 = [robot.c_scale, robot.steering_offset, robot.wheel_base]
        self.p0 = np.array(p0 + ([robot.steering_cubic] if cubic else []))
        self.unobservable: dict[str, str] = {}

    def steps(self, p: NDArray[np.float64], i: int) -> tuple[NDArray[np.float64], ...]:
        s0, a0 = self.raw[i]
        cubed = a0**3 if self.cubic else None
        s, length = p[0] * s0, p[2]
        alpha = a0 + p[1] + (p[3] * cubed if cubed is not None else 0.0)
        r = self.robot
        # Car model (kinematics.car_body_steps); c_scale enters through s = c·s0, so its
        # column is s0·∂/∂s; the offset's is ∂/∂α, the wheel base's ∂/∂L, and the cubic's
        # s³·∂/∂α.
        dd, dtheta = car_body_steps(s, alpha, length, r.encoder_offset, r.encoder_at)
        jac = car_body_jacobian(s, alpha, length, r.encoder_offset, r.encoder_at)
        columns_d = [s0 * jac[:, 0, 0], jac[:, 0, 1], jac[:, 0, 2]]
        columns_t = [s0 * jac[:, 1, 0], jac[:, 1, 1], jac[:, 1, 2]]
        if cubed is not None:
            columns_d.append(cubed * jac[:, 0, 1])
            columns_t.append(cubed * jac[:, 1, 1])
        return dd, dtheta, np.stack(columns_d, axis=1), np.stack(columns_t, axis=1)

    def make_robot(self, p: NDArray[np.float64]) -> Car:
        return replace(self.robot, c_scale=float(p[0]), steering_offset=float(p[1]), wheel_base=float(p[2]),
                       steering_cubic=float(p[3]) if self.cubic else self.robot.steering_cubic)



def _yaw_rate_steps(w: NDArray[np.float64], dt: NDArray[np.float64], bias: float, scale: float,
                    moving: NDArray[np.bool_] | None = None
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Δθ = scale·(ω − bias)·Δt of a measured yaw rate ω held from row k over step k, and its
    derivatives with respect to bias and scale; zero on steps not ``moving`` (a unicycle
    standing still: :func:`odomkit.kinematics.unicycle_moving`)."""
    time = dt if moving is None else np.where(moving, dt, 0.0)
    rate = w - bias
    return scale * rate * time, -scale * time, rate * time


class UnicycleCalibrationModel(_ScaleFirst):
    """p = (c_scale, yaw_rate_bias [rad/s], yaw_rate_scale) of a Unicycle.

    Body velocities (:func:`odomkit.kinematics.body_steps` for a unicycle, Kelly's
    integrated heading with velocities measured at the body):
    Δd_k = c_scale·s_k (s_k the step's ``dist`` increment [m], or ``speed``_k·Δt_k with the
    speed held from row k) and Δθ_k = yaw_rate_scale·(ω_k − yaw_rate_bias)·Δt_k, zero where
    the base stands (s_k = ω_k = 0: :func:`odomkit.kinematics.unicycle_moving`).
    """

    names = ("c_scale", "yaw_rate_bias", "yaw_rate_scale")
    positive = (True, False, True)

    def __init__(self, robot: Unicycle, runs: Sequence[OdometryLog]):
        self.robot = robot
        raw = replace(robot, c_scale=1.0, yaw_rate_bias=0.0, yaw_rate_scale=1.0)
        steps = [body_steps(raw, log) for log in runs]
        # (travel [m] at c_scale 1, measured yaw rate [rad/s] held over the step, Δt [s])
        self.raw = [(s.dd, s.inputs["yaw_rate"], s.dt) for s in steps]
        self.p0 = np.array([robot.c_scale, robot.yaw_rate_bias, robot.yaw_rate_scale])
        self.unobservable: dict[str, str] = {}

    def steps(self, p: NDArray[np.float64], i: int) -> tuple[NDArray[np.float64], ...]:
        s0, w, dt = self.raw[i]
        dtheta, dth_bias, dth_scale = _yaw_rate_steps(w, dt, p[1], p[2], unicycle_moving(s0, w))
        zero = np.zeros_like(s0)
        ddd = np.stack([s0, zero, zero], axis=1)
        ddt = np.stack([zero, dth_bias, dth_scale], axis=1)
        return p[0] * s0, dtheta, ddd, ddt

    def make_robot(self, p: NDArray[np.float64]) -> Unicycle:
        return replace(self.robot, c_scale=float(p[0]), yaw_rate_bias=float(p[1]),
                       yaw_rate_scale=float(p[2]))



class GyroCalibrationModel(_ScaleFirst):
    """p = (m_per_tick [m], gyro_bias [rad/s], gyro_scale) of a GyroOdometry.

    Kelly's integrated heading (:func:`odomkit.kinematics.body_steps` for a gyro robot):
    Δd_k = m_per_tick·n_k for a ``ticks`` increment n_k, the ``dist`` increment or
    ``speed``_k·Δt_k otherwise (metres already: m_per_tick does not enter), and
    Δθ_k = gyro_scale·(ω_k − gyro_bias)·Δt_k with the gyro rate ω_k held from row k.
    When no run has a ``ticks`` channel, m_per_tick changes nothing: it is listed in
    :attr:`unobservable` and its Jacobian column is zero.
    """

    names = ("m_per_tick", "gyro_bias", "gyro_scale")
    positive = (True, False, True)

    def __init__(self, robot: GyroOdometry, runs: Sequence[OdometryLog]):
        self.robot = robot
        raw = replace(robot, m_per_tick=1.0, gyro_bias=0.0, gyro_scale=1.0)
        steps = [body_steps(raw, log) for log in runs]
        # body_steps reads ticks before dist and speed (kinematics._travel)
        self.ticked = ["ticks" in log.channels for log in runs]
        self.raw = [(s.dd, s.inputs["yaw_rate"], s.dt) for s in steps]
        self.p0 = np.array([robot.m_per_tick, robot.gyro_bias, robot.gyro_scale])
        self.unobservable: dict[str, str] = {}
        if not any(self.ticked):
            self.unobservable["m_per_tick"] = ("it converts a ticks channel only and the logs carry "
                                               "dist [m] or speed [m/s], metres already")

    def steps(self, p: NDArray[np.float64], i: int) -> tuple[NDArray[np.float64], ...]:
        s0, w, dt = self.raw[i]
        dtheta, dth_bias, dth_scale = _yaw_rate_steps(w, dt, p[1], p[2])
        zero = np.zeros_like(s0)
        if self.ticked[i]:
            dd, dd_scale = p[0] * s0, s0
        else:
            dd, dd_scale = s0, zero
        ddd = np.stack([dd_scale, zero, zero], axis=1)
        ddt = np.stack([zero, dth_bias, dth_scale], axis=1)
        return dd, dtheta, ddd, ddt

    def make_robot(self, p: NDArray[np.float64]) -> GyroOdometry:
        return replace(self.robot, m_per_tick=float(p[0]), gyro_bias=float(p[1]), gyro_scale=float(p[2]))


CalibrationModel: TypeAlias = (DiffCalibrationModel | TricycleCalibrationModel | CarCalibrationModel
                               | UnicycleCalibrationModel | GyroCalibrationModel)
"""The parameter-to-body-step map of a robot the exact calibration supports.

Every model has ``names`` (3 parameter names), ``positive`` (which of them must stay
> 0: scales and lengths), ``p0`` (the robot's values), ``unobservable`` (name -> why the
runs' channels do not depend on it; such a parameter's Jacobian column is zero, so a fit
must hold it), ``steps(p, i)`` -> (Δd, Δθ, ∂Δd/∂p, ∂Δθ/∂p) of run i, shapes (M,), (M,),
(M, 3), (M, 3), ``make_robot(p)`` and ``fixed_scale_map(p0)`` -> (offset, T) with
p = offset + T q keeping the speed scale.
"""


def calibration_model(robot: CalibratedRobot, runs: Sequence[OdometryLog], *,
                      steering_cubic: bool = False) -> CalibrationModel:
    """The :data:`CalibrationModel` of ``robot`` over ``runs`` (ModelError if unsupported).

    Parameters fitted: DiffDrive (c_left, c_right, c_wheel_base); Tricycle (c_scale,
    steering_offset [rad], wheel_to_axle [m]); Car (c_scale, steering_offset [rad],
    wheel_base [m], and with ``steering_cubic`` the Car's steering_cubic [rad⁻²]);
    Unicycle (c_scale, yaw_rate_bias [rad/s], yaw_rate_scale); GyroOdometry (m_per_tick
    [m], gyro_bias [rad/s], gyro_scale).
    """
    if steering_cubic and not isinstance(robot, Car):
        raise ModelError(f"steering_cubic is a car's; the robot is a {type(robot).__name__}")
    if isinstance(robot, DiffDrive):
        return DiffCalibrationModel(robot, runs)
    if isinstance(robot, Tricycle):
        return TricycleCalibrationModel(robot, runs)
    if isinstance(robot, Car):
        return CarCalibrationModel(robot, runs, cubic=steering_cubic)
    if isinstance(robot, Unicycle):
        return UnicycleCalibrationModel(robot, runs)
    if isinstance(robot, GyroOdometry):
        return GyroCalibrationModel(robot, runs)
    raise ModelError("exact calibration supports DiffDrive, Tricycle, Car, Unicycle and GyroOdometry "
                     f"robots, got {type(robot).__name__}")


class ResidualProblem:
    """Weighted residuals and their Jacobian over all runs, for parameters p = off + T q."""

    def __init__(self, model: CalibrationModel, runs: Sequence[OdometryLog],
                 source: str, heading_weight: float, every: int,
                 whiten: list[NDArray[np.float64]] | None, method: Method):
        self.model, self.source, self.method = model, source, method
        self.pose0 = [initial_pose(log, None) for log in runs]
        self.truth = []
        for log in runs:
            gt = log.ground_truth
            assert gt is not None
            rows = np.array([len(log) - 1]) if source == "endpoints" else np.arange(1, len(log), every)
            if source == "trajectory" and rows[-1] != len(log) - 1:
                rows = np.append(rows, len(log) - 1)
            self.truth.append((rows, gt[rows]))
        self.w = heading_weight
        self.whiten = whiten
        self.offset = np.zeros(len(model.p0))
        self.T = np.eye(len(model.p0))
        self._cache: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None = None

    def full(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.offset + self.T @ q

    def _run(self, p: NDArray[np.float64], i: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        dd, dth, ddd, ddt = self.model.steps(p, i)
        poses, dposes = integrate_with_sensitivity(dd, dth, ddd, ddt, self.pose0[i], self.method)
        rows, gt = self.truth[i]
        res = poses[rows] - gt
        res[:, 2] = heading_residual(poses[rows, 2], gt[:, 2])
        jac = dposes[rows]
        if self.whiten is not None:
            # Endpoint GLS: r ← L⁻¹ r with C = L Lᵀ the predicted end-pose covariance.
            L = self.whiten[i]
            res = np.linalg.solve(L, res[0])[None, :]
            jac = np.linalg.solve(L, jac[0])[None, :, :]
        else:
            res[:, 2] *= self.w
            jac = jac.copy()
            jac[:, 2] *= self.w
        return res.reshape(-1), jac.reshape(-1, jac.shape[-1])

    def scale_sensitivity(self, p: NDArray[np.float64]) -> float:
        """Relative observability of the overall scale, in [0, 1].

        Scaling every length by s moves each compared position by (s − 1)·(pos − start),
        while the other errors move it by up to (s − 1)·(distance travelled so far). The
        ratio sqrt(Σ|pos − start|²)/sqrt(Σ travelled²) over the compared rows is therefore
        the scale's sensitivity relative to a typical parameter's: about 0.002 for the end of
        a closed square, 1 on a straight line, about 0.3 for a whole square track.
        """
        num = den = 0.0
        for i, pose0 in enumerate(self.pose0):
            dd, dth = self.model.steps(p, i)[:2]
            poses, _ = integrate_with_sensitivity(dd, dth, np.zeros((dd.size, 0)),
                                                  np.zeros((dd.size, 0)), pose0, self.method)
            travelled = np.r_[0.0, np.cumsum(np.abs(dd))]
            rows = self.truth[i][0]
            num += float(np.sum((poses[rows, :2] - pose0[:2]) ** 2))
            den += float(np.sum(travelled[rows] ** 2))
        return float(np.sqrt(num / den)) if den > 0 else 0.0

    def _all(self, p: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        # least_squares asks for residuals and Jacobian at the same point: integrate once.
        if self._cache is None or not np.array_equal(self._cache[0], p):
            parts = [self._run(p, i) for i in range(len(self.pose0))]
            self._cache = (p.copy(), np.concatenate([r for r, _ in parts]),
                           np.concatenate([j for _, j in parts]))
        return self._cache[1], self._cache[2]

    def residuals(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return self._all(self.full(q))[0]

    def jacobian_full(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        return self._all(p)[1]

    def jacobian(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.jacobian_full(self.full(q)) @ self.T


def endpoint_whitening(model: CalibrationModel, runs: Sequence[OdometryLog], source: str,
                       noise: object, method: Method) -> list[NDArray[np.float64]]:
    """Per run, the Cholesky factor L (3, 3) of the predicted end-pose covariance
    C = L Lᵀ under the per-wheel noise ``noise``: the endpoint residuals are whitened by L⁻¹."""
    from odomkit.calibrate.noise_fit import wheel_noise_basis
    from odomkit.noise import WheelNoise

    if (source != "endpoints" or not isinstance(model, DiffCalibrationModel)
            or not isinstance(noise, WheelNoise)):
        raise ModelError("noise weighting is available for diff-drive endpoint fits with a WheelNoise")
    out = []
    for i in range(len(runs)):
        a, r = model.raw[i]
        A, B = wheel_noise_basis(model.p0[0] * a, model.p0[1] * r,
                                 model.p0[2] * model.robot.wheel_base,
                                 initial_pose(runs[i], None), method)
        C = noise.k_left**2 * A + noise.k_right**2 * B
        try:
            out.append(np.asarray(np.linalg.cholesky(C), dtype=np.float64))
        except np.linalg.LinAlgError:
            raise ModelError(f"predicted end-pose covariance of run {runs[i].source} is singular; "
                             "both k_left and k_right must be > 0 for weighting") from None
    return out
