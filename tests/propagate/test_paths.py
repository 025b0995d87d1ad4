"""Planned paths as steps (:mod:`odomkit.propagate.paths`): which noise arguments make a
path model (and which vehicle they describe), and segments cut into equal steps whose
sums are each segment's arc length and heading change by hand geometry."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    LateralSlipNoise,
    NoiseSet,
    ParameterUncertainty,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)
from odomkit.path import Arc, KellyArc, Spin, SteerArc, Straight
from odomkit.propagate.paths import (
    check_partitions,
    check_segments,
    check_wheel_base,
    path_model,
    path_steps,
    segment_motion,
)
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle

ACCEPTED = [
    (WheelNoise(0.01, 0.02), "wheel", DiffDrive),
    (ClassicalNoise(0.01, 0.02), "classical", DiffDrive),
    (GyroNoise(1e-4), "gyro", GyroOdometry),
    ((SpeedNoise(1e-3), GyroNoise(1e-4)), "gyro", GyroOdometry),
    (CompassNoise(1e-4), "compass", CompassOdometry),
    (NoiseSet.of((SpeedNoise(1e-3), CompassNoise(1e-4))), "compass", CompassOdometry),
    # every family but the classical takes the vehicle's bias (issue 11 item 1)
    ((WheelNoise(0.01, 0.02), ParameterUncertainty(0.01)), "wheel", DiffDrive),
    ((GyroNoise(1e-4), ParameterUncertainty(sigma_yaw_rate_offset=1e-3)), "gyro", GyroOdometry),
    ((CompassNoise(1e-4), ParameterUncertainty(sigma_heading_offset=1e-3)), "compass", CompassOdometry),
    # the noise fit-noise fits for a diff robot (API study s24, H1): any set the track takes
    ((WheelNoise(0.01, 0.02), SpeedNoise(1e-3), LateralSlipNoise(1e-4), ParameterUncertainty(0.01)),
     "wheel", DiffDrive),
]


@pytest.mark.parametrize("noise,family,vehicle", ACCEPTED,
                         ids=[f"{a[1]}-{i}" for i, a in enumerate(ACCEPTED)])
def test_path_model_picks_family_and_vehicle(noise, family, vehicle):
    model = path_model(noise, wheel_base=0.5)
    assert model.family == family
    assert type(model.robot) is vehicle
    assert model.diff == (vehicle is DiffDrive)
    assert model.noise == NoiseSet.of(noise)
    if vehicle is DiffDrive:
        assert model.robot == DiffDrive(0.5)


REJECTED = [
    SpeedNoise(1e-3),                                   # joins a family, selects none
    (GyroNoise(1e-4), CompassNoise(1e-4)),              # two families
    (),
]


@pytest.mark.parametrize("noise", REJECTED, ids=range(len(REJECTED)))
def test_path_model_rejects_other_combinations(noise):
    with pytest.raises(ModelError, match=r"is not a prediction model; expected WheelNoise"):
        path_model(noise, wheel_base=0.5)
    with pytest.raises(ModelError, match="is not a simulation model"):
        path_model(noise, wheel_base=0.5, purpose="simulation")


def test_a_model_that_does_not_apply_to_the_vehicle_is_refused_by_its_own_check():
    """The track's rule: each model's check_robot; the message names the model and the
    vehicle (a gyro robot by default for GyroNoise)."""
    with pytest.raises(ModelError, match=r"is not a prediction model of a gyro robot \(TricycleNoise "
                                         r"applies to a Tricycle or Car robot, not a GyroOdometry\)"):
        path_model((GyroNoise(1e-4), TricycleNoise(0.01, 0.02)))
    with pytest.raises(ModelError, match=r"of a unicycle robot \(WheelNoise applies to a DiffDrive"):
        path_model(WheelNoise(0.01, 0.01), robot=Unicycle())


def test_path_model_names_what_it_got():
    with pytest.raises(ModelError, match=r"noise \(GyroNoise, CompassNoise\)"):
        path_model((GyroNoise(1e-4), CompassNoise(1e-4)), 0.5)
    with pytest.raises(ModelError, match=r"noise \(nothing\)"):
        path_model(None, 0.5)  # type: ignore[arg-type]


def test_diff_families_need_a_wheel_base_and_kelly_families_do_not():
    with pytest.raises(ModelError, match="needs a wheel base"):
        path_model(WheelNoise(0.01, 0.02))
    with pytest.raises(ModelError, match="wheel base must be a positive finite number"):
        path_model(ClassicalNoise(0.01, 0.02), wheel_base=-0.5)
    assert path_model(GyroNoise(1e-4)).family == "gyro"


def test_check_partitions_and_wheel_base():
    assert check_partitions(3) == 3 and check_partitions(np.int64(7)) == 7
    for bad in (0, -2, 1.5, 3.0, True, "4"):
        with pytest.raises(ModelError, match="partitions must be a positive integer"):
            check_partitions(bad)  # type: ignore[arg-type]
    assert check_wheel_base(0.4) == 0.4
    with pytest.raises(ModelError, match="needs a wheel base"):
        check_wheel_base(None)
    for bad in (0.0, -0.4, float("nan"), float("inf")):
        with pytest.raises(ModelError, match=r"wheel base must be a positive finite number \[m\]"):
            check_wheel_base(bad)


def test_check_segments_names_the_offending_segment():
    wheel, gyro = path_model(WheelNoise(0.01, 0.02), 0.5), path_model(GyroNoise(1e-4))
    segs = (s for s in [Straight(1.0), Spin(0.5), Arc(1.0, 2.0)])
    assert check_segments(segs, wheel) == [Straight(1.0), Spin(0.5), Arc(1.0, 2.0)]
    with pytest.raises(ModelError, match=r"segment 3 is KellyArc\(.*\); the wheel model needs "
                                         r"Arc, Straight or Spin"):
        check_segments([Straight(1.0), Arc(1.0, 2.0), KellyArc(1.0, 0.0, 2.0)], wheel)
    with pytest.raises(ModelError, match=r"segment 2 is Straight\(distance=1.0\); the gyro model "
                                         r"needs KellyArc"):
        check_segments([KellyArc(1.0, 0.0, 2.0), Straight(1.0)], gyro)


def test_segment_motion_by_hand():
    """Arc length (L + R)/2 and heading change (R − L)/B (Chong–Kleeman eq. 14); a spin of
    φ moves its wheels ∓B·φ/2; a Kelly arc covers V·T and turns ω·T."""
    assert segment_motion(Arc(3.0, 1.0), 0.5) == pytest.approx((2.0, -4.0))
    assert segment_motion(Straight(-2.0), 0.5) == pytest.approx((-2.0, 0.0))
    assert segment_motion(Spin(np.pi), 0.5) == pytest.approx((0.0, np.pi))
    assert segment_motion(KellyArc(0.5, 0.1, 4.0), 99.0) == pytest.approx((2.0, 0.4))


def test_path_steps_cut_diff_segments_into_equal_steps():
    base, n = 0.5, 4
    segs = [Arc(3.0, 1.0), Straight(2.0), Spin(np.pi / 2), Arc(-1.0, 0.5)]
    model = path_model(WheelNoise(0.01, 0.02), base)
    steps = path_steps(segs, model, n)
    assert steps.robot is model.robot and len(steps) == len(segs) * n
    # (arc length, heading change) by hand: (L + R)/2 and (R − L)/B
    want = [(2.0, -4.0), (2.0, 0.0), (0.0, np.pi / 2), (-0.25, 3.0)]
    for i, (length, turn) in enumerate(want):
        part = slice(i * n, (i + 1) * n)
        assert np.allclose(steps.dd[part], length / n, rtol=1e-14, atol=1e-15)  # equal steps
        assert np.allclose(steps.dtheta[part], turn / n, rtol=1e-14, atol=1e-15)
        assert steps.dd[part].sum() == pytest.approx(length, abs=1e-14)
        assert steps.dtheta[part].sum() == pytest.approx(turn, abs=1e-14)
    left = np.repeat([3.0, 2.0, -base * np.pi / 4, -1.0], n) / n
    right = np.repeat([1.0, 2.0, base * np.pi / 4, 0.5], n) / n
    assert np.allclose(steps.inputs["d_left"], left, rtol=1e-14)
    assert np.allclose(steps.inputs["d_right"], right, rtol=1e-14)
    assert not steps.dt.any()


def test_path_steps_of_an_arc_end_on_its_circle():
    """Dead-reckoning the steps of Arc(L, R) ends on the circle of radius ρ = Δd/Δθ:
    (ρ sin Δθ, ρ(1 − cos Δθ), Δθ), however finely it is cut."""
    base, left, right = 0.4, 1.0, 1.3
    d, a = 0.5 * (left + right), (right - left) / base
    rho = d / a
    model = path_model(WheelNoise(0.01, 0.02), base)
    for n in (1, 7, 100):
        steps = path_steps([Arc(left, right)], model, n)
        end = dead_reckon(steps.dd, steps.dtheta)[-1]
        assert end == pytest.approx([rho * np.sin(a), rho * (1 - np.cos(a)), a], rel=1e-12)


def test_path_steps_of_kelly_segments():
    model = path_model((SpeedNoise(1e-3), GyroNoise(1e-4)))
    steps = path_steps([KellyArc(0.5, 0.1, 4.0), KellyArc(1.0, 0.0, 3.0)], model, 5)
    assert np.allclose(steps.dd, np.repeat([2.0, 3.0], 5) / 5, rtol=1e-14)
    assert np.allclose(steps.dtheta, np.repeat([0.4, 0.0], 5) / 5, rtol=1e-14)
    assert np.allclose(steps.dt, np.repeat([4.0, 3.0], 5) / 5, rtol=1e-14)
    assert isinstance(steps.robot, GyroOdometry)
    assert np.allclose(steps.inputs["yaw_rate"], np.repeat([0.1, 0.0], 5), rtol=1e-14)
    assert len(path_steps([], model, 5)) == 0


def test_path_steps_drive_commanded_travels_with_a_true_robot():
    """A Monte Carlo of a robot with systematic errors: the travels are commanded with the
    nominal wheel base (a spin's ∓B·φ/2), scaled by each wheel's true/nominal distance
    per tick, and turn the vehicle through its true wheel base."""
    base, phi, n = 0.5, 1.0, 2
    model = path_model(WheelNoise(0.01, 0.02), base)
    true = DiffDrive(base, c_wheel_base=1.1)
    steps = path_steps([Spin(phi)], model, n, robot=true, scales=(1.02, 0.98))
    left, right = -1.02 * base * phi / 2, 0.98 * base * phi / 2
    assert np.allclose(steps.inputs["d_left"], left / n) and np.allclose(steps.inputs["d_right"], right / n)
    assert steps.dd.sum() == pytest.approx(0.5 * (left + right), rel=1e-14)
    assert steps.dtheta.sum() == pytest.approx((right - left) / (1.1 * base), rel=1e-14)
    assert steps.robot is true
    with pytest.raises(ModelError, match="partitions"):
        path_steps([Spin(phi)], model, 0)


def test_a_robot_picks_the_vehicle_and_steered_vehicles_need_one():
    """Issue 12 item 3: a unicycle drives KellyArc segments with the gyro family's noise;
    a tricycle or car drives SteerArc segments ("steering" family), and bias alone is a
    model once the robot says which vehicle it is."""
    uni = path_model((SpeedNoise(1e-3), GyroNoise(1e-4)), robot=Unicycle())
    assert (uni.family, uni.robot) == ("gyro", Unicycle())
    car = Car(2.7, 0.8)
    for noise in (TricycleNoise(0.01, 0.02), ParameterUncertainty(sigma_steering_offset=0.01),
                  (TricycleNoise(0.01, 0.02), SpeedNoise(1e-3), ParameterUncertainty(0.01)),
                  GyroNoise(1e-4)):  # a car's log takes a gyro's noise too (GyroNoise.robot_types)
        model = path_model(noise, robot=car, sample_period=0.1)
        assert (model.family, model.robot, model.steered) == ("steering", car, True)
    assert path_model(ParameterUncertainty(0.01), robot=DiffDrive(0.3)).family == "wheel"
    with pytest.raises(ModelError, match="without a robot: it describes a steered vehicle"):
        path_model(TricycleNoise(0.01, 0.02))
    with pytest.raises(ModelError, match="wheel_base 0.5 m differs"):
        path_model(WheelNoise(0.01, 0.01), 0.5, robot=DiffDrive(0.4))
    with pytest.raises(ModelError, match="needs SteerArc"):
        check_segments([KellyArc(1.0, 0.1, 2.0)],
                       path_model(TricycleNoise(0.01, 0.02), robot=car, sample_period=0.1))
    with pytest.raises(ModelError, match="needs KellyArc"):
        check_segments([SteerArc(1.0, 0.1, 2.0)], uni)
    with pytest.raises(ModelError, match="within ±π/2"):
        SteerArc(1.0, 2.0, 1.0)


@pytest.mark.parametrize("robot", [Tricycle(0.7), Car(2.7, 0.8), Car(2.7, -0.8, "front")],
                         ids=["tricycle", "car-rear", "car-front"])
def test_steer_arc_steps_are_the_vehicles_circle(robot):
    """Hand geometry: a SteerArc turns the rear-axle centre on a circle of radius
    R = L/tan α, whose measuring wheel runs on √(x_w² + (R − H)²) (x_w = L at the front,
    0 at the rear): driven for one turn of that wheel's circle it closes the circle."""
    alpha, length = 0.35, getattr(robot, "wheel_base", None) or robot.wheel_to_axle
    offset = getattr(robot, "encoder_offset", 0.0)
    front = not isinstance(robot, Car) or robot.encoder_at == "front"
    radius = length / np.tan(alpha)
    wheel = np.hypot(length if front else 0.0, radius - offset)
    seg = SteerArc(1.5, alpha, 2 * np.pi * wheel / 1.5)
    model = path_model(SpeedNoise(0.01), robot=robot)
    steps = path_steps([seg], model, 200)
    assert steps.inputs["travel"].sum() == pytest.approx(2 * np.pi * wheel, rel=1e-12)
    assert np.all(steps.inputs["steer"] == alpha) and steps.dt.sum() == pytest.approx(seg.duration)
    assert steps.dtheta.sum() == pytest.approx(2 * np.pi, rel=1e-12)
    assert steps.dd.sum() == pytest.approx(2 * np.pi * radius, rel=1e-12)
    assert np.allclose(dead_reckon(steps.dd, steps.dtheta)[-1], [0, 0, 2 * np.pi], atol=1e-9)
    assert segment_motion(seg, 1.0, robot) == pytest.approx((2 * np.pi * radius, 2 * np.pi), rel=1e-12)
